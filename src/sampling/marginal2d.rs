//! Mitsuba's continuous `Marginal2D`: a density on `[0,1]²` that *linearly* interpolates a
//! `width × height` grid of values, optionally conditioned on parameters (each tabulated at
//! given values and interpolated linearly between them), sampled by inverting its continuous
//! marginal in y, then its continuous conditional in x. The mapping from `[0,1]²` to samples is
//! continuous and bijective; [`Marginal2D::invert`] is its inverse. The measured BSDF (RGL's
//! `.bsdf` files) is built from these.
//!
//! Layout: `data[((p₀ · n₁ + p₁) · … ) · height · width + y · width + x]` for parameter indices
//! `p₀, p₁, …` (outermost first), then row `y`, then column `x`; grid point `(x, y)` sits at
//! `(x / (width − 1), y / (height − 1))`. A *slice* is the grid of one combination of parameter
//! indices. Normalized, every slice integrates to one, and so does any interpolation between
//! slices (a mixture of densities); unnormalized, [`Marginal2D::eval`] interpolates the values
//! as they are.
//!
//! Per slice, `marginal[y]` is ∫ of the rows' integrals from 0 to grid row `y + 1` (trapezoids;
//! `height − 1` entries) and `conditional[y · (width − 1) + x]` the integral of row `y` from 0
//! to column `x + 1` (`height · (width − 1)` entries); both are linear in the data, so they
//! interpolate between slices exactly as the data does.

use crate::math::{lerp, Vec2};

/// Most parameters a distribution may depend on (Mitsuba instantiates 0, 2 and 3).
pub const MAX_PARAMS: usize = 3;

/// A continuous, parameterized 2D distribution (Mitsuba's `Marginal2D<Float, N, true>`).
#[derive(Clone, Debug)]
pub struct Marginal2D {
    width: usize,
    height: usize,
    /// Values at which each parameter is tabulated (increasing), outermost first.
    params: Vec<Vec<f32>>,
    /// Slice stride of each parameter.
    strides: Vec<usize>,
    /// The values, scaled by each slice's normalization when normalized.
    data: Vec<f32>,
    marginal: Vec<f32>,
    conditional: Vec<f32>,
    normalized: bool,
}

/// The slices a parameter value falls between and their weights (at most `2^MAX_PARAMS`).
#[derive(Clone, Copy, Debug)]
struct Corners {
    slice: [usize; 1 << MAX_PARAMS],
    weight: [f32; 1 << MAX_PARAMS],
    count: usize,
}

impl Corners {
    /// `Σ wₖ table[sliceₖ · slice_len + i]`.
    #[inline]
    fn lookup(&self, table: &[f32], slice_len: usize, i: usize) -> f32 {
        let mut v = 0.0;
        for k in 0..self.count {
            v += self.weight[k] * table[self.slice[k] * slice_len + i];
        }
        v
    }
}

/// The first index in `lo..=hi` whose `pred` is false (`hi` if none is), by bisection.
#[inline]
fn first_false(mut lo: usize, hi: usize, pred: impl Fn(usize) -> bool) -> usize {
    let mut end = hi;
    while lo < end {
        let mid = (lo + end) / 2;
        if pred(mid) {
            lo = mid + 1;
        } else {
            end = mid;
        }
    }
    lo
}

/// Inverts the integral of a linear density `v₀ → v₁` over a segment of width `1 / inv_width`:
/// the fraction `t ∈ [0, 1]` of the segment at which the integral reaches `u`.
#[inline]
fn sample_segment(u: f32, inv_width: f32, v0: f32, v1: f32) -> f32 {
    let non_const = (v0 - v1).abs() > 1e-4 * (v0 + v1);
    let divisor = if non_const { v0 - v1 } else { v0 + v1 };
    let mut t = u * 2.0 * inv_width;
    if non_const {
        t = v0 - (v0 * v0 + t * (v1 - v0)).max(0.0).sqrt();
    }
    if divisor != 0.0 {
        t /= divisor;
    }
    t
}

