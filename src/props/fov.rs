//! Fields of view as Mitsuba's sensors and projectors read them: `fov` along `fov_axis`, or a
//! `focal_length` on a 36 × 24 mm frame.

use super::{Obj, Result, SceneError, Value};
use crate::math::Vec2;

/// Which image axis the field of view spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    /// Horizontal.
    X,
    /// Vertical.
    Y,
    /// The shorter image side.
    Smaller,
    /// The longer image side.
    Larger,
    /// The diagonal.
    Diagonal,
}

crate::choices!(FovAxis, "fov_axis", {
    FovAxis::X => "x", "the image's width";
    FovAxis::Y => "y", "the image's height";
    FovAxis::Diagonal => "diagonal", "the image's diagonal";
    FovAxis::Smaller => "smaller", "the shorter image side";
    FovAxis::Larger => "larger", "the longer image side";
});

/// `fov` (degrees) + `fov_axis` (`x` by default), or `focal_length` (a string like `"50mm"`, the
/// default: the diagonal field of view of a 36 × 24 mm frame); not both.
pub fn fov_from_props(o: &Obj) -> Result<(f32, FovAxis)> {
    match (o.float_opt("fov")?, o.get("focal_length")) {
        (Some(_), Some(p)) => Err(SceneError::at(&p.loc, "give either 'fov' or 'focal_length', not both")),
        (Some(fov), None) => {
            let names = <FovAxis as crate::choice::Choice>::names();
            let axis = o.choice("fov_axis", &names)?.parse().map_err(|e: String| o.error_at("fov_axis", e))?;
            Ok((fov, axis))
        }
        (None, p) => {
            let mm = match p.map(|p| &p.value) {
                None => 50.0,
                Some(Value::String(s)) => {
                    s.trim().trim_end_matches("mm").trim().parse::<f32>().ok().filter(|f| *f > 0.0).ok_or_else(|| {
                        o.error_at("focal_length", format!("focal_length must be like \"50mm\", got {s:?}"))
                    })?
                }
                Some(Value::Float(f)) if *f > 0.0 => *f as f32,
                Some(_) => return Err(o.error_at("focal_length", "focal_length must be a string like \"50mm\"")),
            };
            Ok((2.0 * ((36.0f32.hypot(24.0)) / (2.0 * mm)).atan().to_degrees(), FovAxis::Diagonal))
        }
    }
}

/// Tangents of the half fields of view along x and y (the image plane at unit distance spans
/// `[-tan_x, tan_x] × [-tan_y, tan_y]`) for a full field of view `fov_deg` along `axis` and an
/// image of aspect ratio `aspect` (width / height).
pub fn tan_half(fov_deg: f32, axis: FovAxis, aspect: f32) -> Vec2 {
    let t = (0.5 * fov_deg.to_radians()).tan();
    match axis {
        FovAxis::X => Vec2::new(t, t / aspect),
        FovAxis::Y => Vec2::new(t * aspect, t),
        FovAxis::Smaller if aspect >= 1.0 => Vec2::new(t * aspect, t),
        FovAxis::Smaller => Vec2::new(t, t / aspect),
        FovAxis::Larger if aspect >= 1.0 => Vec2::new(t, t / aspect),
        FovAxis::Larger => Vec2::new(t * aspect, t),
        FovAxis::Diagonal => {
            let diag = (aspect * aspect + 1.0).sqrt();
            Vec2::new(t * aspect / diag, t / diag)
        }
    }
}
