//! Pixel reconstruction filters (Mitsuba's `rfilter`: `box`, `tent`, `gaussian`), applied by
//! Mitsuba 3's weighted splatting ([`crate::film`]): a sample at film position `x` weighs
//! `f(c − x)` in every pixel of centre `c` within the radius, and a pixel's value is
//! `Σ f L / Σ f`.
//!
//! All filters here are separable, `f(x, y) = f₁(x) f₁(y)`, with `f₁` (unnormalized, in pixels):
//! - `box` (radius r, ½ in Mitsuba: the sample counts in its own pixel only; pbrt-v4's
//!   `xradius`): `f₁(x) = 1` for `|x| ≤ r`.
//! - `tent` (radius r, default 1): `f₁(x) = max(0, 1 − |x|/r)`.
//! - `gaussian` (standard deviation σ, default ½; radius r, 4σ in Mitsuba, pbrt-v4's `xradius`
//!   default 1.5): `f₁(x) = max(0, exp(−x²/2σ²) − exp(−r²/2σ²))` (shifted to reach zero at the
//!   radius; Mitsuba's shift is exp(−8)).
//! - `mitchell` (B = C = ⅓) and `catmullrom` (B = 0, C = ½): Mitchell–Netravali cubics on
//!   `|x| < 2` (Mitsuba's `radius`, default 2, can only cut them shorter; neumann's `stretch`
//!   scales the cubic to `|x| < stretch`, pbrt-v4's `mitchell` of radius `stretch`).
//! - `lanczos` (`lobes` n, default 3): `sinc(x) sinc(x/n)` on `|x| < n`; pbrt-v4's `sinc`
//!   window `sinc(x) sinc(x/τ)` on `|x| ≤ r` with any radius r and τ.
//!
//! The last three have negative lobes: samples add negative weights to some pixels, and the
//! ratio `Σ f L / Σ f` still has the right expectation (Mitsuba's handling).

use crate::math::special::exp4;
use crate::math::{ceil, floor, Vec2};
use crate::props::{Obj, Result as PropResult};

/// Largest border (pixels beyond a tile) a filter footprint may need: radii up to
/// `MAX_BORDER + ½` pixels are accepted.
pub const MAX_BORDER: u32 = 16;

/// Largest accepted filter radius (pixels).
pub const MAX_RADIUS: f32 = MAX_BORDER as f32 + 0.5;

/// A reconstruction filter.
#[derive(Clone, Debug, PartialEq)]
pub enum Filter {
    /// A square of half-width `radius` (pixels; ½ is the pixel's own square, [`Filter::BOX`]).
    Box {
        /// Half-width in pixels.
        radius: f32,
    },
    /// Tent of the given radius (pixels).
    Tent {
        /// Radius in pixels.
        radius: f32,
    },
    /// Truncated Gaussian, shifted to reach zero at `radius`.
    Gaussian {
        /// Standard deviation in pixels.
        stddev: f32,
        /// Support half-width (pixels; Mitsuba's is 4σ).
        radius: f32,
        /// `exp(-r² / 2σ²)`, the shift that makes the filter reach 0 at the radius (computed
        /// once: it is the same for every weight).
        floor: f32,
    },
    /// Mitchell–Netravali cubic with parameters `b`, `c` (Mitsuba's `mitchell`: ⅓, ⅓;
    /// `catmullrom`: 0, ½) stretched so that its support `[-2, 2]` spans `[-stretch, stretch]`
    /// pixels (Mitsuba: 2, pbrt-v4: its radius), and cut at `radius` (≤ `stretch`).
    Cubic {
        /// B.
        b: f32,
        /// C.
        c: f32,
        /// Support half-width (pixels).
        radius: f32,
        /// Half-width the cubic's natural support of 2 is stretched to (pixels).
        stretch: f32,
    },
    /// Windowed sinc `sinc(x) sinc(x/τ)` cut at `radius` (Mitsuba's `lanczos` has `τ` =
    /// `radius` = its `lobes`; pbrt-v4's `sinc` any of each).
    Lanczos {
        /// Width of the window's sinc, τ (pixels; the number of lobes when it equals the radius).
        tau: f32,
        /// Support half-width (pixels).
        radius: f32,
    },
}

