//! Math layer: vectors, frames, transforms, bounds, rays and floating-point error bounds.
//!
//! Vectors, points and normals are all `glam::Vec3` (single precision, the renderer's working
//! precision). Which one a value is shows in the *name* of the function that handles it:
//! [`Transform::apply_point`] translates, [`Transform::apply_vector`] does not and
//! [`Transform::apply_normal`] uses the inverse transpose. World space is right-handed; the
//! local shading frame ([`Frame`]) has its normal on +z.

pub mod bounds;
pub mod color;
pub mod cone;
pub mod float;
pub mod frame;
pub mod quadrature;
pub mod ray;
pub mod simd;
pub mod special;
pub mod spectrum;
pub mod transform;
pub mod trig;

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
    fn one_minus_epsilon_is_below_one() {
        const { assert!(ONE_MINUS_EPSILON < 1.0) };
        assert_eq!(f32::from_bits(ONE_MINUS_EPSILON.to_bits() + 1), 1.0);
    }
}
