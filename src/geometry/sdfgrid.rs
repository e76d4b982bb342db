//! Mitsuba's `sdfgrid`: the zero level set of a signed distance function sampled on a grid
//! (positive outside), interpolated trilinearly between the samples. The grid spans the unit
//! cube of object space, `[0, 1]³`, its `n` samples along an axis lying at `i / (n − 1)`.
//!
//! Each voxel (the cell between 2×2×2 samples) whose corners change sign (or touch zero) is one
//! primitive of the BVH, bounded by the tight box of Hansson-Söderlund and Akenine-Möller (2023):
//! the corners on the surface and the points where the surface crosses the voxel's edges. A ray
//! meets the trilinear interpolant along its segment in the voxel as a cubic in the ray
//! parameter (Hansson-Söderlund, Evans and Akenine-Möller, JCGT 2022); the first root is
//! bracketed by splitting the segment at the cubic's extrema (Marmitt et al. 2004) and refined
//! by Newton's method safeguarded by bisection, as Mitsuba does. The geometric normal is the
//! gradient of the interpolant; the shading normal is that (`normals = "analytic"`) or the smooth
//! blend of the eight neighbouring voxels' gradients of the JCGT paper (`"smooth"`, Mitsuba's
//! default). Like Mitsuba's, the shape has no texture coordinates and no area (it cannot emit).

use crate::image::GridVolume;
use crate::math::{lerp, Bounds3, Ray, Transform, Vec3};

/// Ray-parameter tolerance of the root finder (Mitsuba's `NumSolveEpsilon`), also bounded by a
/// fraction of the segment in the voxel so that tiny grids stay accurate.
const SOLVE_EPSILON: f32 = 1e-5;
/// Iterations of the root finder at most.
const SOLVE_MAX_ITERATIONS: u32 = 50;

/// Why a grid volume does not make an SDF grid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SdfGridError {
    /// Not one value per grid point.
    #[error("an SDF grid has one channel, this one has {0}")]
    Channels(usize),
    /// Fewer than two samples along an axis.
    #[error("an SDF grid has at least 2 samples per axis, this one {0:?}")]
    TooSmall([usize; 3]),
    /// More samples than 32-bit indices reach.
    #[error("the SDF grid has more than 2³² samples")]
    TooLarge,
    /// A sample is NaN or infinite.
    #[error("SDF sample {index} is {value} (the samples must be finite)")]
    NonFinite {
        /// Its index.
        index: usize,
        /// Its value.
        value: f32,
    },
    /// No voxel's samples change sign.
    #[error("the SDF grid holds no surface: no voxel's samples change sign")]
    NoSurface,
}

/// A signed distance field on a grid (world space through `to_world`).
#[derive(Clone, Debug)]
pub struct SdfGrid {
    /// Samples along x, y, z (each ≥ 2).
    res: [usize; 3],
    /// The samples, x fastest.
    values: Vec<f32>,
    to_world: Transform,
    to_object: Transform,
    /// Smooth shading normals (else the interpolant's gradient).
    smooth: bool,
    /// Sample index of the lower corner of each voxel the surface passes through.
    voxels: Vec<u32>,
    /// Their tight bounds (world space).
    bounds: Vec<Bounds3>,
}

/// The cubic `c0 + c1 t + c2 t² + c3 t³`.
#[derive(Clone, Copy)]
struct Cubic([f32; 4]);

impl Cubic {
    #[inline]
    fn eval(&self, t: f32) -> f32 {
        let c = self.0;
        ((c[3] * t + c[2]) * t + c[1]) * t + c[0]
    }

    #[inline]
    fn derivative(&self, t: f32) -> f32 {
        let c = self.0;
        (3.0 * c[3] * t + 2.0 * c[2]) * t + c[1]
    }

    /// The real roots of the derivative `3 c3 t² + 2 c2 t + c1` (ascending; none, or two that
    /// may coincide).
    fn extrema(&self) -> Option<(f32, f32)> {
        let (a, b, c) = (3.0 * self.0[3], 2.0 * self.0[2], self.0[1]);
        if a == 0.0 {
            return (b != 0.0).then(|| (-c / b, -c / b));
        }
        let disc = b as f64 * b as f64 - 4.0 * a as f64 * c as f64;
        if disc < 0.0 {
            return None;
        }
        // The numerically stable pair of roots.
        let q = -0.5 * (b as f64 + (b as f64).signum() * disc.sqrt());
        let (r0, r1) = if q == 0.0 { (0.0, 0.0) } else { (q / a as f64, c as f64 / q) };
        Some((r0.min(r1) as f32, r0.max(r1) as f32))
    }
}

