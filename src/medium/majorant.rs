//! Majorant grids: a piecewise-constant bound `σ̄(x)` of a heterogeneous medium's extinction
//! over a coarse grid of cells spanning its box (pbrt-v4's `MajorantGrid`), and the walk that
//! draws tentative collisions at the rate `σ̄` along a ray through it.
//!
//! Null-collision tracking is unbiased for any majorant `σ̄(x) ≥ σₜ(x)`; its cost is the number
//! of tentative collisions, the majorant's optical depth `∫ σ̄ dt` along the ray. One global
//! bound (the largest `σₜ` anywhere) makes a sparse cloud cost as much as a solid block of its
//! densest voxel; a bound per cell (the largest texel any lookup in the cell can read) costs
//! nothing in empty cells and little in thin ones.
//!
//! Tentative collisions are a Poisson process of rate `σ̄(t)` along the ray: from `t`, the next
//! is where the majorant's optical depth since `t` reaches `τ = −ln(1 − u)`
//! ([`MajorantWalk::next`]), found by walking the cells the ray crosses (a 3D DDA) and
//! subtracting each cell's `σ̄ ℓ`. One random number per collision, however many cells lie
//! between, and exactly the distribution of a homogeneous process where `σ̄` is one constant.

use crate::math::{Bounds3, Ray, Vec3};
use crate::texture::volume::Volume;
use rayon::prelude::*;

/// Cells per axis at most (pbrt-v4 uses 16 for its grids).
pub const MAX_CELLS: usize = 32;

/// A grid whose cells' mean majorant exceeds this share of the largest is one cell: it would
/// save at most a fifth of the tentative collisions, fewer than the cell crossings it costs
/// (measured: a 6³ grid of values from 0.4 to 0.95, whose cells average 0.97 of the largest,
/// rendered 11 % slower by `volpathmis` with its cells than with one).
pub const DENSE_SHARE: f32 = 0.8;

/// A grid of extinction bounds (m⁻¹) over a world box, `x` fastest.
#[derive(Clone, Debug)]
pub struct MajorantGrid {
    /// The box the cells divide (world).
    bounds: Bounds3,
    /// Cells per axis.
    res: [usize; 3],
    /// `σ̄` per cell (m⁻¹), finite and ≥ 0.
    cells: Vec<f32>,
    /// The largest cell.
    max: f32,
}

impl MajorantGrid {
    /// The majorant grid of the extinction `factor · volume(x)` over the volume's box: as many
    /// cells per axis as the volume's grid has texels, at most [`MAX_CELLS`] (one cell for a
    /// constant or a procedural volume, or where the cells would be nearly as dense as the
    /// densest, [`DENSE_SHARE`]).
    pub fn new(volume: &Volume, factor: f32) -> MajorantGrid {
        let res = volume.grid_resolution().map_or([1; 3], |r| r.map(|n| n.clamp(1, MAX_CELLS)));
        let grid = MajorantGrid::with_resolution(volume, factor, res);
        let mean = grid.cells.iter().map(|&c| c as f64).sum::<f64>() / grid.cells.len() as f64;
        if grid.cells.len() > 1 && mean > (DENSE_SHARE * grid.max) as f64 {
            return MajorantGrid { res: [1; 3], cells: vec![grid.max], ..grid };
        }
        grid
    }

