//! Fresnel equations, reflection and refraction, and Mitsuba's named indices of refraction.
//!
//! Conventions (Mitsuba 3): `eta = int_ior / ext_ior` is the relative index of the interior
//! (the side opposite the normal) to the exterior; `cos_theta_i > 0` means incidence from the
//! exterior. Light is unpolarized.

use crate::math::{Rgb, Vec3};
use crate::props::{nearest, Obj, Result as PropResult, Value};

/// Unpolarized Fresnel reflectance of a dielectric interface, with the refracted direction's
/// cosine. Returns `(F, cos θₜ, η_it, η_ti)`: reflectance; the (signed, opposite to cos θᵢ) cosine
/// of the transmitted direction (0 under total internal reflection); and the relative indices
/// of refraction from the incident to the transmitted side and back.
#[inline]
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> (f32, f32, f32, f32) {
    let outside = cos_theta_i >= 0.0;
    let (eta_it, eta_ti) = if outside { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    let cos_i = cos_theta_i.abs().min(1.0);
    // Snell: sin²θₜ = sin²θᵢ / η².
    let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
    if cos_t2 <= 0.0 {
        return (1.0, 0.0, eta_it, eta_ti); // total internal reflection
    }
    let cos_t = cos_t2.sqrt();
    let rs = (cos_i - eta_it * cos_t) / (cos_i + eta_it * cos_t);
    let rp = (eta_it * cos_i - cos_t) / (eta_it * cos_i + cos_t);
    let f = 0.5 * (rs * rs + rp * rp);
    (f, if outside { -cos_t } else { cos_t }, eta_it, eta_ti)
}

/// Unpolarized Fresnel reflectance of a conductor with complex index `eta + i k` (per channel,
/// relative to the exterior) at incidence `cos θᵢ ∈ [0, 1]`; exact formula (no approximation).
pub fn fresnel_conductor(cos_theta_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    let f = |eta: f32, k: f32| fresnel_conductor_channel(cos_theta_i, eta, k);
    Rgb::new(f(eta.x, k.x), f(eta.y, k.y), f(eta.z, k.z))
}

/// [`fresnel_conductor`] of one channel (index `eta + i k`), in double precision.
#[inline(always)]
pub(crate) fn fresnel_conductor_channel(cos_theta_i: f32, eta: f32, k: f32) -> f32 {
    let c = cos_theta_i.clamp(0.0, 1.0) as f64;
    let (eta, k) = (eta as f64, k as f64);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let (eta2, k2) = (eta * eta, k * k);
    let t0 = eta2 - k2 - s2;
    let a2b2 = (t0 * t0 + 4.0 * eta2 * k2).sqrt();
    let t1 = a2b2 + c2;
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t2 = 2.0 * c * a;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    (0.5 * (rp + rs)) as f32
}

/// Mirror reflection of `wi` about the local normal +z.
#[inline]
pub fn reflect(wi: Vec3) -> Vec3 {
    Vec3::new(-wi.x, -wi.y, wi.z)
}

/// Mirror reflection of `wi` about the unit vector `m`.
#[inline]
pub fn reflect_about(wi: Vec3, m: Vec3) -> Vec3 {
    2.0 * wi.dot(m) * m - wi
}

/// Refraction of `wi` through the local interface (normal +z), given `cos θₜ` and `η_ti` from
/// [`fresnel_dielectric`].
#[inline]
pub fn refract(wi: Vec3, cos_theta_t: f32, eta_ti: f32) -> Vec3 {
    Vec3::new(-eta_ti * wi.x, -eta_ti * wi.y, cos_theta_t)
}

/// Refraction of `wi` through a microfacet with unit normal `m`.
#[inline]
pub fn refract_about(wi: Vec3, m: Vec3, cos_theta_t: f32, eta_ti: f32) -> Vec3 {
    m * (wi.dot(m) * eta_ti + cos_theta_t) - wi * eta_ti
}

/// Mitsuba 3's named indices of refraction (at 589 nm).
pub const NAMED_IORS: [(&str, f32); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// The index of refraction named `name` (case-insensitive), if Mitsuba knows it.
pub fn lookup_ior(name: &str) -> Option<f32> {
    let n = name.trim().to_ascii_lowercase();
    NAMED_IORS.iter().find(|(k, _)| *k == n).map(|&(_, v)| v)
}

/// An index of refraction parameter `name` (Mitsuba's `int_ior` / `ext_ior`): a number or a
/// named material ([`NAMED_IORS`]), positive; `default` if absent.
pub fn ior_from_props(o: &Obj, name: &str, default: f32) -> PropResult<f32> {
    let v = match o.get(name).map(|p| &p.value) {
        None => default,
        Some(Value::Float(f)) => *f as f32,
        Some(Value::Integer(i)) => *i as f32,
        Some(Value::String(s)) => lookup_ior(s).ok_or_else(|| {
            let names = NAMED_IORS.iter().map(|n| n.0);
            let hint = nearest(s, names).map(|n| format!(" (did you mean '{n}'?)")).unwrap_or_default();
            o.error_at(name, format!("unknown index of refraction '{s}'{hint}"))
        })?,
        Some(_) => return Err(o.error_at(name, format!("'{name}' must be a number or a material name"))),
    };
    if !(v > 0.0 && v.is_finite()) {
        return Err(o.error_at(name, format!("'{name}' must be positive, got {v}")));
    }
    Ok(v)
}

/// The relative index `int_ior / ext_ior` of a dielectric interface (defaults `default_int` and
/// air, 1.000277).
pub fn eta_from_props(o: &Obj, default_int: f32) -> PropResult<f32> {
    Ok(ior_from_props(o, "int_ior", default_int)? / ior_from_props(o, "ext_ior", 1.000277)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent f64 evaluation of the Fresnel equations from the angles.
    fn reference(theta_i: f64, n1: f64, n2: f64) -> f64 {
        let s = n1 / n2 * theta_i.sin();
        if s >= 1.0 {
            return 1.0;
        }
        let theta_t = s.asin();
        let rs = ((n1 * theta_i.cos() - n2 * theta_t.cos()) / (n1 * theta_i.cos() + n2 * theta_t.cos())).powi(2);
        let rp = ((n1 * theta_t.cos() - n2 * theta_i.cos()) / (n1 * theta_t.cos() + n2 * theta_i.cos())).powi(2);
        0.5 * (rs + rp)
    }

    #[test]
    fn dielectric_matches_reference_both_sides() {
        for eta in [1.1f32, 1.5, 2.419] {
            for k in 0..90 {
                let th = (k as f64).to_radians();
                let (f, cos_t, _, eta_ti) = fresnel_dielectric(th.cos() as f32, eta);
                assert!((f as f64 - reference(th, 1.0, eta as f64)).abs() < 1e-5, "outside η={eta} θ={k}");
                assert!(cos_t <= 0.0 && (eta_ti - 1.0 / eta).abs() < 1e-7);
                let (f_in, cos_t_in, _, _) = fresnel_dielectric(-(th.cos() as f32), eta);
                assert!((f_in as f64 - reference(th, eta as f64, 1.0)).abs() < 1e-5, "inside η={eta} θ={k}");
                assert!(cos_t_in >= 0.0);
            }
            // Normal incidence and total internal reflection.
            let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!((fresnel_dielectric(1.0, eta).0 - f0).abs() < 1e-6);
            let critical = (1.0 / eta).asin();
            assert_eq!(fresnel_dielectric(-(critical + 0.01).cos(), eta).0, 1.0);
        }
    }

    #[test]
    fn refraction_obeys_snell_and_reciprocity() {
        let eta = 1.5;
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let (f, cos_t, _, eta_ti) = fresnel_dielectric(wi.z, eta);
        let wt = refract(wi, cos_t, eta_ti);
        assert!((wt.length() - 1.0).abs() < 1e-6);
        assert!((wi.x.hypot(wi.y) - eta * wt.x.hypot(wt.y)).abs() < 1e-6, "Snell");
        // Going back through the interface retraces the path with the same reflectance.
        let (f_back, cos_back, _, eta_back) = fresnel_dielectric(wt.z, eta);
        let back = refract(wt, cos_back, eta_back);
        assert!((back - wi).length() < 1e-5, "{back} vs {wi}");
        assert!((f - f_back).abs() < 1e-6);
        assert!((reflect(wi) - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-7);
        let m = Vec3::new(0.0, 0.6, 0.8);
        assert!((reflect_about(Vec3::Z, m).dot(m) - m.z).abs() < 1e-6);
    }

    #[test]
    fn conductor_reduces_to_dielectric_and_normal_incidence() {
        for k in 0..90 {
            let c = (k as f32).to_radians().cos();
            let f = fresnel_conductor(c, Rgb::splat(1.5), Rgb::ZERO);
            assert!((f.x - fresnel_dielectric(c, 1.5).0).abs() < 1e-5, "θ={k}");
        }
        let (n, kk) = (0.2f32, 3.9f32);
        let f0 = ((n - 1.0).powi(2) + kk * kk) / ((n + 1.0).powi(2) + kk * kk);
        assert!((fresnel_conductor(1.0, Rgb::splat(n), Rgb::splat(kk)).x - f0).abs() < 1e-5);
        assert!((fresnel_conductor(0.0, Rgb::splat(n), Rgb::splat(kk)).x - 1.0).abs() < 1e-5, "grazing → 1");
    }

    #[test]
    fn named_iors() {
        assert_eq!(lookup_ior("BK7"), Some(1.5046));
        assert_eq!(lookup_ior("water"), Some(1.333));
        assert!(lookup_ior("unobtainium").is_none());
    }
}