/// Bilinear interpolant of `f` (indexed u + 2v) at (u, v).
#[inline]
fn bilerp(f: [f32; 4], u: f32, v: f32) -> f32 {
    lerp(lerp(f[0], f[1], u), lerp(f[2], f[3], u), v)
}

/// Trilinear interpolant of the corner values `f` (indexed x + 2y + 4z) at `p` in the unit cube.
#[inline]
fn trilerp(f: &[f32; 8], p: Vec3) -> f32 {
    lerp(bilerp([f[0], f[1], f[2], f[3]], p.x, p.y), bilerp([f[4], f[5], f[6], f[7]], p.x, p.y), p.z)
}

/// Gradient of the trilinear interpolant (per unit of the cube).
#[inline]
fn trilerp_grad(f: &[f32; 8], p: Vec3) -> Vec3 {
    Vec3::new(
        bilerp([f[1] - f[0], f[3] - f[2], f[5] - f[4], f[7] - f[6]], p.y, p.z),
        bilerp([f[2] - f[0], f[3] - f[1], f[6] - f[4], f[7] - f[5]], p.x, p.z),
        bilerp([f[4] - f[0], f[5] - f[1], f[6] - f[2], f[7] - f[3]], p.x, p.y),
    )
}

/// The offset of corner `i` (x + 2y + 4z) of a voxel.
#[inline]
fn corner(i: usize) -> Vec3 {
    Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32)
}

impl SdfGrid {
    /// The SDF of a one-channel grid volume placed by `to_world`; an error if the grid is not
    /// one channel of at least 2×2×2 finite values, or no voxel holds surface.
    pub fn new(grid: &GridVolume, to_world: Transform, smooth: bool) -> Result<SdfGrid, SdfGridError> {
        if grid.channels != 1 {
            return Err(SdfGridError::Channels(grid.channels));
        }
        if grid.res.iter().any(|&n| n < 2) {
            return Err(SdfGridError::TooSmall(grid.res));
        }
        if grid.data.len() > u32::MAX as usize {
            return Err(SdfGridError::TooLarge);
        }
        if let Some(i) = grid.data.iter().position(|v| !v.is_finite()) {
            return Err(SdfGridError::NonFinite { index: i, value: grid.data[i] });
        }
        let mut sdf = SdfGrid {
            res: grid.res,
            values: grid.data.clone(),
            to_object: to_world.inverse(),
            to_world,
            smooth,
            voxels: Vec::new(),
            bounds: Vec::new(),
        };
        let [nx, ny, nz] = sdf.res;
        let voxel_size = sdf.voxel_size();
        for z in 0..nz - 1 {
            for y in 0..ny - 1 {
                for x in 0..nx - 1 {
                    let base = (z * ny + y) * nx + x;
                    if let Some(b) = sdf.tight_bounds(base) {
                        let offset = Vec3::new(x as f32, y as f32, z as f32);
                        let local = Bounds3::new((b.min + offset) * voxel_size, (b.max + offset) * voxel_size);
                        let world = sdf.to_world.apply_bounds(&local);
                        // Padding against rounding in the box tests (as Mitsuba pads).
                        let voxel_extent = sdf.to_world.apply_vector(voxel_size).abs();
                        let pad = voxel_extent * 1e-3 + world.min.abs().max(world.max.abs()) * (8.0 * f32::EPSILON);
                        sdf.voxels.push(base as u32);
                        sdf.bounds.push(Bounds3::new(world.min - pad, world.max + pad));
                    }
                }
            }
        }
        if sdf.voxels.is_empty() {
            return Err(SdfGridError::NoSurface);
        }
        Ok(sdf)
    }

    /// Object-space size of a voxel.
    #[inline]
    fn voxel_size(&self) -> Vec3 {
        Vec3::new(1.0 / (self.res[0] - 1) as f32, 1.0 / (self.res[1] - 1) as f32, 1.0 / (self.res[2] - 1) as f32)
    }