    /// The majorant grid of `factor · volume(x)` with `res` cells per axis (each ≥ 1), each
    /// bounding every value lookups inside it (slightly widened, so that points that round
    /// across a cell face stay bounded) can return.
    pub fn with_resolution(volume: &Volume, factor: f32, res: [usize; 3]) -> MajorantGrid {
        let bounds = volume.bounds();
        let size = bounds.diagonal();
        let cell = Vec3::new(size.x / res[0] as f32, size.y / res[1] as f32, size.z / res[2] as f32);
        let margin = cell * 1e-3 + Vec3::splat(1e-6 * bounds.max.abs().max(bounds.min.abs()).max_element());
        let slice = res[0] * res[1];
        let mut cells = vec![0.0f32; slice * res[2]];
        cells.par_chunks_mut(slice).enumerate().for_each(|(z, out)| {
            for (k, c) in out.iter_mut().enumerate() {
                let i = Vec3::new((k % res[0]) as f32, (k / res[0]) as f32, z as f32);
                let lo = bounds.min + cell * i - margin;
                let hi = bounds.min + cell * (i + Vec3::ONE) + margin;
                let m = factor * volume.max_in(&Bounds3::new(lo, hi));
                // A cell whose bound is not a finite non-negative number bounds nothing: the
                // global one (the callers check that it is finite).
                *c = if m.is_finite() && m >= 0.0 { m } else { factor * volume.max() };
            }
        });
        let max = cells.iter().copied().fold(0.0, f32::max);
        MajorantGrid { bounds, res, cells, max }
    }

    /// The largest cell's majorant (m⁻¹): a bound of the extinction everywhere in the box.
    pub fn max(&self) -> f32 {
        self.max
    }

    /// Cells per axis.
    pub fn resolution(&self) -> [usize; 3] {
        self.res
    }

    /// Multiplies every cell by `f ≥ 0` (a microflake medium's largest projected area).
    pub fn scale(&mut self, f: f32) {
        self.cells.iter_mut().for_each(|c| *c *= f);
        self.max *= f;
    }

    /// The cell of world point `p` (clamped into the grid).
    fn cell_of(&self, p: Vec3) -> [usize; 3] {
        let o = self.bounds.offset(p);
        std::array::from_fn(|a| {
            let x = o[a] * self.res[a] as f32;
            if x.is_nan() {
                0
            } else {
                (x.max(0.0) as usize).min(self.res[a] - 1)
            }
        })
    }

    #[inline]
    fn cell(&self, i: [usize; 3]) -> f32 {
        self.cells[(i[2] * self.res[1] + i[1]) * self.res[0] + i[0]]
    }

    /// The majorant (m⁻¹) of the cell holding world point `p` (points outside the box: of the
    /// nearest cell).
    pub fn at(&self, p: Vec3) -> f32 {
        self.cell(self.cell_of(p))
    }

    /// The walk along `ray` (its direction unit or not: distances are in its parameter) over
    /// `[t0, t1]`, a part of the ray inside the box.
    pub fn walk(&self, ray: &Ray, t0: f32, t1: f32) -> MajorantWalk<'_> {
        let mut w = MajorantWalk {
            grid: self,
            cell: [0; 3],
            step: [0; 3],
            next_t: [f32::INFINITY; 3],
            delta_t: [f32::INFINITY; 3],
            t: t0,
            end: t1,
            sigma: self.cells[0],
            t1,
            depth: 0.0,
        };
        if self.cells.len() == 1 {
            return w;
        }
        let p = ray.at(t0);
        let cell = self.cell_of(p);
        w.cell = cell.map(|c| c as i32);
        let size = self.bounds.diagonal();
        for a in 0..3 {
            let d = ray.d[a];
            let width = size[a] / self.res[a] as f32;
            if self.res[a] == 1 || d == 0.0 || width <= 0.0 {
                // One cell along this axis, or a ray that never leaves its slab.
                w.step[a] = 0;
                continue;
            }
            let (face, step) = if d > 0.0 { (cell[a] + 1, 1) } else { (cell[a], -1) };
            let x = self.bounds.min[a] + face as f32 * width;
            w.next_t[a] = t0 + (x - p[a]) / d;
            w.delta_t[a] = width / d.abs();
            w.step[a] = step;
        }
        w.enter();
        w
    }
}

/// A walk along a ray through a [`MajorantGrid`]'s cells (3D DDA, pbrt-v4's
/// `DDAMajorantIterator`), drawing tentative collisions one at a time.
#[derive(Clone, Debug)]
pub struct MajorantWalk<'a> {
    grid: &'a MajorantGrid,
    /// The current cell.
    cell: [i32; 3],
    /// Direction of the next cell per axis (0: the ray stays in this slab).
    step: [i32; 3],
    /// Ray parameter of the next face crossing per axis.
    next_t: [f32; 3],
    /// Ray parameter between face crossings per axis.
    delta_t: [f32; 3],
    /// Where the walk is (the last collision, or where it entered the current cell).
    t: f32,
    /// Where the current cell's part of the ray ends (≤ `t1`).
    end: f32,
    /// The current cell's majorant.
    sigma: f32,
    /// Where the walk ends.
    t1: f32,
    /// The majorant's optical depth walked so far, from `t0` to `t`.
    depth: f32,
}

