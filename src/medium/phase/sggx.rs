//! Mitsuba's `sggx` phase function: specular reflection from microflakes whose normals follow
//! the SGGX distribution (Heitz et al. 2015, "The SGGX microflake distribution"), a symmetric
//! positive definite matrix `S` per point, given as a six-channel grid
//! `[S_xx, S_yy, S_zz, S_xy, S_xz, S_yz]` (Mitsuba's `S`).
//!
//! With `σ(ω) = √(ωᵀ S ω)` the flakes' projected area toward `ω` and
//! `D(m) = |S|^{3/2} / (π (mᵀ adj(S) m)²)` their normal density (= `1 / (π √|S| (mᵀ S⁻¹ m)²)`),
//! the phase function is `p(wo → wi) = D(h) / (4 σ(wo))` with `h` the half vector of `wo` and
//! `wi` (Mitsuba's `0.25 · D(normalize(wo + wi)) / σ(wo)`). It is sampled exactly: a normal from
//! the distribution of normals visible from `wo` (Heitz et al.'s construction in a frame around
//! `wo`), `wo` reflected about it; the density is the same expression.
//!
//! A medium with this phase function is a microflake medium: its extinction toward a direction
//! `ω` is `σₜ · σ(ω)` (Mitsuba's `Microflake` flag: the medium multiplies `sigma_t` by the
//! projected area along the ray), see [`super::super::Heterogeneous`].

use crate::image::VolumeSource;
use crate::math::{Frame, Vec2, Vec3, PI};
use crate::props::{Obj, Result, Value};
use crate::sampling::{sample_cosine_hemisphere_malley, Sample};
use crate::texture::volume::Volume6;

/// The SGGX phase function over space.
#[derive(Clone, Debug)]
pub struct SggxPhase {
    /// `[S_xx, S_yy, S_zz, S_xy, S_xz, S_yz]` at each point.
    s: Volume6,
    /// An upper bound of `σ(ω)` over every direction and point.
    max_area: f32,
}

/// `[S_xx, S_yy, S_zz, S_xy, S_xz, S_yz]`.
type Params = [f32; 6];
const XX: usize = 0;
const YY: usize = 1;
const ZZ: usize = 2;
const XY: usize = 3;
const XZ: usize = 4;
const YZ: usize = 5;

/// The projected area `σ(ω) = √(ωᵀ S ω)` of the flakes toward unit `w` (zero where `S` is not
/// positive there).
#[inline]
pub fn projected_area(w: Vec3, s: &Params) -> f32 {
    let sigma2 = w.x * w.x * s[XX]
        + w.y * w.y * s[YY]
        + w.z * w.z * s[ZZ]
        + 2.0 * (w.x * w.y * s[XY] + w.x * w.z * s[XZ] + w.y * w.z * s[YZ]);
    sigma2.max(0.0).sqrt()
}

/// The density of flake normals `D(m)` (flake area per unit solid angle of normals, normalised
/// so that `∫ ⟨ω, m⟩₊ D(m) dm = σ(ω)`; the identity gives `1/π`).
#[inline]
pub fn normal_density(m: Vec3, s: &Params) -> f32 {
    let det = (s[XX] * s[YY] * s[ZZ] - s[XX] * s[YZ] * s[YZ] - s[YY] * s[XZ] * s[XZ] - s[ZZ] * s[XY] * s[XY]
        + 2.0 * s[XY] * s[XZ] * s[YZ])
        .abs();
    let den = m.x * m.x * (s[YY] * s[ZZ] - s[YZ] * s[YZ])
        + m.y * m.y * (s[XX] * s[ZZ] - s[XZ] * s[XZ])
        + m.z * m.z * (s[XX] * s[YY] - s[XY] * s[XY])
        + 2.0
            * (m.x * m.y * (s[XZ] * s[YZ] - s[ZZ] * s[XY])
                + m.x * m.z * (s[XY] * s[YZ] - s[YY] * s[XZ])
                + m.y * m.z * (s[XY] * s[XZ] - s[XX] * s[YZ]));
    let d = det * det.sqrt() / (PI * den * den);
    if d.is_finite() {
        d
    } else {
        0.0
    }
}