impl std::fmt::Display for Filter {
    /// The filter as a scene file names it, with its parameters (`gaussian, stddev 0.5`).
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            Filter::Box { radius } if *radius == 0.5 => write!(f, "box"),
            Filter::Box { radius } => write!(f, "box, radius {radius}"),
            Filter::Tent { radius } => write!(f, "tent, radius {radius}"),
            Filter::Gaussian { stddev, radius, .. } if *radius == 4.0 * stddev => {
                write!(f, "gaussian, stddev {stddev}")
            }
            Filter::Gaussian { stddev, radius, .. } => write!(f, "gaussian, stddev {stddev}, radius {radius}"),
            Filter::Cubic { b, c, radius, stretch } if *stretch == 2.0 => {
                write!(f, "cubic, B {b}, C {c}, radius {radius}")
            }
            Filter::Cubic { b, c, radius, stretch } => {
                write!(f, "cubic, B {b}, C {c}, radius {radius}, stretched to {stretch}")
            }
            Filter::Lanczos { tau, radius } if tau == radius => write!(f, "lanczos, lobes {tau}"),
            Filter::Lanczos { tau, radius } => write!(f, "windowed sinc, tau {tau}, radius {radius}"),
        }
    }
}

impl Filter {
    /// The pixel's own square (Mitsuba's `box`): a sample counts in its pixel only.
    pub const BOX: Filter = Filter::Box { radius: 0.5 };

    /// Whether this is [`Filter::BOX`] (the renderers' fast path: no footprint to visit).
    pub fn is_pixel_box(&self) -> bool {
        matches!(self, Filter::Box { radius } if *radius == 0.5)
    }

    /// A box of half-width `radius` (pixels, in `[½, MAX_RADIUS]`: narrower boxes would miss
    /// pixel centres).
    pub fn boxed(radius: f32) -> Option<Filter> {
        (0.5..=MAX_RADIUS).contains(&radius).then_some(Filter::Box { radius })
    }

    /// Mitsuba's `tent` of radius `radius` (pixels, in `(0, MAX_RADIUS]`).
    pub fn tent(radius: f32) -> Option<Filter> {
        (radius > 0.0 && radius <= MAX_RADIUS).then_some(Filter::Tent { radius })
    }

    /// Mitsuba's `gaussian` with standard deviation `stddev` (pixels, `0 < 4σ ≤ MAX_RADIUS`).
    pub fn gaussian(stddev: f32) -> Option<Filter> {
        Filter::gaussian_cut(stddev, 4.0 * stddev)
    }

    /// A Gaussian of standard deviation `stddev` cut at `radius` (pixels, `0 < r ≤ MAX_RADIUS`;
    /// pbrt-v4's `gaussian`).
    pub fn gaussian_cut(stddev: f32, radius: f32) -> Option<Filter> {
        (stddev > 0.0 && radius > 0.0 && radius <= MAX_RADIUS).then(|| {
            let floor = (-1.0 / (2.0 * stddev * stddev) * radius * radius).exp();
            Filter::Gaussian { stddev, radius, floor }
        })
    }

    /// pbrt-v4's `sinc` (windowed sinc, τ `tau`, cut at `radius`; both in pixels, τ > 0,
    /// `0 < r ≤ MAX_RADIUS`). Mitsuba's `lanczos` with `n` lobes is `windowed_sinc(n, n)`.
    pub fn windowed_sinc(tau: f32, radius: f32) -> Option<Filter> {
        (tau > 0.0 && tau.is_finite() && radius > 0.0 && radius <= MAX_RADIUS)
            .then_some(Filter::Lanczos { tau, radius })
    }

    /// Half-width of the filter's support (pixels).
    pub fn radius(&self) -> f32 {
        match self {
            Filter::Box { radius } | Filter::Tent { radius } => *radius,
            Filter::Gaussian { radius, .. } | Filter::Cubic { radius, .. } | Filter::Lanczos { radius, .. } => *radius,
        }
    }

    /// How many pixels beyond its own the footprint of a sample can reach: `⌈r − ½⌉`.
    pub fn border(&self) -> u32 {
        ((self.radius() - 0.5).ceil().max(0.0) as u32).min(MAX_BORDER)
    }

