//! Math layer: vectors, frames, transforms, bounds, rays and floating-point error bounds.
//!
//! Vectors, points and normals are all `glam::Vec3` (single precision, the renderer's working
//! precision). Which one a value is shows in the *name* of the function that handles it:
//! [`Transform::apply_point`] translates, [`Transform::apply_vector`] does not and
//! [`Transform::apply_normal`] uses the inverse transpose. World space is right-handed; the
//! local shading frame ([`Frame`]) has its normal on +z.

pub mod animated;
pub mod bounds;
pub mod color;
pub mod cone;
pub mod float;
pub mod frame;
pub mod lanes;
pub mod quadrature;
pub mod ray;
pub mod simd;
pub mod special;
pub mod spline;
pub mod spectrum;
pub mod transform;
pub mod trig;

pub use animated::AnimatedTransform;
pub use bounds::Bounds3;
pub use color::{luminance, Rgb};
pub use cone::DirectionCone;
pub use frame::Frame;
pub use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
pub use ray::Ray;
pub use transform::Transform;
pub use trig::{sin_cos_2pi, sin_cos_quarter};

/// π as `f32`.
pub const PI: f32 = std::f32::consts::PI;
/// 1/π.
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
/// 1/(2π).
pub const INV_2PI: f32 = 0.5 * std::f32::consts::FRAC_1_PI;
/// 1/(4π).
pub const INV_4PI: f32 = 0.25 * std::f32::consts::FRAC_1_PI;

/// The largest `f32` strictly below one: uniform random numbers live in `[0, ONE_MINUS_EPSILON]`.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// `x` rounded to the nearest IEEE half-precision value (ties to even), as a texture stored in
/// half precision holds it: 10 bits of mantissa down to 2⁻¹⁴, steps of 2⁻²⁴ below, ±∞ from
/// 65520 on (the first value that rounds past 65504); NaN stays NaN.
pub fn round_to_half(x: f32) -> f32 {
    let a = x.abs();
    if a.is_nan() || a.is_infinite() {
        return x;
    }
    if a >= 65520.0 {
        return f32::INFINITY.copysign(x);
    }
    if a < 6.103_515_6e-5 {
        // Subnormal halves: multiples of 2⁻²⁴ (exact scalings by powers of two).
        const STEP: f32 = 5.960_464_5e-8;
        return (x / STEP).round_ties_even() * STEP;
    }
    let bits = x.to_bits();
    // Keep 10 of the 23 mantissa bits, rounding to nearest, ties to even.
    let rounded = bits + 0x0fff + ((bits >> 13) & 1);
    f32::from_bits(rounded & !0x1fff)
}

/// Linear interpolation `a (1 − t) + b t`, exact at both ends.
#[inline]
pub fn lerp(a: f32, b: f32, t: f32) -> f32 {
    (1.0 - t) * a + t * b
}