/// A flake normal from the distribution of normals visible from unit `w`, `D_w(m) =
/// ⟨w, m⟩₊ D(m) / σ(w)`, by Heitz et al.'s construction: `u` mapped to a cosine-distributed
/// point of the hemisphere about `w`, carried by the matrix that maps the unit sphere's visible
/// normals onto the ellipsoid's in the frame `(k, j, i = w)`.
pub fn sample_visible_normal(w: Vec3, u: Vec2, s: &Params) -> Vec3 {
    let frame = Frame::from_z(w);
    let axes = [frame.s, frame.t, frame.n];
    let sm = |a: Vec3| {
        Vec3::new(
            s[XX] * a.x + s[XY] * a.y + s[XZ] * a.z,
            s[XY] * a.x + s[YY] * a.y + s[YZ] * a.z,
            s[XZ] * a.x + s[YZ] * a.y + s[ZZ] * a.z,
        )
    };
    // S in the frame: s2[r][c] = axes[r]ᵀ S axes[c].
    let s2: [[f32; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| axes[r].dot(sm(axes[c]))));
    let (k, j, i) = (0, 1, 2);
    let det = s2[0][0] * (s2[1][1] * s2[2][2] - s2[1][2] * s2[2][1])
        - s2[0][1] * (s2[1][0] * s2[2][2] - s2[1][2] * s2[2][0])
        + s2[0][2] * (s2[1][0] * s2[2][1] - s2[1][1] * s2[2][0]);
    let inv_sqrt_s_ii = 1.0 / s2[i][i].max(f32::MIN_POSITIVE).sqrt();
    let tmp = (s2[j][j] * s2[i][i] - s2[j][i] * s2[j][i]).max(0.0).sqrt();
    let m_k = Vec3::new(det.abs().sqrt() / tmp, 0.0, 0.0);
    let m_j = Vec3::new(-inv_sqrt_s_ii * (s2[k][i] * s2[j][i] - s2[k][j] * s2[i][i]) / tmp, inv_sqrt_s_ii * tmp, 0.0);
    let m_i = Vec3::new(s2[k][i], s2[j][i], s2[i][i]) * inv_sqrt_s_ii;
    let uvw = sample_cosine_hemisphere_malley(u).value;
    frame.to_world((m_k * uvw.x + m_j * uvw.y + m_i * uvw.z).normalize_or_zero())
}

impl SggxPhase {
    /// The phase function of the SGGX matrices `s`.
    pub fn new(s: Volume6) -> SggxPhase {
        // σ(ω)² = ωᵀSω ≤ λ_max(S) ≤ the largest absolute row sum (Gershgorin), at every texel,
        // and an interpolated S is a convex combination of texels.
        let max_area = s
            .texels()
            .map(|t| {
                let rows = [
                    t[XX].abs() + t[XY].abs() + t[XZ].abs(),
                    t[XY].abs() + t[YY].abs() + t[YZ].abs(),
                    t[XZ].abs() + t[YZ].abs() + t[ZZ].abs(),
                ];
                rows.into_iter().fold(0.0f32, f32::max)
            })
            .fold(0.0f32, f32::max)
            .sqrt();
        SggxPhase { s, max_area }
    }

    /// The projected area `σ(w)` of the flakes at `p` toward unit `w` (either sign).
    #[inline]
    pub fn projected_area(&self, p: Vec3, w: Vec3) -> f32 {
        projected_area(w, &self.s.eval(p))
    }

    /// An upper bound of [`SggxPhase::projected_area`] everywhere.
    pub fn max_projected_area(&self) -> f32 {
        self.max_area
    }

    /// Density of scattering from `wo` into `wi` at `p` (sr⁻¹, module docs).
    #[inline]
    pub fn eval(&self, p: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let s = self.s.eval(p);
        let area = projected_area(wo, &s);
        let h = (wo + wi).normalize_or_zero();
        if area <= 0.0 || h == Vec3::ZERO {
            return 0.0;
        }
        0.25 * normal_density(h, &s) / area
    }

    /// Samples `wi` for `wo` at `p`: a visible normal, `wo` reflected about it.
    #[inline]
    pub fn sample(&self, p: Vec3, wo: Vec3, u: Vec2) -> Sample<Vec3> {
        let s = self.s.eval(p);
        let area = projected_area(wo, &s);
        let m = sample_visible_normal(wo, u, &s);
        if area <= 0.0 || m == Vec3::ZERO {
            return Sample::solid_angle(-wo, 0.0);
        }
        let wi = (m * (2.0 * wo.dot(m)) - wo).normalize();
        Sample::solid_angle(wi, 0.25 * normal_density(m, &s) / area)
    }