    /// Voxels per axis, as a vector (object space → grid coordinates).
    #[inline]
    fn resolution(&self) -> Vec3 {
        Vec3::new((self.res[0] - 1) as f32, (self.res[1] - 1) as f32, (self.res[2] - 1) as f32)
    }

    /// The eight samples of the voxel whose lower corner is sample `base` (x + 2y + 4z).
    #[inline]
    fn corners(&self, base: usize) -> [f32; 8] {
        let [nx, ny, _] = self.res;
        std::array::from_fn(|i| self.values[base + (i & 1) + nx * (((i >> 1) & 1) + ny * (i >> 2))])
    }

    /// The sample at grid point `q`, clamped to the grid.
    #[inline]
    fn sample(&self, q: [i64; 3]) -> f32 {
        let c = |k: usize| q[k].clamp(0, self.res[k] as i64 - 1) as usize;
        self.values[(c(2) * self.res[1] + c(1)) * self.res[0] + c(0)]
    }

    /// The voxel's tight box in its unit cube, if the surface passes through it (its samples
    /// are neither all positive nor all negative).
    fn tight_bounds(&self, base: usize) -> Option<Bounds3> {
        let f = self.corners(base);
        if !(f.iter().any(|&v| v >= 0.0) && f.iter().any(|&v| v <= 0.0)) {
            return None;
        }
        let mut b = Bounds3::EMPTY;
        for (i, &v) in f.iter().enumerate() {
            if v == 0.0 {
                b = b.union_point(corner(i));
            }
            for axis in 0..3 {
                let j = i | (1 << axis);
                if i & (1 << axis) != 0 || !(v * f[j] <= 0.0 && v != f[j]) {
                    continue;
                }
                let mut p = corner(i);
                p[axis] = v / (v - f[j]);
                b = b.union_point(p);
            }
        }
        Some(b)
    }

    /// Voxel primitive `i`: the sample index of its lower corner and that corner's grid
    /// coordinates.
    #[inline]
    fn voxel(&self, i: usize) -> (usize, Vec3) {
        let base = self.voxels[i] as usize;
        let [nx, ny, _] = self.res;
        (base, Vec3::new((base % nx) as f32, ((base / nx) % ny) as f32, (base / (nx * ny)) as f32))
    }

    /// Number of voxels holding surface (the BVH's primitives).
    pub fn len(&self) -> usize {
        self.voxels.len()
    }