impl MajorantWalk<'_> {
    /// Takes the current cell's majorant and where its part of the ray ends.
    #[inline]
    fn enter(&mut self) {
        let i = self.cell.map(|c| c as usize);
        self.sigma = self.grid.cell(i);
        self.end = self.next_t[0].min(self.next_t[1]).min(self.next_t[2]).min(self.t1);
    }

    /// Moves into the next cell along the ray; false where the walk leaves the grid or reaches
    /// `t1`.
    #[inline]
    fn advance(&mut self) -> bool {
        if self.end >= self.t1 {
            return false;
        }
        let a = if self.next_t[0] <= self.next_t[1] {
            if self.next_t[0] <= self.next_t[2] {
                0
            } else {
                2
            }
        } else if self.next_t[1] <= self.next_t[2] {
            1
        } else {
            2
        };
        if self.step[a] == 0 {
            return false;
        }
        self.t = self.t.max(self.end);
        self.cell[a] += self.step[a];
        if self.cell[a] < 0 || self.cell[a] >= self.grid.res[a] as i32 {
            return false;
        }
        self.next_t[a] += self.delta_t[a];
        self.enter();
        true
    }

    /// The next tentative collision from where the walk is, drawn with `u ∈ [0, 1)`: its ray
    /// parameter and the majorant there, or `None` where the majorant's optical depth to `t1`
    /// is less than `−ln(1 − u)` (the walk is then at its end).
    #[inline]
    pub fn next(&mut self, u: f32) -> Option<(f32, f32)> {
        let mut tau = -(-u).ln_1p();
        loop {
            let len = (self.end - self.t).max(0.0);
            let cell_depth = self.sigma * len;
            if tau < cell_depth {
                let t = (self.t + tau / self.sigma).min(self.end);
                self.depth += tau;
                self.t = t;
                return Some((t, self.sigma));
            }
            tau -= cell_depth;
            self.depth += cell_depth;
            if !self.advance() {
                self.t = self.t1;
                return None;
            }
        }
    }

    /// The majorant's optical depth `∫ σ̄ dt` from the walk's start to where it is.
    pub fn optical_depth(&self) -> f32 {
        self.depth
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::GridVolume;
    use crate::math::Transform;
    use crate::sampling::Pcg32;
    use crate::texture::volume::{GridFilter, GridWrap};
    use std::sync::Arc;

    /// A 7 × 5 × 3 grid of random values, a third of them zero, one channel or three.
    fn random_grid(channels: usize, rng: &mut Pcg32) -> Arc<GridVolume> {
        let res = [7, 5, 3];
        let data = (0..res.iter().product::<usize>() * channels)
            .map(|_| if rng.next_f32() < 0.33 { 0.0 } else { 4.0 * rng.next_f32() })
            .collect();
        Arc::new(GridVolume { res, channels, bbox: [[0.0; 3], [1.0; 3]], data })
    }

    fn transforms() -> Vec<Transform> {
        vec![
            Transform::IDENTITY,
            Transform::translate(Vec3::new(-1.0, 2.0, 0.5)) * Transform::scale(Vec3::new(3.0, 0.5, 2.0)).unwrap(),
            Transform::translate(Vec3::new(0.3, -0.2, 1.0))
                * Transform::rotate(Vec3::new(1.0, 2.0, 0.5).normalize(), 37.0).unwrap()
                * Transform::scale(Vec3::new(2.0, 1.0, 1.5)).unwrap(),
        ]
    }

    /// Every lookup anywhere in the box (a rotated volume's box holds points outside its unit
    /// cube, read by the wrap mode) is at most its cell's majorant, for both filters, every wrap
    /// mode and one or three channels; and the bound is local: cells of zero texels are zero
    /// (a zero bound where the volume is not zero would be a bias, a global one no speed-up).
    #[test]
    fn majorants_bound_every_lookup_in_their_cell() {
        let mut rng = Pcg32::new(7, 1);
        for channels in [1, 3] {
            let data = random_grid(channels, &mut rng);
            for filter in [GridFilter::Nearest, GridFilter::Trilinear] {
                for wrap in [GridWrap::Clamp, GridWrap::Repeat, GridWrap::Mirror, GridWrap::Zero] {
                    for to_world in transforms() {
                        let v = Volume::grid(data.clone(), filter, wrap, to_world).unwrap();
                        let grid = MajorantGrid::with_resolution(&v, 2.5, [7, 5, 3]);
                        assert!(grid.max() <= 2.5 * v.max() * (1.0 + 1e-6));
                        let b = v.bounds();
                        for _ in 0..20_000 {
                            let f = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                            let p = b.min + b.diagonal() * f;
                            let value = 2.5 * v.eval(p).max_element();
                            assert!(
                                value <= grid.at(p) * (1.0 + 1e-5) + 1e-6,
                                "{filter:?} {wrap:?} {channels} channels at {p}: {value} above {}",
                                grid.at(p)
                            );
                        }
                    }
                }
            }
        }
        // Half the grid empty: the majorants there are zero, the others the texels' largest.
        let mut data = vec![0.0f32; 8 * 8 * 8];
        for (k, d) in data.iter_mut().enumerate() {
            if k % 8 >= 4 {
                *d = 1.0 + (k % 8) as f32;
            }
        }
        let data = Arc::new(GridVolume { res: [8, 8, 8], channels: 1, bbox: [[0.0; 3], [1.0; 3]], data });
        let v = Volume::grid(data, GridFilter::Nearest, GridWrap::Clamp, Transform::IDENTITY).unwrap();
        let grid = MajorantGrid::new(&v, 1.0);
        assert_eq!(grid.resolution(), [8, 8, 8]);
        assert_eq!(grid.at(Vec3::new(0.1, 0.5, 0.5)), 0.0);
        assert_eq!(grid.at(Vec3::new(0.3, 0.5, 0.5)), 0.0);
        assert_eq!(grid.at(Vec3::new(0.55, 0.5, 0.5)), 6.0);
        assert_eq!(grid.at(Vec3::new(0.99, 0.5, 0.5)), 8.0);
        // Constant volumes have one cell, and so do grids nearly as dense everywhere as their
        // densest texel.
        let c = Volume::constant(crate::math::Rgb::new(1.0, 3.0, 2.0), Transform::IDENTITY);
        let grid = MajorantGrid::new(&c, 2.0);
        assert_eq!((grid.resolution(), grid.max()), ([1; 3], 6.0));
        let dense: Vec<f32> = (0..6 * 6 * 6).map(|k| 0.8 + 0.2 * ((k % 6) as f32 / 5.0)).collect();
        let dense = Arc::new(GridVolume { res: [6, 6, 6], channels: 1, bbox: [[0.0; 3], [1.0; 3]], data: dense });
        let v = Volume::grid(dense, GridFilter::Trilinear, GridWrap::Clamp, Transform::IDENTITY).unwrap();
        let grid = MajorantGrid::new(&v, 1.0);
        assert_eq!((grid.resolution(), grid.max(), grid.at(Vec3::splat(0.1))), ([1; 3], 1.0, 1.0));
    }

    /// The majorant's optical depth from `t0` to `t` along `ray`, by the midpoint rule on a
    /// fine lattice (exact but for the few steps that straddle a face).
    fn depth_to(grid: &MajorantGrid, ray: &Ray, t0: f32, t: f32) -> f64 {
        let n = 20_000;
        let h = (t - t0) as f64 / n as f64;
        (0..n).map(|i| grid.at(ray.at(t0 + ((i as f64 + 0.5) * h) as f32)) as f64 * h).sum()
    }

    /// The walk inverts the majorant's optical depth: a collision drawn with `u` lies where
    /// `∫ σ̄ dt` from the start reaches `−ln(1 − u)` (so collisions have the density of the
    /// Poisson process of rate `σ̄`), and successive draws continue from the last collision;
    /// where the depth to `t1` falls short, the walk ends with the whole depth walked. Rays
    /// along and against every axis, oblique ones, and one parallel to a face.
    #[test]
    fn the_walk_inverts_the_majorant_optical_depth() {
        let mut rng = Pcg32::new(3, 9);
        let data = random_grid(1, &mut rng);
        let to_world =
            Transform::translate(Vec3::new(-1.0, 2.0, 0.5)) * Transform::scale(Vec3::new(3.0, 0.5, 2.0)).unwrap();
        let v = Volume::grid(data, GridFilter::Trilinear, GridWrap::Clamp, to_world).unwrap();
        let grid = MajorantGrid::with_resolution(&v, 0.4, [7, 5, 3]);
        let b = v.bounds();
        let c = b.centroid();
        let dirs = [
            Vec3::X,
            -Vec3::X,
            Vec3::Y,
            -Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(0.6, -0.3, 0.5).normalize(),
            Vec3::new(-0.2, 0.9, -0.4).normalize(),
        ];
        for d in dirs {
            let ray = Ray::new(c - d * 10.0, d);
            let (t0, t1) = b.intersect_p(&ray, d.recip()).unwrap();
            let total = depth_to(&grid, &ray, t0, t1);
            assert!(total > 0.5, "{d}: depth {total}");
            // One draw from the start, at several quantiles of the depth.
            for q in [0.05, 0.3, 0.7, 0.95, 1.2] {
                let u = (1.0 - (-q * total).exp()) as f32;
                let tau = -(1.0 - u as f64).ln();
                let mut walk = grid.walk(&ray, t0, t1);
                match walk.next(u) {
                    Some((t, sigma)) => {
                        assert!(q < 1.0, "{d}: a collision beyond the depth");
                        let got = depth_to(&grid, &ray, t0, t);
                        assert!((got - tau).abs() < 2e-3 * total, "{d} q {q}: depth {got}, wanted {tau}");
                        assert!((walk.optical_depth() as f64 - tau).abs() < 1e-4 * total);
                        assert_eq!(sigma, grid.at(ray.at(t)), "{d}: the majorant where the collision is");
                    }
                    None => {
                        assert!(q > 1.0, "{d} q {q}: no collision");
                        assert!((walk.optical_depth() as f64 - total).abs() < 2e-3 * total);
                    }
                }
            }
            // Successive draws: each continues from the last.
            let mut walk = grid.walk(&ray, t0, t1);
            let mut sum = 0.0f64;
            while let Some((t, _)) = walk.next(0.3) {
                sum += -(0.7f64).ln();
                let got = depth_to(&grid, &ray, t0, t);
                assert!((got - sum).abs() < 3e-3 * total.max(sum), "{d}: depth {got}, wanted {sum}");
            }
        }
        // A ray in a face's plane inside the box and one along an axis through a corner's edge.
        let ray = Ray::new(Vec3::new(b.min.x - 1.0, b.min.y + 0.5 * b.diagonal().y, c.z), Vec3::X);
        let (t0, t1) = b.intersect_p(&ray, ray.d.recip()).unwrap();
        let mut walk = grid.walk(&ray, t0, t1);
        while walk.next(0.5).is_some() {}
        let total = depth_to(&grid, &ray, t0, t1);
        assert!((walk.optical_depth() as f64 - total).abs() < 2e-3 * total.max(1.0));
    }

    /// Walks end, within `[t0, t1]`, on any ray: from inside and outside the box, along axes
    /// (zero direction components), with `t0 = t1`, and with NaN or infinite components (which
    /// leave the grid or never collide, but never loop).
    #[test]
    fn walks_end_on_any_ray() {
        let mut rng = Pcg32::new(2, 2);
        let data = random_grid(1, &mut rng);
        let v = Volume::grid(data, GridFilter::Trilinear, GridWrap::Clamp, Transform::IDENTITY).unwrap();
        let grid = MajorantGrid::with_resolution(&v, 3.0, [7, 5, 3]);
        let odd = [0.0, -0.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e-30, 0.5, -0.7];
        for k in 0..4000 {
            let pick = |i: usize| odd[(k / 8usize.pow(i as u32)) % 8];
            let o = if k % 3 == 0 {
                Vec3::new(pick(0), 0.5, pick(1))
            } else {
                Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 1.4 - Vec3::splat(0.2)
            };
            let d = Vec3::new(pick(2), pick(3), 0.3);
            let ray = Ray::new(o, d);
            let (t0, t1) = if k % 5 == 0 { (0.3, 0.3) } else { (0.0, 2.0 * rng.next_f32()) };
            let mut walk = grid.walk(&ray, t0, t1);
            let mut n = 0;
            while let Some((t, sigma)) = walk.next(rng.next_f32()) {
                assert!((t0..=t1).contains(&t) && sigma > 0.0, "{o} {d}: collision at {t} of [{t0}, {t1}]");
                n += 1;
                assert!(n < 100_000, "{o} {d}: no end");
            }
        }
    }

    /// Sampled by uniform numbers, the first collision's distance has the density
    /// `σ̄(t) e^(−∫σ̄)` (χ² over equal-probability bins of the exact CDF, computed by the
    /// midpoint rule), and passes with probability `e^(−∫₀^{t1} σ̄)`.
    #[test]
    fn first_collisions_follow_the_exponential_law_of_the_majorant() {
        let mut rng = Pcg32::new(11, 2);
        let data = random_grid(3, &mut rng);
        let to_world = Transform::scale(Vec3::new(0.4, 0.3, 0.5)).unwrap();
        let v = Volume::grid(data, GridFilter::Nearest, GridWrap::Clamp, to_world).unwrap();
        let grid = MajorantGrid::with_resolution(&v, 1.0, [7, 5, 3]);
        let b = v.bounds();
        let d = Vec3::new(0.7, 0.2, 0.3).normalize();
        let ray = Ray::new(b.centroid() - d * 3.0, d);
        let (t0, t1) = b.intersect_p(&ray, d.recip()).unwrap();
        // The cumulative depth on a fine lattice (midpoint rule), interpolated.
        let m = 20_000;
        let h = (t1 - t0) as f64 / m as f64;
        let mut cumulative = vec![0.0f64; m + 1];
        for i in 0..m {
            cumulative[i + 1] = cumulative[i] + grid.at(ray.at(t0 + ((i as f64 + 0.5) * h) as f32)) as f64 * h;
        }
        let depth = |t: f32| {
            let x = ((t - t0) as f64 / h).clamp(0.0, m as f64);
            let i = (x as usize).min(m - 1);
            cumulative[i] + (cumulative[i + 1] - cumulative[i]) * (x - i as f64)
        };
        // Bins at equal steps of the CDF F(t) = 1 − e^(−depth(t)), up to F(t1), and one for
        // passing.
        let bins = 16;
        let f1 = 1.0 - (-cumulative[m]).exp();
        let n = 200_000;
        let mut counts = vec![0usize; bins + 1];
        for _ in 0..n {
            match grid.walk(&ray, t0, t1).next(rng.next_f32()) {
                None => counts[bins] += 1,
                Some((t, _)) => {
                    let f = 1.0 - (-depth(t)).exp();
                    counts[((f / f1 * bins as f64) as usize).min(bins - 1)] += 1;
                }
            }
        }
        let expect: Vec<f64> =
            (0..=bins).map(|k| if k < bins { f1 / bins as f64 } else { 1.0 - f1 } * n as f64).collect();
        let chi2: f64 = counts.iter().zip(&expect).map(|(&c, &e)| (c as f64 - e).powi(2) / e).sum();
        // 16 degrees of freedom: p = 1e-4 at 46.
        assert!(chi2 < 46.0, "χ² {chi2}: {counts:?}");
    }
}