    /// Mitsuba's `sggx`: `S`, a six-channel `gridvolume` (`<volume type="gridvolume" name="S">`).
    pub fn from_props(o: &Obj, files: &mut dyn VolumeSource) -> Result<SggxPhase> {
        o.check_children(&[])?;
        let v =
            match o.get("S").map(|p| &p.value) {
                Some(Value::Object(v)) if v.tag == "volume" => v,
                Some(_) => return Err(o.error_at("S", "'S' takes a <volume type=\"gridvolume\"> of six channels")),
                None => return Err(o.error(
                    "an sggx phase function needs its 'S': a <volume type=\"gridvolume\" name=\"S\"> of six channels",
                )),
            };
        v.built.set(true);
        let s = Volume6::from_props(v, files)?;
        if s.texels().flatten().any(|x| !x.is_finite()) {
            return Err(v.error("the S grid holds a value that is not finite"));
        }
        Ok(SggxPhase::new(s))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::image::GridVolume;
    use crate::math::Transform;
    use crate::texture::volume::{GridFilter, GridWrap};
    use std::sync::Arc;

    /// The phase function of one texel `s` everywhere.
    pub(crate) fn uniform(s: Params) -> SggxPhase {
        let grid = GridVolume { res: [1, 1, 1], channels: 6, bbox: [[0.0; 3], [1.0; 3]], data: s.to_vec() };
        let v = Volume6::grid(Arc::new(grid), GridFilter::Trilinear, GridWrap::Clamp, Transform::IDENTITY).unwrap();
        SggxPhase::new(v)
    }

    /// Densities and projected areas as Mitsuba 3.9.1 gives them (`tools/mitsuba/phase_values.py`)
    /// for the identity (isotropic scattering), a diagonal and two full matrices, one with
    /// eigenvalues above 1. The pair `wo = -wi` (light going straight on) has no half vector:
    /// Mitsuba's density is NaN there, neumann's 0.
    #[test]
    fn matches_mitsuba() {
        let pairs = super::super::PROBE_PAIRS;
        let cases: [(Params, [f32; 4], [f32; 5]); 4] = [
            (
                [1.0, 1.0, 1.0, 0.0, 0.0, 0.0],
                [0.07957747, 0.07957747, 0.07957747, 0.0795775],
                [1.0, 1.0, 1.0, 1.0, 0.9999999],
            ),
            (
                [1.0, 0.2, 0.05, 0.0, 0.0, 0.0],
                [0.008897032, 0.1171262, 0.01541613, 0.01758174],
                [0.2236068, 0.2236068, 0.4165112, 0.6260991, 0.4008918],
            ),
            (
                [0.6, 0.5, 0.3, 0.2, -0.1, 0.15],
                [0.02659582, 0.03808675, 0.1891206, 0.1212],
                [0.5477226, 0.5477226, 0.3824926, 0.5585696, 0.7221001],
            ),
            (
                [2.5, 0.4, 1.2, 0.3, 0.5, -0.2],
                [0.06657356, 0.1557346, 0.01185186, 0.0087141],
                [1.095445, 1.095445, 1.197042, 1.465606, 1.09218],
            ),
        ];
        let p = Vec3::new(0.2, 0.3, 0.4);
        for (s, densities, areas) in cases {
            let phase = uniform(s);
            for (k, (wo, wi)) in pairs.iter().enumerate() {
                let (wo, wi) = (Vec3::from(*wo).normalize(), Vec3::from(*wi).normalize());
                let area = phase.projected_area(p, wo);
                assert!(
                    (area - areas[k]).abs() <= 2e-6 * areas[k],
                    "{s:?} {wo}: area {area} vs Mitsuba's {}",
                    areas[k]
                );
                let got = phase.eval(p, wo, wi);
                if k == 0 {
                    assert_eq!(got, 0.0);
                    continue;
                }
                let want = densities[k - 1];
                assert!((got - want).abs() <= 2e-5 * want, "{s:?} {wo} {wi}: {got} vs Mitsuba's {want}");
            }
            assert!(phase.max_projected_area() >= areas.iter().fold(0.0f32, |a, &b| a.max(b)));
        }
    }

    /// `D` is a density of flake area with projected area `σ`: `∫ ⟨w, m⟩₊ D(m) dm = σ(w)` for
    /// any `w` (so the visible normals `⟨w, m⟩₊ D(m) / σ(w)` are a density); and the sampled
    /// visible normals lie in `w`'s hemisphere.
    #[test]
    fn normals_project_to_the_projected_area() {
        use crate::testkit::{integrate_pdf_2d, SPHERE};
        for s in [[1.0, 0.2, 0.05, 0.0, 0.0, 0.0], [0.6, 0.5, 0.3, 0.2, -0.1, 0.15]] {
            for w in [Vec3::Z, Vec3::new(0.6, -0.3, 0.2).normalize()] {
                let proj =
                    integrate_pdf_2d(&SPHERE, [64, 128], |m| (w.dot(*m).max(0.0) * normal_density(*m, &s)) as f64);
                let area = projected_area(w, &s) as f64;
                assert!((proj - area).abs() < 0.01 * area, "{s:?} {w}: {proj} vs σ = {area}");
                let mut rng = crate::sampling::Pcg32::new(3, 1);
                for _ in 0..1000 {
                    let m = sample_visible_normal(w, Vec2::new(rng.next_f32(), rng.next_f32()), &s);
                    assert!(m.dot(w) >= -1e-5 && (m.length() - 1.0).abs() < 1e-4, "{m}");
                }
            }
        }
    }
}