/// `sqrt(max(x, 0))`: square root that tolerates tiny negative round-off.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// `x.floor()` inlined: on x86-64 without SSE4.1 (the baseline neumann is compiled for),
/// `f32::floor` is a call into the C library, which texture lookups and filters make several
/// times per sample. Exact, as `floor`, for every input (the sign of zero, ±∞ and NaN included).
#[inline(always)]
pub fn floor(x: f32) -> f32 {
    // From 2²³ on every f32 is an integer; NaN fails the comparison and comes back as it is.
    if x.is_nan() || x.abs() >= 8_388_608.0 || x == 0.0 {
        return x;
    }
    let t = x as i32 as f32;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

/// `x.ceil()` inlined, exact as `ceil` for every input (see [`floor`]).
#[inline(always)]
pub fn ceil(x: f32) -> f32 {
    if x.is_nan() || x.abs() >= 8_388_608.0 || x == 0.0 {
        return x;
    }
    let t = x as i32 as f32;
    // `t` has the sign of `x` except for x in (-1, 0), whose ceiling is -0.
    if t < x {
        t + 1.0
    } else {
        t.copysign(x)
    }
}

/// `x.round()` (half away from zero) inlined, exact as `round` for every input (see [`floor`]).
#[inline(always)]
pub fn round(x: f32) -> f32 {
    if x.is_nan() {
        // Quieted, as the library's.
        return x + x;
    }
    if x.abs() >= 8_388_608.0 || x == 0.0 {
        return x;
    }
    let t = x as i32 as f32;
    // The fraction `x - t` is exact; `x + 0.5` rounded would not be (0.49999997 + 0.5 is 1).
    let d = x - t;
    let r = if d >= 0.5 {
        t + 1.0
    } else if d <= -0.5 {
        t - 1.0
    } else {
        t
    };
    r.copysign(x)
}

/// `acos` with its argument clamped to `[-1, 1]`.
#[inline]
pub fn safe_acos(x: f32) -> f32 {
    x.clamp(-1.0, 1.0).acos()
}

/// `asin` with its argument clamped to `[-1, 1]`.
#[inline]
pub fn safe_asin(x: f32) -> f32 {
    x.clamp(-1.0, 1.0).asin()
}

/// Spherical direction from (sin θ, cos θ, φ): z is the polar axis, φ is measured from +x toward +y.
#[inline]
pub fn spherical_direction(sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    let (sin_phi, cos_phi) = phi.sin_cos();
    Vec3::new(sin_theta.clamp(-1.0, 1.0) * cos_phi, sin_theta.clamp(-1.0, 1.0) * sin_phi, cos_theta.clamp(-1.0, 1.0))
}

/// Azimuth φ ∈ [0, 2π) of a direction about the z axis.
#[inline]
pub fn spherical_phi(w: Vec3) -> f32 {
    let p = w.y.atan2(w.x);
    if p < 0.0 {
        p + 2.0 * PI
    } else {
        p
    }
}

/// Polar angle θ ∈ [0, π] of a unit direction, measured from +z.
#[inline]
pub fn spherical_theta(w: Vec3) -> f32 {
    safe_acos(w.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Half-precision rounding against NumPy's `float16` (ties to even, subnormals, overflow).
    #[test]
    fn rounds_to_half_precision() {
        for (x, half) in [
            (1.0f32, 1.0f32),
            (0.1, 0.099_975_586),
            (-1.0 / 3.0, -0.333_251_95),
            (2049.0, 2048.0),
            (2051.0, 2052.0),
            (65504.0, 65504.0),
            (65519.0, 65504.0),
            (65520.0, f32::INFINITY),
            (1e-7, 1.192_092_9e-7),
            (3e-8, 5.960_464_5e-8),
            (2.9e-8, 0.0),
            (6.1e-5, 6.097_555e-5),
        ] {
            assert_eq!(round_to_half(x), half, "{x}");
        }
        assert!(round_to_half(f32::NAN).is_nan());
    }

    #[test]
    fn spherical_round_trip() {
        for &(theta, phi) in &[(0.3f32, 0.1f32), (1.2, 3.0), (2.9, 6.0), (1.5, 4.5)] {
            let w = spherical_direction(theta.sin(), theta.cos(), phi);
            assert!((w.length() - 1.0).abs() < 1e-6);
            assert!((spherical_theta(w) - theta).abs() < 1e-4, "theta {theta}");
            assert!((spherical_phi(w) - phi).abs() < 1e-4, "phi {phi}");
        }
    }

    #[test]
    fn floor_ceil_and_round_are_the_library_ones_bit_for_bit() {
        let mut special = vec![0.0f32, -0.0, 0.5, -0.5, 1.5, -2.5, 0.499_999_97, -0.499_999_97, 1.0, -1.0, 8_388_607.5, -8_388_607.5, 8_388_608.0];
        special.extend([-8_388_609.0, 1e30, -1e30, f32::MIN_POSITIVE, -f32::MIN_POSITIVE, 1e-45, -1e-45]);
        special.extend([f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 0.999_999_94, -0.999_999_94, 2.0e9, -2.0e9]);
        // Every special value, and a sweep over all exponents (every 97th bit pattern).
        let sweep = (0..=u32::MAX / 97).map(|k| f32::from_bits(k * 97));
        for x in special.into_iter().chain(sweep) {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "floor({x:e})");
            assert_eq!(ceil(x).to_bits(), x.ceil().to_bits(), "ceil({x:e})");
            assert_eq!(round(x).to_bits(), x.round().to_bits(), "round({x:e})");
        }
    }

    #[test]
    fn one_minus_epsilon_is_below_one() {
        const { assert!(ONE_MINUS_EPSILON < 1.0) };
        assert_eq!(f32::from_bits(ONE_MINUS_EPSILON.to_bits() + 1), 1.0);
    }
}
