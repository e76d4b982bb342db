//! Pixel reconstruction filters (Mitsuba's `rfilter`: `box`, `tent`, `gaussian`), applied by
//! Mitsuba 3's weighted splatting ([`crate::film`]): a sample at film position `x` weighs
//! `f(c − x)` in every pixel of centre `c` within the radius, and a pixel's value is
//! `Σ f L / Σ f`.
//!
//! All filters here are separable, `f(x, y) = f₁(x) f₁(y)`, with `f₁` (unnormalized, in pixels):
//! - `box` (radius ½): `f₁(x) = 1` for `|x| ≤ ½`; the sample counts in its own pixel only.
//! - `tent` (radius r, default 1): `f₁(x) = max(0, 1 − |x|/r)`.
//! - `gaussian` (standard deviation σ, default ½; radius 4σ as in Mitsuba):
//!   `f₁(x) = max(0, exp(−x²/2σ²) − exp(−8))` (shifted to reach zero at the radius).
//! - `mitchell` (B = C = ⅓) and `catmullrom` (B = 0, C = ½): Mitchell–Netravali cubics on
//!   `|x| < 2` (Mitsuba's `radius`, default 2, can only cut them shorter).
//! - `lanczos` (`lobes` n, default 3): `sinc(x) sinc(x/n)` on `|x| < n`.
//!
//! The last three have negative lobes: samples add negative weights to some pixels, and the
//! ratio `Σ f L / Σ f` still has the right expectation (Mitsuba's handling).

use crate::math::Vec2;
use crate::props::{Obj, Result as PropResult};

/// Largest border (pixels beyond a tile) a filter footprint may need: radii up to
/// `MAX_BORDER + ½` pixels are accepted.
pub const MAX_BORDER: u32 = 16;

/// Largest accepted filter radius (pixels).
pub const MAX_RADIUS: f32 = MAX_BORDER as f32 + 0.5;

/// A reconstruction filter.
#[derive(Clone, Debug, PartialEq)]
pub enum Filter {
    /// The pixel's square.
    Box,
    /// Tent of the given radius (pixels).
    Tent {
        /// Radius in pixels.
        radius: f32,
    },
    /// Truncated, shifted Gaussian.
    Gaussian {
        /// Standard deviation in pixels.
        stddev: f32,
    },
    /// Mitchell–Netravali cubic with parameters `b`, `c` (Mitsuba's `mitchell`: ⅓, ⅓;
    /// `catmullrom`: 0, ½), cut at `radius` (≤ 2).
    Cubic {
        /// B.
        b: f32,
        /// C.
        c: f32,
        /// Support half-width (pixels).
        radius: f32,
    },
    /// Windowed sinc with `lobes` lobes (Mitsuba's `lanczos`).
    Lanczos {
        /// Number of lobes (the radius, in pixels).
        lobes: f32,
    },
}

impl std::fmt::Display for Filter {
    /// The filter as a scene file names it, with its parameters (`gaussian, stddev 0.5`).
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            Filter::Box => write!(f, "box"),
            Filter::Tent { radius } => write!(f, "tent, radius {radius}"),
            Filter::Gaussian { stddev } => write!(f, "gaussian, stddev {stddev}"),
            Filter::Cubic { b, c, radius } => write!(f, "cubic, B {b}, C {c}, radius {radius}"),
            Filter::Lanczos { lobes } => write!(f, "lanczos, lobes {lobes}"),
        }
    }
}

impl Filter {
    /// Mitsuba's `tent` of radius `radius` (pixels, in `(0, MAX_RADIUS]`).
    pub fn tent(radius: f32) -> Option<Filter> {
        (radius > 0.0 && radius <= MAX_RADIUS).then_some(Filter::Tent { radius })
    }

    /// Mitsuba's `gaussian` with standard deviation `stddev` (pixels, `0 < 4σ ≤ MAX_RADIUS`).
    pub fn gaussian(stddev: f32) -> Option<Filter> {
        (stddev > 0.0 && 4.0 * stddev <= MAX_RADIUS).then_some(Filter::Gaussian { stddev })
    }

    /// Half-width of the filter's support (pixels).
    pub fn radius(&self) -> f32 {
        match self {
            Filter::Box => 0.5,
            Filter::Tent { radius } => *radius,
            Filter::Gaussian { stddev } => 4.0 * stddev,
            Filter::Cubic { radius, .. } => *radius,
            Filter::Lanczos { lobes } => *lobes,
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
            Filter::Box => f32::from(x.abs() <= 0.5),
            Filter::Tent { radius } => (1.0 - x.abs() / radius).max(0.0),
            Filter::Gaussian { stddev } => {
                if x.abs() <= 4.0 * stddev {
                    // exp(-(4σ)² / 2σ²) = exp(-8): the shift that makes f reach 0 at the radius.
                    ((-x * x / (2.0 * stddev * stddev)).exp() - (-8.0f32).exp()).max(0.0)
                } else {
                    0.0
                }
            }
            Filter::Cubic { b, c, radius } => {
                let x = x.abs();
                if x >= radius.min(2.0) {
                    return 0.0;
                }
                let (x2, x3) = (x * x, x * x * x);
                let v = if x < 1.0 {
                    (12.0 - 9.0 * b - 6.0 * c) * x3 + (-18.0 + 12.0 * b + 6.0 * c) * x2 + (6.0 - 2.0 * b)
                } else {
                    (-b - 6.0 * c) * x3 + (6.0 * b + 30.0 * c) * x2 + (-12.0 * b - 48.0 * c) * x + (8.0 * b + 24.0 * c)
                };
                v / 6.0
            }
            Filter::Lanczos { lobes } => {
                let x = x.abs();
                if x < 1e-5 {
                    1.0
                } else if x >= *lobes {
                    0.0
                } else {
                    let (a, b) = (std::f32::consts::PI * x, std::f32::consts::PI * x / lobes);
                    (a.sin() * b.sin()) / (a * b)
                }
            }
        }
    }
}