    /// The 1D filter value `f₁(x)` (unnormalized) at offset `x` pixels from a pixel centre.
    #[inline]
    pub fn eval_1d(&self, x: f32) -> f32 {
        match self {
            Filter::Box { radius } => f32::from(x.abs() <= *radius),
            Filter::Tent { radius } => (1.0 - x.abs() / radius).max(0.0),
            Filter::Gaussian { stddev, radius, floor } => gaussian4(*stddev, *radius, *floor, [x; 4])[0],
            Filter::Cubic { b, c, radius, stretch } => {
                if x.abs() >= radius.min(*stretch) {
                    return 0.0;
                }
                let x = x.abs() * (2.0 / stretch);
                let (x2, x3) = (x * x, x * x * x);
                let v = if x < 1.0 {
                    (12.0 - 9.0 * b - 6.0 * c) * x3 + (-18.0 + 12.0 * b + 6.0 * c) * x2 + (6.0 - 2.0 * b)
                } else {
                    (-b - 6.0 * c) * x3 + (6.0 * b + 30.0 * c) * x2 + (-12.0 * b - 48.0 * c) * x + (8.0 * b + 24.0 * c)
                };
                v / 6.0
            }
            Filter::Lanczos { tau, radius } => {
                let x = x.abs();
                if x < 1e-5 {
                    1.0
                } else if x >= *radius {
                    0.0
                } else {
                    let (a, b) = (std::f32::consts::PI * x, std::f32::consts::PI * x / tau);
                    (a.sin() * b.sin()) / (a * b)
                }
            }
        }
    }
}

impl Filter {
    /// `out[k] = f₁(d₀ + k + ½ − offset)` for `k < n` (`n ≤ MAX_ROW`): the 1D filter values at
    /// the centres of consecutive pixels `d₀ + k` seen from a sample at `offset` (pixels). The
    /// entries from `n` to the next multiple of four may be overwritten too.
    #[inline(always)]
    fn row(&self, d0: i64, offset: f32, out: &mut [f32; ROW], n: usize) {
        if let Filter::Gaussian { .. } = self {
            return self.gaussian_row(d0, offset, out, n);
        }
        for (k, w) in out[..n].iter_mut().enumerate() {
            *w = self.eval_1d((d0 + k as i64) as f32 + 0.5 - offset);
        }
    }

    /// [`Filter::row`] of the Gaussian, `max(e^(−x²/2σ²) − e^(−r²/2σ²), 0)` within the radius
    /// and 0 beyond (as [`Filter::eval_1d`], bit for bit): four exponentials at a time
    /// ([`exp4`]; a footprint takes one or two rows of four per axis, where one call of the C
    /// library's `expf` per pixel offset took a tenth of the time of scenes with small bright
    /// lights), stored four at a time (a copy of `n mod 4` values was a call of `memcpy`).
    #[inline(always)]
    fn gaussian_row(&self, d0: i64, offset: f32, out: &mut [f32; ROW], n: usize) {
        let Filter::Gaussian { stddev, radius, floor } = *self else { return };
        for c in 0..n.div_ceil(4) {
            let x: [f32; 4] = std::array::from_fn(|j| (d0 + (4 * c + j) as i64) as f32 + 0.5 - offset);
            out[4 * c..4 * c + 4].copy_from_slice(&gaussian4(stddev, radius, floor, x));
        }
    }

    /// Visits the footprint of a sample at `origin + offset` (pixel units; pixel `k` spans
    /// `[k, k + 1)`): every pixel whose centre lies within the radius, clipped to the inclusive
    /// range `lo ..= hi`, row by row, as `visit(x, y, w)` with the separable weight
    /// `w = f₁(x + ½ − pₓ) f₁(y + ½ − p_y) ≠ 0` (negative for the lobes of `mitchell`,
    /// `catmullrom` and `lanczos`). Weights are computed relative to `origin`, so a
    /// small `offset` keeps them exact at any image size.
    #[inline(always)]
    pub fn footprint(
        &self,
        origin: [i64; 2],
        offset: Vec2,
        lo: [i64; 2],
        hi: [i64; 2],
        mut visit: impl FnMut(i64, i64, f32),
    ) {
        self.footprint_rows(origin, offset, lo, hi, |x0, y, wy, wx| {
            for (i, &wx) in wx.iter().enumerate() {
                let w = wy * wx;
                if w != 0.0 {
                    visit(x0 + i as i64, y, w);
                }
            }
        });
    }