/// The integral of a linear density `v₀ → v₁` over the first fraction `t` of a segment of
/// `width` (the inverse of [`sample_segment`]).
#[inline]
fn invert_segment(t: f32, width: f32, v0: f32, v1: f32) -> f32 {
    t * (v0 + (v1 - v0) * 0.5 * t) * width
}

impl Marginal2D {
    /// A distribution of `width × height` grid values per slice (both ≥ 2) over the parameter
    /// grid `params` (each non-empty and increasing; at most [`MAX_PARAMS`]). `normalize`: scale
    /// every slice to integrate to one (needed for sampling); a density cannot be negative, so
    /// negative values (measured data has small ones) are then taken as 0, while an unnormalized
    /// table interpolates them as they are. Errors name what is wrong: the data's length, a
    /// value that is not finite, a slice to normalize that is zero everywhere.
    pub fn new(
        data: &[f32],
        width: usize,
        height: usize,
        params: Vec<Vec<f32>>,
        normalize: bool,
    ) -> Result<Marginal2D, String> {
        if width < 2 || height < 2 {
            return Err(format!("a {width} × {height} grid is too small to interpolate (at least 2 × 2)"));
        }
        if params.len() > MAX_PARAMS {
            return Err(format!("{} parameters (at most {MAX_PARAMS})", params.len()));
        }
        let mut strides = vec![0; params.len()];
        let mut slices = 1usize;
        for (i, p) in params.iter().enumerate().rev() {
            if p.is_empty() || p.iter().any(|v| !v.is_finite()) || p.windows(2).any(|w| w[0] >= w[1]) {
                return Err(format!("parameter {i} is not tabulated at finite, increasing values: {p:?}"));
            }
            strides[i] = slices;
            slices = slices.checked_mul(p.len()).ok_or("too many slices")?;
        }
        let n = width * height;
        if Some(data.len()) != slices.checked_mul(n) {
            return Err(format!("{} values for {slices} slices of {width} × {height}", data.len()));
        }
        if let Some(v) = data.iter().find(|v| !v.is_finite()) {
            return Err(format!("a value is {v} (values must be finite)"));
        }
        let clamped: Vec<f32>;
        let data = if normalize && data.iter().any(|&v| v < 0.0) {
            clamped = data.iter().map(|&v| v.max(0.0)).collect();
            &clamped[..]
        } else {
            data
        };
        let (sx, sy) = (0.5 / (width - 1) as f64, 0.5 / (height - 1) as f64);
        let mut out = Marginal2D {
            width,
            height,
            params,
            strides,
            data: Vec::with_capacity(data.len()),
            marginal: Vec::with_capacity(slices * (height - 1)),
            conditional: Vec::with_capacity(slices * height * (width - 1)),
            normalized: normalize,
        };
        let mut row_sums = vec![0.0f64; height];
        for (s, slice) in data.chunks_exact(n).enumerate() {
            let (cond_start, marg_start) = (out.conditional.len(), out.marginal.len());
            for (y, row) in slice.chunks_exact(width).enumerate() {
                let mut acc = 0.0f64;
                for x in 0..width - 1 {
                    acc += sx * (row[x] as f64 + row[x + 1] as f64);
                    out.conditional.push(acc as f32);
                }
                row_sums[y] = acc;
            }
            let mut acc = 0.0f64;
            for y in 0..height - 1 {
                acc += sy * (row_sums[y] + row_sums[y + 1]);
                out.marginal.push(acc as f32);
            }
            let norm = if normalize {
                if acc <= 0.0 {
                    return Err(format!("slice {s} is zero everywhere and cannot be normalized"));
                }
                (1.0 / acc) as f32
            } else {
                1.0
            };
            out.conditional[cond_start..].iter_mut().for_each(|c| *c *= norm);
            out.marginal[marg_start..].iter_mut().for_each(|c| *c *= norm);
            out.data.extend(slice.iter().map(|v| v * norm));
        }
        Ok(out)
    }