impl Filter {
    /// Visits the footprint of a sample at `origin + offset` (pixel units; pixel `k` spans
    /// `[k, k + 1)`): every pixel whose centre lies within the radius, clipped to the inclusive
    /// range `lo ..= hi`, row by row, as `visit(x, y, w)` with the separable weight
    /// `w = f₁(x + ½ − pₓ) f₁(y + ½ − p_y) ≠ 0` (negative for the lobes of `mitchell`,
    /// `catmullrom` and `lanczos`). Weights are computed relative to `origin`, so a
    /// small `offset` keeps them exact at any image size.
    #[inline]
    pub fn footprint(
        &self,
        origin: [i64; 2],
        offset: Vec2,
        lo: [i64; 2],
        hi: [i64; 2],
        mut visit: impl FnMut(i64, i64, f32),
    ) {
        let r = self.radius();
        let d0x = ((offset.x - r - 0.5).ceil() as i64).max(lo[0] - origin[0]);
        let d1x = ((offset.x + r - 0.5).floor() as i64).min(hi[0] - origin[0]);
        let d0y = ((offset.y - r - 0.5).ceil() as i64).max(lo[1] - origin[1]);
        let d1y = ((offset.y + r - 0.5).floor() as i64).min(hi[1] - origin[1]);
        const MAX: usize = 2 * MAX_BORDER as usize + 2;
        let mut wx = [0.0f32; MAX];
        for d in d0x..=d1x {
            wx[(d - d0x) as usize] = self.eval_1d(d as f32 + 0.5 - offset.x);
        }
        for dy in d0y..=d1y {
            let wy = self.eval_1d(dy as f32 + 0.5 - offset.y);
            if wy == 0.0 {
                continue;
            }
            for dx in d0x..=d1x {
                let w = wy * wx[(dx - d0x) as usize];
                if w != 0.0 {
                    visit(origin[0] + dx, origin[1] + dy, w);
                }
            }
        }
    }
}

/// Every reconstruction-filter plugin by its (Mitsuba) name.
pub const FILTER_PLUGINS: &[&str] = &["box", "tent", "gaussian", "mitchell", "catmullrom", "lanczos"];

impl Filter {
    /// Mitsuba's `rfilter` plugins: `box`, `tent` (`radius` 1), `gaussian` (`stddev` 0.5),
    /// `mitchell` (`B` ⅓, `C` ⅓, `radius` 2), `catmullrom` (`radius` 2), `lanczos` (`lobes` 3).
    pub fn from_props(r: &Obj) -> PropResult<Filter> {
        r.built.set(true);
        match r.ty.as_str() {
            "box" => Ok(Filter::Box),
            "tent" => {
                let radius = r.float("radius", 1.0)?;
                Filter::tent(radius)
                    .ok_or_else(|| r.error_at("radius", "radius must be positive and at most 16.5 pixels"))
            }
            "gaussian" => {
                let s = r.float("stddev", 0.5)?;
                Filter::gaussian(s).ok_or_else(|| {
                    r.error_at("stddev", "stddev must be positive and at most 4.125 pixels (radius 4 stddev)")
                })
            }
            "mitchell" | "catmullrom" => {
                let (b, c) = if r.ty == "mitchell" { (r.float("B", 1.0 / 3.0)?, r.float("C", 1.0 / 3.0)?) } else { (0.0, 0.5) };
                let radius = r.float("radius", 2.0)?;
                if !(radius > 0.0 && radius <= MAX_RADIUS) {
                    return Err(r.error_at("radius", "radius must be positive and at most 16.5 pixels"));
                }
                Ok(Filter::Cubic { b, c, radius })
            }
            "lanczos" => {
                let lobes = r.int("lobes", 3)?;
                if !(1..=16).contains(&lobes) {
                    return Err(r.error_at("lobes", format!("lobes must be between 1 and 16, got {lobes}")));
                }
                Ok(Filter::Lanczos { lobes: lobes as f32 })
            }
            _ => Err(r.unknown_plugin(FILTER_PLUGINS)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_radii_and_borders() {
        let g = Filter::gaussian(0.5).unwrap();
        assert_eq!(g.radius(), 2.0);
        assert_eq!(g.border(), 2);
        assert_eq!(Filter::Box.border(), 0);
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
        let m = Filter::Cubic { b: 1.0 / 3.0, c: 1.0 / 3.0, radius: 2.0 };
        assert!((m.eval_1d(0.0) - (6.0 - 2.0 / 3.0) / 6.0).abs() < 1e-6);
        assert!((m.eval_1d(1.0) - 1.0 / 18.0).abs() < 1e-6, "{}", m.eval_1d(1.0));
        assert!(m.eval_1d(1.5) < 0.0 && m.eval_1d(2.0) == 0.0 && m.radius() == 2.0);
        let l = Filter::Lanczos { lobes: 3.0 };
        assert_eq!(l.eval_1d(0.0), 1.0);
        assert!(l.eval_1d(1.0).abs() < 1e-6 && l.eval_1d(1.5) < 0.0 && l.eval_1d(3.0) == 0.0);
        let mut negative = 0;
        l.footprint([10, 10], Vec2::new(0.3, 0.6), [0, 0], [20, 20], |_, _, w| negative += usize::from(w < 0.0));
        assert!(negative > 0, "negative lobes reach the film");
    }
}