    /// Whether no voxel holds surface (never, for a grid [`SdfGrid::new`] accepted).
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty()
    }

    /// World bounds of voxel primitive `i`.
    pub fn voxel_bounds(&self, i: usize) -> Bounds3 {
        self.bounds[i]
    }

    /// The first crossing of the surface by `ray` inside voxel primitive `i`, in `(0, t_max)`.
    pub fn intersect(&self, i: usize, ray: &Ray, t_max: f32) -> Option<f32> {
        let (base, voxel) = self.voxel(i);
        let res = self.resolution();
        // Object space (the direction keeps its length change, so t is the world t), then the
        // voxel's unit cube.
        let o = self.to_object.apply_point(ray.o) * res - voxel;
        let d = self.to_object.apply_vector(ray.d) * res;
        let d_rcp = d.recip();
        let d_pos = d_rcp.cmpge(Vec3::ZERO);
        // Slab test; a ray in a boundary plane (NaN distance) counts as inside that slab.
        let near = Vec3::select(d_pos, Vec3::ZERO, Vec3::ONE);
        let far = Vec3::select(d_pos, Vec3::ONE, Vec3::ZERO);
        let mut t0 = (near - o) * d_rcp;
        let mut t1 = (far - o) * d_rcp;
        t0 = Vec3::select(t0.is_nan_mask(), Vec3::NEG_INFINITY, t0);
        t1 = Vec3::select(t1.is_nan_mask(), Vec3::INFINITY, t1);
        let t_beg = t0.max_element().max(0.0);
        let t_end = t1.min_element();
        if !(t_beg < t_end && t_beg < t_max) {
            return None;
        }
        let f = self.corners(base);
        // The crossed faces' coordinates are snapped to 0 or 1, where the interpolant is exact,
        // so that neighbouring voxels agree on their shared face.
        let on_beg = t0.cmpeq(Vec3::splat(t_beg));
        let on_end = t1.cmpeq(Vec3::splat(t_end));
        let p_beg = o + d * t_beg;
        let f_beg = trilerp(&f, Vec3::select(on_beg, near, p_beg).clamp(Vec3::ZERO, Vec3::ONE));
        let f_end = trilerp(&f, Vec3::select(on_end, far, o + d * t_end).clamp(Vec3::ZERO, Vec3::ONE));
        let cubic = voxel_cubic(&f, p_beg, d);
        let t = solve(&cubic, t_end - t_beg, f_beg, f_end)? + t_beg;
        (t > 0.0 && t < t_max).then_some(t)
    }

    /// The hit at parameter `t` of `ray` in voxel primitive `i`: the point, its error bound, the
    /// geometric normal (the interpolant's gradient) and the shading normal.
    pub fn surface(&self, i: usize, ray: &Ray, t: f32) -> (Vec3, Vec3, Vec3, Vec3) {
        let (base, voxel) = self.voxel(i);
        let res = self.resolution();
        let p = ray.o + ray.d * t;
        let local = self.to_object.apply_point(p);
        let w = (local * res - voxel).clamp(Vec3::ZERO, Vec3::ONE);
        let grad = trilerp_grad(&self.corners(base), w) * res;
        let ng = self.to_world.apply_normal(grad).normalize_or_zero();
        let ng = if ng == Vec3::ZERO { -ray.d.normalize() } else { ng };
        let ns = if self.smooth {
            let n = self.to_world.apply_normal(self.smooth_gradient(local)).normalize_or_zero();
            if n == Vec3::ZERO {
                ng
            } else {
                n
            }
        } else {
            ng
        };
        // The point is where the root finder stopped, within its tolerance along the ray, not
        // reprojected onto the level set.
        let voxel_extent = self.to_world.apply_vector(self.voxel_size()).abs().max_element();
        let p_error =
            Vec3::splat(SOLVE_EPSILON * ray.d.length() + 1e-5 * voxel_extent) + p.abs() * (32.0 * f32::EPSILON);
        (p, p_error, ng, ns)
    }

    /// The smooth normal of Hansson-Söderlund et al. (object space, not normalized): the
    /// gradients of the eight voxels around the grid point nearest to `p` (object space), each
    /// the differences of the interpolant across the voxel along one axis at `p`'s position
    /// along the other two, normalized and blended trilinearly by `p`'s position relative to
    /// the voxels' centres; voxels outside the grid get weight zero.
    fn smooth_gradient(&self, p: Vec3) -> Vec3 {
        let res = self.resolution();
        let scaled = p * res;
        let n = [self.res[0] as i64, self.res[1] as i64, self.res[2] as i64];
        // The lower corner of the 2×2×2 voxels around the nearest grid point, and p relative to
        // their centres.
        let v = [0, 1, 2].map(|a| (crate::math::round(scaled[a]) as i64).saturating_sub(1));
        let mut uvw = [0, 1, 2].map(|a| scaled[a] - v[a] as f32 - 0.5);
        // The cell holding p, and p in it.
        let cell = [0, 1, 2].map(|a| (crate::math::floor(scaled[a]) as i64).clamp(0, n[a] - 2));
        let w = [0, 1, 2].map(|a| scaled[a] - cell[a] as f32);
        // The interpolant on the sample plane `q` across axis `a`, at p along the other two.
        let plane = |a: usize, q: i64| {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let f = std::array::from_fn(|i| {
                let mut idx = [0i64; 3];
                idx[a] = q;
                idx[b] = cell[b] + (i & 1) as i64;
                idx[c] = cell[c] + (i >> 1) as i64;
                self.sample(idx)
            });
            bilerp(f, w[b], w[c])
        };
        // Differences across the lower (d0) and upper (d1) voxels along each axis: one spans
        // p's cell, the other reaches the next sample plane on the other side (zero at the
        // grid's edge, where samples clamp).
        let (mut d0, mut d1) = (Vec3::ZERO, Vec3::ZERO);
        for a in 0..3 {
            let upper = cell[a] != v[a];
            let g0 = plane(a, cell[a]);
            let g1 = plane(a, cell[a] + 1);
            let gq = plane(a, cell[a] + if upper { -1 } else { 2 });
            let (dc, dq) = (g1 - g0, if upper { g0 - gq } else { gq - g1 });
            d0[a] = if upper { dq } else { dc } * res[a];
            d1[a] = if upper { dc } else { dq } * res[a];
        }
        let inside = v.map(|x| x >= 0);
        for a in 0..3 {
            if !inside[a] {
                uvw[a] = 1.0;
            }
        }
        let normals: [Vec3; 8] = std::array::from_fn(|i| {
            let hi = [i & 1 != 0, i & 2 != 0, i & 4 != 0];
            if (0..3).all(|a| hi[a] || inside[a]) {
                Vec3::new(
                    if hi[0] { d1.x } else { d0.x },
                    if hi[1] { d1.y } else { d0.y },
                    if hi[2] { d1.z } else { d0.z },
                )
                .normalize_or_zero()
            } else {
                Vec3::ZERO
            }
        });
        let l = |a: Vec3, b: Vec3, t: f32| a + (b - a) * t;
        l(
            l(l(normals[0], normals[1], uvw[0]), l(normals[2], normals[3], uvw[0]), uvw[1]),
            l(l(normals[4], normals[5], uvw[0]), l(normals[6], normals[7], uvw[0]), uvw[1]),
            uvw[2],
        )
    }

    /// The interpolant at object-space point `p` (clamped into the grid), for tests.
    #[cfg(test)]
    fn value_at(&self, p: Vec3) -> f32 {
        let res = self.resolution();
        let g = (p * res).clamp(Vec3::ZERO, res);
        let cell = g.map(crate::math::floor).min(res - Vec3::ONE);
        let base = (cell.z as usize * self.res[1] + cell.y as usize) * self.res[0] + cell.x as usize;
        trilerp(&self.corners(base), g - cell)
    }
}