    /// [`Filter::footprint`] a row at a time: `visit_row(x₀, y, f₁(y), f₁(x))` for each row `y`
    /// whose weight is not zero (top to bottom), `f₁(x)` the weights of the pixels `x₀, x₀ + 1,
    /// …` (some may be zero); pixel `(x, y)`'s weight is the product `f₁(y) · f₁(x)` (in `f32`).
    #[inline(always)]
    pub fn footprint_rows(
        &self,
        origin: [i64; 2],
        offset: Vec2,
        lo: [i64; 2],
        hi: [i64; 2],
        mut visit_row: impl FnMut(i64, i64, f32, &[f32]),
    ) {
        let r = self.radius();
        let (d0x, d1x) = ceil_floor(offset.x - r - 0.5, offset.x + r - 0.5);
        let (d0y, d1y) = ceil_floor(offset.y - r - 0.5, offset.y + r - 0.5);
        let (d0x, d1x) = (d0x.max(lo[0] - origin[0]), d1x.min(hi[0] - origin[0]));
        let (d0y, d1y) = (d0y.max(lo[1] - origin[1]), d1y.min(hi[1] - origin[1]));
        let (mut wx, mut wy) = ([0.0f32; ROW], [0.0f32; ROW]);
        let (nx, ny) = ((d1x - d0x + 1).max(0) as usize, (d1y - d0y + 1).max(0) as usize);
        self.row(d0x, offset.x, &mut wx, nx);
        self.row(d0y, offset.y, &mut wy, ny);
        let (x0, y0) = (origin[0] + d0x, origin[1] + d0y);
        for (j, &wy) in wy[..ny].iter().enumerate() {
            if wy != 0.0 {
                visit_row(x0, y0 + j as i64, wy, &wx[..nx]);
            }
        }
    }
}

/// Most pixels a footprint spans along an axis: `2 r + 1` for the largest radius.
const MAX_ROW: usize = 2 * MAX_BORDER as usize + 2;

/// A row buffer's length: [`MAX_ROW`] rounded up to whole groups of four.
const ROW: usize = MAX_ROW.div_ceil(4) * 4;

/// `(⌈a⌉, ⌊b⌋)` as integers, as `ceil(a) as i64` and `floor(b) as i64` give them: where both
/// lie within ±2²² (a footprint's span, always), by truncating conversions corrected by one,
/// without the saturating conversions' checks for NaN and range.
#[inline(always)]
fn ceil_floor(a: f32, b: f32) -> (i64, i64) {
    const EXACT: f32 = 4_194_304.0;
    if a.abs() < EXACT && b.abs() < EXACT {
        // SAFETY: both are finite and well inside i32's range (checked just above; false for NaN).
        let (ta, tb) = unsafe { (a.to_int_unchecked::<i32>(), b.to_int_unchecked::<i32>()) };
        // Truncation rounds toward zero (exactly representable back below 2²⁴): one up where
        // that fell below `a`, one down where it rose above `b`.
        (i64::from(ta + i32::from((ta as f32) < a)), i64::from(tb - i32::from((tb as f32) > b)))
    } else {
        (ceil(a) as i64, floor(b) as i64)
    }
}

/// The Gaussian of standard deviation `stddev` (pixels) cut at `radius` at four offsets `x`:
/// `max(e^(−x²/2σ²) − floor, 0)` within the radius (`floor` the shift that makes it reach 0
/// there, e^(−8) at 4σ), 0 beyond, the exponentials in one SIMD register ([`exp4`]). `s x²` lies
/// in [−8, 0] within Mitsuba's 4σ; a cut Gaussian's radius may be wider, but the weight is 0 to
/// within 10⁻³⁷ where `s x² < −86`, so the argument is clamped there, inside `exp4`'s range.
#[inline]
fn gaussian4(stddev: f32, radius: f32, floor: f32, x: [f32; 4]) -> [f32; 4] {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of every x86-64 CPU (the target's baseline), and the unaligned load
    // and store access the sixteen bytes of a four-f32 array.
    unsafe {
        use std::arch::x86_64::*;
        // The lanes of `gaussian4_lanes`, operation for operation: |x| by clearing the sign,
        // `<=` false for NaN as in the scalar test, `maxps` returning its second operand (the
        // clamp) for a NaN first one as `f32::max` does.
        let s = -1.0 / (2.0 * stddev * stddev);
        let xv = _mm_loadu_ps(x.as_ptr());
        let inside = _mm_cmple_ps(_mm_andnot_ps(_mm_set1_ps(-0.0), xv), _mm_set1_ps(radius));
        let arg = _mm_max_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(s), xv), xv), _mm_set1_ps(-86.0));
        let e = crate::math::special::exp4_sse(_mm_and_ps(inside, arg));
        let w = _mm_and_ps(inside, _mm_max_ps(_mm_sub_ps(e, _mm_set1_ps(floor)), _mm_setzero_ps()));
        let mut out = [0.0f32; 4];
        _mm_storeu_ps(out.as_mut_ptr(), w);
        out
    }
    #[cfg(not(target_arch = "x86_64"))]
    gaussian4_lanes(stddev, radius, floor, x)
}