    /// Grid resolution `(width, height)`.
    pub fn resolution(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The slices `param` falls between and their weights: per parameter, the interval of its
    /// table holding the value (clamped to the table) and linear weights (clamped to [0, 1]).
    fn corners(&self, param: &[f32]) -> Corners {
        debug_assert_eq!(param.len(), self.params.len(), "one value per parameter");
        let mut c = Corners { slice: [0; 1 << MAX_PARAMS], weight: [0.0; 1 << MAX_PARAMS], count: 1 };
        c.weight[0] = 1.0;
        for (d, values) in self.params.iter().enumerate() {
            if values.len() == 1 {
                continue;
            }
            let x = param[d];
            // The interval [values[i], values[i + 1]] holding x, clamped to the table.
            let i = values[1..values.len() - 1].partition_point(|&v| v < x);
            let (p0, p1) = (values[i], values[i + 1]);
            let w1 = ((x - p0) / (p1 - p0)).clamp(0.0, 1.0);
            let w1 = if w1.is_nan() { 0.0 } else { w1 };
            for k in 0..c.count {
                c.slice[k + c.count] = c.slice[k] + (i + 1) * self.strides[d];
                c.weight[k + c.count] = c.weight[k] * w1;
                c.slice[k] += i * self.strides[d];
                c.weight[k] *= 1.0 - w1;
            }
            c.count *= 2;
        }
        c
    }

    /// The four grid values around the patch at column `col`, row `row`: `(v₀₀, v₁₀, v₀₁, v₁₁)`.
    #[inline]
    fn patch(&self, c: &Corners, col: usize, row: usize) -> [f32; 4] {
        let (n, i) = (self.width * self.height, row * self.width + col);
        [
            c.lookup(&self.data, n, i),
            c.lookup(&self.data, n, i + 1),
            c.lookup(&self.data, n, i + self.width),
            c.lookup(&self.data, n, i + self.width + 1),
        ]
    }

    /// Maps `u ∈ [0,1]²` to a point of `[0,1]²` distributed as the density (at `param`), and
    /// that density there. Needs a normalized distribution for the density to be a pdf.
    pub fn sample(&self, u: Vec2, param: &[f32]) -> (Vec2, f32) {
        let c = self.corners(param);
        let (w, h) = (self.width, self.height);
        let (n_marg, n_cond) = (h - 1, h * (w - 1));
        let u = u.clamp(Vec2::splat(f32::EPSILON * 0.5), Vec2::splat(1.0 - f32::EPSILON * 0.5));
        let (mut ux, mut uy) = (u.x, u.y);
        let marginal = |i: usize| c.lookup(&self.marginal, n_marg, i);
        if !self.normalized {
            uy *= marginal(n_marg - 1);
        }
        let row = first_false(0, n_marg - 1, |i| marginal(i) < uy);
        if row > 0 {
            uy -= marginal(row - 1);
        }
        let oc = row * (w - 1);
        let cond = |i: usize| c.lookup(&self.conditional, n_cond, i);
        let (r0, r1) = (cond(oc + w - 2), cond(oc + 2 * (w - 1) - 1));
        let ty = sample_segment(uy, (h - 1) as f32, r0, r1);
        ux *= lerp(r0, r1, ty);
        let cond_at = |i: usize| lerp(cond(oc + i), cond(oc + w - 1 + i), ty);
        let col = first_false(0, w - 2, |i| cond_at(i) < ux);
        if col > 0 {
            ux -= cond_at(col - 1);
        }
        let [v00, v10, v01, v11] = self.patch(&c, col, row);
        let (c0, c1) = (lerp(v00, v01, ty), lerp(v10, v11, ty));
        let tx = sample_segment(ux, (w - 1) as f32, c0, c1);
        let p = Vec2::new((col as f32 + tx) / (w - 1) as f32, (row as f32 + ty) / (h - 1) as f32);
        (p, lerp(c0, c1, tx))
    }

    /// The inverse of [`Marginal2D::sample`]: the `u` that maps to `p`, and the density at `p`.
    pub fn invert(&self, p: Vec2, param: &[f32]) -> (Vec2, f32) {
        let c = self.corners(param);
        let (w, h) = (self.width, self.height);
        let (n_marg, n_cond) = (h - 1, h * (w - 1));
        let (col, row, tx, ty) = self.locate(p);
        let [v00, v10, v01, v11] = self.patch(&c, col, row);
        let (c0, c1) = (lerp(v00, v01, ty), lerp(v10, v11, ty));
        let pdf = lerp(c0, c1, tx);
        let mut ux = invert_segment(tx, 1.0 / (w - 1) as f32, c0, c1);
        let oc = row * (w - 1);
        let cond = |i: usize| c.lookup(&self.conditional, n_cond, i);
        if col > 0 {
            ux += lerp(cond(oc + col - 1), cond(oc + w - 1 + col - 1), ty);
        }
        let (r0, r1) = (cond(oc + w - 2), cond(oc + 2 * (w - 1) - 1));
        ux /= lerp(r0, r1, ty);
        let mut uy = invert_segment(ty, 1.0 / (h - 1) as f32, r0, r1);
        let marginal = |i: usize| c.lookup(&self.marginal, n_marg, i);
        if row > 0 {
            uy += marginal(row - 1);
        }
        if !self.normalized {
            uy /= marginal(n_marg - 1);
        }
        (Vec2::new(ux, uy), pdf)
    }

    /// The density (or, unnormalized, the interpolated value) at `p` for `param`.
    pub fn eval(&self, p: Vec2, param: &[f32]) -> f32 {
        let c = self.corners(param);
        let (col, row, tx, ty) = self.locate(p);
        let [v00, v10, v01, v11] = self.patch(&c, col, row);
        lerp(lerp(v00, v10, tx), lerp(v01, v11, tx), ty)
    }

    /// The patch holding `p` (clamped to the square) and `p`'s position inside it.
    #[inline]
    fn locate(&self, p: Vec2) -> (usize, usize, f32, f32) {
        let p = p.clamp(Vec2::ZERO, Vec2::ONE);
        let (sx, sy) = (p.x * (self.width - 1) as f32, p.y * (self.height - 1) as f32);
        let col = (sx as usize).min(self.width - 2);
        let row = (sy as usize).min(self.height - 2);
        (col, row, sx - col as f32, sy - row as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_2d, integrate_pdf_2d, u2, Chi2Config, Rect};

    /// A 5 × 4 grid per slice over two parameters (2 and 3 values): bumps that move with the
    /// parameters, some zero values.
    fn distribution() -> Marginal2D {
        let (w, h) = (5, 4);
        let mut data = Vec::new();
        for a in 0..2 {
            for b in 0..3 {
                for y in 0..h {
                    for x in 0..w {
                        let v =
                            0.2 + ((x * (a + 1) + y * (b + 2)) % 5) as f32 + if x == 2 && y == 1 { 0.0 } else { 0.5 };
                        data.push(if (x + y + a + b) % 7 == 0 { 0.0 } else { v });
                    }
                }
            }
        }
        Marginal2D::new(&data, w, h, vec![vec![0.0, 1.0], vec![-1.0, 0.5, 2.0]], true).unwrap()
    }

    const PARAMS: [[f32; 2]; 4] = [[0.0, -1.0], [0.3, 0.2], [1.0, 1.7], [5.0, -3.0]];

    #[test]
    fn density_integrates_to_one_and_matches_samples() {
        let d = distribution();
        for (k, param) in PARAMS.iter().enumerate() {
            let total = integrate_pdf_2d(&Rect::UNIT, [64, 64], |p| d.eval(*p, param) as f64);
            assert!((total - 1.0).abs() < 1e-4, "{param:?}: ∫ = {total}");
            let out = chi2_2d(
                &Rect::UNIT,
                [17, 13],
                200_000,
                |r| Some(d.sample(u2(r), param).0),
                |p| d.eval(*p, param) as f64,
                &Chi2Config::default().with_seed(k as u64),
            );
            assert!(out.passed(), "{param:?}: {out}");
        }
    }

    #[test]
    fn sample_returns_the_density_and_invert_undoes_it() {
        let d = distribution();
        let mut rng = crate::sampling::Pcg32::new(1, 2);
        for param in PARAMS {
            for _ in 0..2000 {
                let u = u2(&mut rng);
                let (p, pdf) = d.sample(u, &param);
                assert!((pdf - d.eval(p, &param)).abs() <= 1e-4 * pdf.max(1.0), "{pdf} vs {}", d.eval(p, &param));
                let (back, pdf2) = d.invert(p, &param);
                assert!((back - u).abs().max_element() < 2e-4, "{u} → {p} → {back}");
                assert!((pdf2 - pdf).abs() <= 1e-4 * pdf.max(1.0));
            }
        }
    }

    /// Unnormalized, `eval` interpolates the values themselves: at grid points it returns them,
    /// between slices their linear blend.
    #[test]
    fn unnormalized_eval_interpolates_the_values() {
        let data: Vec<f32> = (0..2 * 3 * 2).map(|i| i as f32).collect();
        let d = Marginal2D::new(&data, 3, 2, vec![vec![10.0, 20.0]], false).unwrap();
        assert_eq!(d.eval(Vec2::new(0.5, 1.0), &[10.0]), 4.0);
        assert_eq!(d.eval(Vec2::new(0.25, 0.0), &[15.0]), 0.5 * (0.5 + 6.5));
        assert_eq!(d.eval(Vec2::new(1.0, 0.0), &[99.0]), 8.0);
        // Sampling one unnormalized slice gives the normalized density's samples (between
        // slices the two differ: unnormalized slices mix in proportion to their integrals).
        let (d, n) = (
            Marginal2D::new(&data[6..], 3, 2, vec![], false).unwrap(),
            Marginal2D::new(&data[6..], 3, 2, vec![], true).unwrap(),
        );
        let u = Vec2::new(0.3, 0.8);
        assert!((d.sample(u, &[]).0 - n.sample(u, &[]).0).abs().max_element() < 1e-5);
        assert!(
            (d.invert(Vec2::new(0.2, 0.7), &[]).0 - n.invert(Vec2::new(0.2, 0.7), &[]).0).abs().max_element() < 1e-5
        );
    }

    #[test]
    fn bad_tables_are_errors() {
        assert!(Marginal2D::new(&[1.0; 4], 1, 4, vec![], true).unwrap_err().contains("too small"));
        assert!(Marginal2D::new(&[1.0; 5], 2, 2, vec![], true).unwrap_err().contains("5 values"));
        assert!(Marginal2D::new(&[1.0, f32::NAN, 1.0, 1.0], 2, 2, vec![], true).unwrap_err().contains("finite"));
        // A negative value is a zero of a density, and interpolated as it is otherwise.
        let (a, b) = (Vec2::new(0.2, 0.7), [1.0, 0.0, 1.0, 1.0]);
        let clamped = Marginal2D::new(&[1.0, -1.0, 1.0, 1.0], 2, 2, vec![], true).unwrap();
        assert_eq!(clamped.eval(a, &[]), Marginal2D::new(&b, 2, 2, vec![], true).unwrap().eval(a, &[]));
        assert_eq!(Marginal2D::new(&[1.0, -1.0, 1.0, 1.0], 2, 2, vec![], false).unwrap().eval(Vec2::X, &[]), -1.0);
        assert!(Marginal2D::new(&[0.0; 4], 2, 2, vec![], true).unwrap_err().contains("zero everywhere"));
        assert!(Marginal2D::new(&[1.0; 8], 2, 2, vec![vec![1.0, 1.0]], true).unwrap_err().contains("increasing"));
        assert!(Marginal2D::new(&[0.0; 4], 2, 2, vec![], false).is_ok());
    }
}