/// The trilinear interpolant of `f` along the ray `o + t d` (voxel unit-cube coordinates) as a
/// cubic in t. With `f = k0 + k1 x + k2 y + k4 z + k3 xy + k5 xz + k6 yz + k7 xyz`, expanding
/// each coordinate `x = o.x + t d.x` gives the coefficients below.
fn voxel_cubic(f: &[f32; 8], o: Vec3, d: Vec3) -> Cubic {
    let k0 = f[0];
    let k1 = f[1] - f[0];
    let k2 = f[2] - f[0];
    let k4 = f[4] - f[0];
    let k3 = f[3] - f[2] - k1;
    let k5 = f[5] - f[4] - k1;
    let k6 = f[6] - f[4] - k2;
    let k7 = (f[7] - f[6] - f[5] + f[4]) - k3;
    let c0 =
        k0 + k1 * o.x + k2 * o.y + k4 * o.z + k3 * o.x * o.y + k5 * o.x * o.z + k6 * o.y * o.z + k7 * o.x * o.y * o.z;
    let c1 = k1 * d.x
        + k2 * d.y
        + k4 * d.z
        + k3 * (o.x * d.y + o.y * d.x)
        + k5 * (o.x * d.z + o.z * d.x)
        + k6 * (o.y * d.z + o.z * d.y)
        + k7 * (d.x * o.y * o.z + o.x * d.y * o.z + o.x * o.y * d.z);
    let c2 =
        k3 * d.x * d.y + k5 * d.x * d.z + k6 * d.y * d.z + k7 * (d.x * d.y * o.z + d.x * o.y * d.z + o.x * d.y * d.z);
    let c3 = k7 * d.x * d.y * d.z;
    Cubic([c0, c1, c2, c3])
}