/// [`gaussian4`] lane by lane (the portable version, and the SSE one's reference).
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline]
fn gaussian4_lanes(stddev: f32, radius: f32, floor: f32, x: [f32; 4]) -> [f32; 4] {
    let s = -1.0 / (2.0 * stddev * stddev);
    let e = exp4(x.map(|x| if x.abs() <= radius { (s * x * x).max(-86.0) } else { 0.0 }));
    std::array::from_fn(|j| if x[j].abs() <= radius { (e[j] - floor).max(0.0) } else { 0.0 })
}

/// Every reconstruction-filter plugin by its (Mitsuba) name.
pub const FILTER_PLUGINS: &[&str] = &["box", "tent", "gaussian", "mitchell", "catmullrom", "lanczos", "sinc"];

impl Filter {
    /// Mitsuba's `rfilter` plugins: `box`, `tent` (`radius` 1), `gaussian` (`stddev` 0.5),
    /// `mitchell` (`B` ⅓, `C` ⅓, `radius` 2), `catmullrom` (`radius` 2), `lanczos` (`lobes` 3);
    /// with neumann's parameters for pbrt-v4's filters: `box` `radius` (0.5), `gaussian`
    /// `radius` (4σ), `mitchell`/`catmullrom` `stretch` (2), and the `sinc` plugin (`radius` 4,
    /// `tau` 3, pbrt-v4's defaults).
    pub fn from_props(r: &Obj) -> PropResult<Filter> {
        r.built.set(true);
        let too_wide = "radius must be positive and at most 16.5 pixels";
        match r.ty.as_str() {
            "box" => Filter::boxed(r.float("radius", 0.5)?)
                .ok_or_else(|| r.error_at("radius", "a box's radius must be at least 0.5 and at most 16.5 pixels")),
            "tent" => {
                let radius = r.float("radius", 1.0)?;
                Filter::tent(radius)
                    .ok_or_else(|| r.error_at("radius", "radius must be positive and at most 16.5 pixels"))
            }
            "gaussian" => {
                let s = r.float("stddev", 0.5)?;
                if s.is_nan() || s <= 0.0 {
                    return Err(r.error_at("stddev", format!("stddev must be positive, got {s}")));
                }
                Filter::gaussian_cut(s, r.float("radius", 4.0 * s)?).ok_or_else(|| r.error_at("radius", too_wide))
            }
            "mitchell" | "catmullrom" => {
                let (b, c) =
                    if r.ty == "mitchell" { (r.float("B", 1.0 / 3.0)?, r.float("C", 1.0 / 3.0)?) } else { (0.0, 0.5) };
                let stretch = r.float("stretch", 2.0)?;
                if !(stretch > 0.0 && stretch <= MAX_RADIUS) {
                    return Err(r.error_at("stretch", "stretch must be positive and at most 16.5 pixels"));
                }
                let radius = r.float("radius", stretch)?;
                if !(radius > 0.0 && radius <= MAX_RADIUS) {
                    return Err(r.error_at("radius", too_wide));
                }
                Ok(Filter::Cubic { b, c, radius, stretch })
            }
            "lanczos" => {
                let lobes = r.int("lobes", 3)?;
                if !(1..=16).contains(&lobes) {
                    return Err(r.error_at("lobes", format!("lobes must be between 1 and 16, got {lobes}")));
                }
                Ok(Filter::Lanczos { tau: lobes as f32, radius: lobes as f32 })
            }
            "sinc" => {
                let tau = r.float("tau", 3.0)?;
                if !(tau > 0.0 && tau.is_finite()) {
                    return Err(r.error_at("tau", format!("tau must be positive, got {tau}")));
                }
                Filter::windowed_sinc(tau, r.float("radius", 4.0)?).ok_or_else(|| r.error_at("radius", too_wide))
            }
            _ => Err(r.unknown_plugin(FILTER_PLUGINS)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The footprint's integer span is the library's ceiling and floor, converted: at
    /// integers, halves, ±0, either side of the fast path's limit, NaN and ±∞.
    #[test]
    fn ceil_floor_is_the_libraries() {
        let mut rng = crate::sampling::Pcg32::new(3, 9);
        let mut values = vec![0.0f32, -0.0, 0.5, -0.5, 1.0, -1.0, 2.5, -2.5, 1e-30, -1e-30, f32::NAN, f32::INFINITY];
        values.extend([f32::NEG_INFINITY, 4_194_304.0, -4_194_304.0, 4_194_303.5, -4_194_303.5, 1e12, -1e12]);
        values.extend([(1.0f32).next_up(), (1.0f32).next_down(), (-1.0f32).next_up(), (-1.0f32).next_down()]);
        values.extend((0..2000).map(|_| (rng.next_f32() - 0.5) * 40.0));
        values.extend((0..200).map(|k| k as f32 / 4.0 - 25.0));
        for &a in &values {
            for b in [a, -a, 0.3] {
                assert_eq!(ceil_floor(a, b), (a.ceil() as i64, b.floor() as i64), "{a} {b}");
            }
        }
    }

    /// The SSE Gaussian gives the bits of the lane-by-lane one: inside, outside and exactly at
    /// the radius, at ±0, and for NaN and infinite offsets.
    #[test]
    fn gaussian_lanes_are_the_scalar_formula() {
        let mut rng = crate::sampling::Pcg32::new(5, 2);
        for (stddev, radius) in [(0.5f32, 2.0f32), (0.3, 1.2), (1.5, 6.0), (0.5, 16.5), (0.01, 16.5)] {
            let Filter::Gaussian { floor, .. } = Filter::gaussian_cut(stddev, radius).unwrap() else { unreachable!() };
            let edges = [0.0, -0.0, radius, -radius, radius.next_up(), f32::NAN, f32::INFINITY, 1e30];
            for k in 0..4000 {
                let x: [f32; 4] = std::array::from_fn(|j| match k {
                    0..=1 => edges[4 * k + j],
                    _ => (rng.next_f32() - 0.5) * 2.4 * radius,
                });
                let (a, b) = (gaussian4(stddev, radius, floor, x), gaussian4_lanes(stddev, radius, floor, x));
                assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "σ {stddev}, r {radius}, x {x:?}");
            }
        }
    }

    /// The Gaussian's rows (four exponentials at a time) are `eval_1d` at each pixel, bit for
    /// bit, and within 2·10⁻⁷ of the formula in `f64`, over sub-pixel offsets and radii.
    #[test]
    fn gaussian_rows_are_eval_1d() {
        for (stddev, radius) in [(0.5f32, 2.0f32), (0.3, 1.2), (1.5, 6.0), (0.5, 16.5)] {
            let g = Filter::gaussian_cut(stddev, radius).unwrap();
            for i in 0..50 {
                let offset = i as f32 / 50.0;
                let d0 = -(radius.ceil() as i64) - 1;
                let mut row = [0.0f32; ROW];
                g.row(d0, offset, &mut row, MAX_ROW);
                for (k, &w) in row[..MAX_ROW].iter().enumerate() {
                    let x = (d0 + k as i64) as f32 + 0.5 - offset;
                    assert_eq!(w.to_bits(), g.eval_1d(x).to_bits(), "σ {stddev}, x {x}");
                    let s = -1.0 / (2.0 * stddev as f64 * stddev as f64);
                    let exact = if x.abs() <= radius {
                        ((s * x as f64 * x as f64).exp() - (s * radius as f64 * radius as f64).exp()).max(0.0)
                    } else {
                        0.0
                    };
                    assert!((w as f64 - exact).abs() < 2e-7, "σ {stddev}, x {x}: {w} vs {exact}");
                }
            }
        }
    }

    #[test]
    fn shapes_radii_and_borders() {
        let g = Filter::gaussian(0.5).unwrap();
        assert_eq!(g.radius(), 2.0);
        assert_eq!(g.border(), 2);
        assert_eq!(Filter::BOX.border(), 0);
        assert_eq!(Filter::tent(1.0).unwrap().border(), 1);
        assert_eq!(Filter::tent(1.6).unwrap().border(), 2);
        assert!((g.eval_1d(0.0) - (1.0 - (-8.0f32).exp())).abs() < 1e-6);
        assert_eq!(g.eval_1d(2.0), 0.0);
        assert_eq!(g.eval_1d(2.5), 0.0);
        assert!(g.eval_1d(1.0) > 0.0 && g.eval_1d(1.0) < g.eval_1d(0.5));
        assert_eq!(Filter::tent(2.0).unwrap().eval_1d(1.0), 0.5);
        assert!(Filter::tent(0.0).is_none() && Filter::gaussian(-1.0).is_none());
        assert!(Filter::tent(f32::NAN).is_none() && Filter::tent(100.0).is_none() && Filter::gaussian(5.0).is_none());
    }

    /// Mitchell–Netravali and Lanczos as Mitsuba defines them: values at the knots, negative
    /// lobes, zero at the support's edge, and the footprint keeps the negative weights.
    #[test]
    fn cubic_and_lanczos_filters() {
        let m = Filter::Cubic { b: 1.0 / 3.0, c: 1.0 / 3.0, radius: 2.0, stretch: 2.0 };
        assert!((m.eval_1d(0.0) - (6.0 - 2.0 / 3.0) / 6.0).abs() < 1e-6);
        assert!((m.eval_1d(1.0) - 1.0 / 18.0).abs() < 1e-6, "{}", m.eval_1d(1.0));
        assert!(m.eval_1d(1.5) < 0.0 && m.eval_1d(2.0) == 0.0 && m.radius() == 2.0);
        let l = Filter::windowed_sinc(3.0, 3.0).unwrap();
        assert_eq!(l.eval_1d(0.0), 1.0);
        assert!(l.eval_1d(1.0).abs() < 1e-6 && l.eval_1d(1.5) < 0.0 && l.eval_1d(3.0) == 0.0);
        let mut negative = 0;
        l.footprint([10, 10], Vec2::new(0.3, 0.6), [0, 0], [20, 20], |_, _, w| negative += usize::from(w < 0.0));
        assert!(negative > 0, "negative lobes reach the film");
    }

    /// pbrt-v4's filters: a box of any radius, a Gaussian cut at its radius (not 4σ), the
    /// Mitchell cubic stretched to its radius, and a windowed sinc whose radius is not its τ.
    #[test]
    fn pbrt_filter_shapes() {
        let b = Filter::boxed(1.5).unwrap();
        assert_eq!((b.eval_1d(1.5), b.eval_1d(1.51), b.border()), (1.0, 0.0, 1));
        let mut n = 0;
        b.footprint([10, 10], Vec2::new(0.5, 0.5), [0, 0], [20, 20], |_, _, w| n += usize::from(w == 1.0));
        assert_eq!(n, 9, "a 3-pixel box from the pixel centre covers 3×3 pixels");
        assert!(Filter::boxed(0.4).is_none());
        let g = Filter::gaussian_cut(0.5, 1.5).unwrap();
        assert!((g.eval_1d(0.0) - (1.0 - (-4.5f32).exp())).abs() < 1e-6 && g.eval_1d(1.5) == 0.0 && g.radius() == 1.5);
        let mitsuba = Filter::Cubic { b: 1.0 / 3.0, c: 1.0 / 3.0, radius: 2.0, stretch: 2.0 };
        let pbrt = Filter::Cubic { b: 1.0 / 3.0, c: 1.0 / 3.0, radius: 1.0, stretch: 1.0 };
        for x in [0.0, 0.2, 0.45, 0.7, 0.99] {
            assert!((pbrt.eval_1d(x) - mitsuba.eval_1d(2.0 * x)).abs() < 1e-6, "{x}");
        }
        assert_eq!(pbrt.eval_1d(1.0), 0.0);
        let s = Filter::windowed_sinc(3.0, 4.0).unwrap();
        let sinc = |x: f32| (std::f32::consts::PI * x).sin() / (std::f32::consts::PI * x);
        assert!((s.eval_1d(3.5) - sinc(3.5) * sinc(3.5 / 3.0)).abs() < 1e-6 && s.eval_1d(3.5) != 0.0);
        assert_eq!((s.eval_1d(4.0), s.radius(), s.border()), (0.0, 4.0, 4));
    }
}