/// The first root of `cubic` in `[0, t_end]` (whose values at the ends are `f_beg`, `f_end`):
/// the interval is cut at the cubic's extrema to the first part whose ends differ in sign, then
/// Newton's method from the secant estimate, falling back to bisection when a step leaves the
/// bracket. `None` if no part brackets a root.
fn solve(cubic: &Cubic, t_end: f32, f_beg: f32, f_end: f32) -> Option<f32> {
    let (mut t_near, mut t_far, mut f_near, mut f_far) = (0.0f32, t_end, f_beg, f_end);
    if let Some((r0, r1)) = cubic.extrema() {
        for r in [r0, r1] {
            if t_near <= r && r <= t_far {
                let fr = cubic.eval(r);
                if f_near * fr <= 0.0 {
                    (t_far, f_far) = (r, fr);
                } else {
                    (t_near, f_near) = (r, fr);
                }
            }
        }
    }
    if f_near * f_far > 0.0 || f_near.is_nan() || f_far.is_nan() {
        return None;
    }
    let epsilon = SOLVE_EPSILON.min(1e-3 * t_end);
    let mut t = t_near + (t_far - t_near) * (-f_near / (f_far - f_near));
    if !(t >= t_near && t <= t_far) {
        t = 0.5 * (t_near + t_far);
    }
    for _ in 0..SOLVE_MAX_ITERATIONS {
        let ft = cubic.eval(t);
        if ft == 0.0 {
            return Some(t);
        }
        if ft * f_near <= 0.0 {
            t_far = t;
        } else {
            t_near = t;
        }
        let newton = t - ft / cubic.derivative(t);
        let next = if newton > t_near && newton < t_far { newton } else { 0.5 * (t_near + t_far) };
        let step = (next - t).abs();
        t = next;
        // A NaN step ends the iteration too.
        if step.is_nan() || step < epsilon {
            break;
        }
    }
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_uniform_sphere, Pcg32};

    /// A sphere of radius `r` at the cube's centre, sampled on an `n`³ grid.
    fn sphere_grid(n: usize, r: f32) -> GridVolume {
        let mut data = Vec::with_capacity(n * n * n);
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = Vec3::new(x as f32, y as f32, z as f32) / (n - 1) as f32;
                    data.push((p - Vec3::splat(0.5)).length() - r);
                }
            }
        }
        GridVolume { res: [n; 3], channels: 1, bbox: [[0.0; 3], [1.0; 3]], data }
    }

    fn closest(sdf: &SdfGrid, ray: &Ray) -> Option<(f32, usize)> {
        (0..sdf.len())
            .filter(|&i| sdf.voxel_bounds(i).intersect_p(ray, ray.d.recip()).is_some())
            .filter_map(|i| sdf.intersect(i, ray, ray.t_max).map(|t| (t, i)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// Rays from outside toward a grid sphere hit where the interpolant vanishes, at the sphere's
    /// radius within the grid's approximation, with normals along the radius; rays that miss the
    /// sphere hit nothing.
    #[test]
    fn rays_hit_the_zero_level_set() {
        let to_world = Transform::translate(Vec3::new(1.0, -2.0, 0.5)) * Transform::scale(Vec3::splat(2.0)).unwrap();
        let sdf = SdfGrid::new(&sphere_grid(24, 0.3), to_world, false).unwrap();
        let smooth = SdfGrid { smooth: true, ..sdf.clone() };
        let center = to_world.apply_point(Vec3::splat(0.5));
        let mut rng = Pcg32::new(3, 7);
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..2000 {
            let dir = sample_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32())).value;
            let offset = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5) * 1.6;
            let origin = center - dir * 5.0 + offset;
            let ray = Ray::new(origin, dir);
            // Distance of the ray's line from the centre.
            let d_line = (center - origin - dir * (center - origin).dot(dir)).length();
            match closest(&sdf, &ray) {
                Some((t, i)) => {
                    hits += 1;
                    let (p, _, ng, ns) = sdf.surface(i, &ray, t);
                    assert!(sdf.voxel_bounds(i).contains(p), "the tight box holds the hit");
                    assert!(sdf.value_at(to_world.inverse().apply_point(p)).abs() < 1e-4, "on the level set");
                    assert!(((p - center).length() - 0.6).abs() < 0.01, "radius {}", (p - center).length());
                    let radial = (p - center).normalize();
                    assert!(ng.dot(radial) > 0.99 && ns.dot(radial) > 0.99, "{ng} {ns} vs {radial}");
                    let (.., ns_smooth) = smooth.surface(i, &ray, t);
                    assert!(ns_smooth.dot(radial) > 0.995, "smooth {ns_smooth} vs {radial}");
                    assert!(d_line < 0.6 + 0.01);
                }
                None => {
                    misses += 1;
                    assert!(d_line > 0.6 - 0.01, "missed a ray {d_line} from the centre");
                }
            }
        }
        assert!(hits > 200 && misses > 200, "{hits} hits, {misses} misses");
    }

    /// The smooth normal varies continuously across voxel faces (the analytic one does not).
    #[test]
    fn smooth_normals_are_continuous_across_voxels() {
        let sdf = SdfGrid::new(&sphere_grid(8, 0.35), Transform::IDENTITY, true).unwrap();
        let mut worst = 0.0f32;
        // Walk a great circle of the level set finely.
        let mut prev: Option<Vec3> = None;
        for k in 0..=2000 {
            let a = k as f32 / 2000.0 * std::f32::consts::PI;
            let dir = Vec3::new(a.cos(), a.sin(), 0.3).normalize();
            let ray = Ray::new(Vec3::splat(0.5) + dir * 2.0, -dir);
            let Some((t, i)) = closest(&sdf, &ray) else { panic!("ray {k} misses") };
            let (.., ns) = sdf.surface(i, &ray, t);
            if let Some(p) = prev {
                worst = worst.max(p.angle_between(ns));
            }
            prev = Some(ns);
        }
        assert!(worst < 0.01, "largest jump between neighbouring rays {worst} rad");
    }

    /// On a grid whose resolutions differ (5 × 3 × 7 samples), a linear field is reproduced
    /// exactly: hits lie on its plane and normals follow its gradient, which a mixed-up axis
    /// order or voxel indexing would break.
    #[test]
    fn non_cubic_grids_keep_their_axes() {
        let (res, grad, offset) = ([5usize, 3, 7], Vec3::new(0.5, 0.3, -0.2), -0.1);
        let mut data = Vec::new();
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    let p = Vec3::new(x as f32 / 4.0, y as f32 / 2.0, z as f32 / 6.0);
                    data.push(grad.dot(p) + offset);
                }
            }
        }
        let grid = GridVolume { res, channels: 1, bbox: [[0.0; 3], [1.0; 3]], data };
        let to_world = Transform::scale(Vec3::new(2.0, 1.0, 3.0)).unwrap();
        let sdf = SdfGrid::new(&grid, to_world, true).unwrap();
        let normal = to_world.apply_normal(grad).normalize();
        let mut rng = Pcg32::new(11, 2);
        let mut hits = 0;
        for _ in 0..500 {
            let target = to_world.apply_point(Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()));
            let dir = sample_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32())).value;
            let ray = Ray::new(target - dir * 10.0, dir);
            if let Some((t, i)) = closest(&sdf, &ray) {
                hits += 1;
                let (p, _, ng, ns) = sdf.surface(i, &ray, t);
                let local = to_world.inverse().apply_point(p);
                assert!((grad.dot(local) + offset).abs() < 1e-5, "off the plane at {local}");
                assert!(ng.dot(normal) > 0.9999, "{ng} vs {normal}");
                // The smooth normal too, a voxel or more inside the grid (at its edge the
                // clamped samples flatten the outer voxels' differences, as in Mitsuba).
                let voxel = Vec3::new(0.25, 0.5, 1.0 / 6.0);
                if local.cmpge(voxel).all() && local.cmple(Vec3::ONE - voxel).all() {
                    assert!(ns.dot(normal) > 0.9999, "{ns} vs {normal} at {local}");
                }
            }
        }
        assert!(hits > 100, "{hits}");
    }

    #[test]
    fn bad_grids_are_refused() {
        let mut g = sphere_grid(4, 0.3);
        g.channels = 3;
        assert!(SdfGrid::new(&g, Transform::IDENTITY, true).unwrap_err().to_string().contains("one channel"));
        let g = GridVolume { res: [1, 4, 4], channels: 1, bbox: [[0.0; 3]; 2], data: vec![0.0; 16] };
        assert!(SdfGrid::new(&g, Transform::IDENTITY, true).unwrap_err().to_string().contains("at least 2"));
        let g = GridVolume { res: [2, 2, 2], channels: 1, bbox: [[0.0; 3]; 2], data: vec![1.0; 8] };
        assert_eq!(SdfGrid::new(&g, Transform::IDENTITY, true).unwrap_err(), SdfGridError::NoSurface);
        let mut g = sphere_grid(4, 0.3);
        g.data[5] = f32::NAN;
        assert!(SdfGrid::new(&g, Transform::IDENTITY, true).unwrap_err().to_string().contains("finite"));
    }

    use crate::math::Vec2;
}
