//! Mitsuba's `measured`: the data-driven BRDF of Dupuy and Jakob, "An Adaptive Parameterization
//! for Efficient Material Acquisition and Rendering" (2018), read from the `.bsdf` tensor files of
//! the RGL material database, evaluated and sampled as Mitsuba 3 does.
//!
//! Coordinates: for the viewer direction `wo` (Mitsuba's `si.wi`) at elevation `θᵢ` and azimuth
//! `φᵢ`, and the half vector `m` of `wo` and the light direction `wi`, the unit coordinates are
//! `u_θ = √(2θ/π)` and `u_φ = (φ + π) / 2π` (for isotropic materials `φ_m` is taken relative to
//! `φᵢ`). The file holds, tabulated over `(φᵢ, θᵢ)` and interpolated linearly between entries
//! ([`Marginal2D`]):
//!
//! - `vndf` (per `(φᵢ, θᵢ)`, over `u_m`): the distribution of visible normals, which maps a
//!   point of the *sample square* to `u_m`; sampling goes square → `u_m` → `m` → `wi = reflect(wo, m)`;
//! - `luminance` (over the sample square): the luminance of the reflectance there, sampled first
//!   so that bright regions get more samples;
//! - `rgb` (3 channels) or `spectra` (per wavelength of `wavelengths`, nm), over the sample square:
//!   `f cos θ` divided, when the `jacobian` flag is set, by `D(m) / (4 σ(wo))`;
//! - `ndf` (`D` over `u_m`) and `sigma` (the projected area `σ` over `u_wo`).
//!
//! The density of `wi` is `p_vndf(u_m) · p_lum(s) / (2π² u_θ sin θ_m · 4 (wo·m))` (the Jacobian
//! of `u_m → m` and of reflection; its first factor clamped to 10⁻⁶ as in Mitsuba). Anisotropic
//! files tabulate `φᵢ` over a half or a quarter of the circle; directions are mirrored into that
//! range and the sampled direction mirrored back.
//!
//! Spectral files (`wavelengths`, `spectra`), which Mitsuba's RGB variants refuse, are reduced to
//! linear sRGB on loading: each tabulated spectrum (linear between its wavelengths) integrated
//! against the CIE colour-matching functions under D65, as a reflectance (the image Mitsuba's
//! spectral variants give, up to the difference between rendering spectra and RGB).
//!
//! One-sided and glossy: black from the back, no delta lobe.

use super::{Bsdf, BsdfBuilder, BsdfContext, BsdfSample};
use crate::math::{spherical_direction, Rgb, Vec2, Vec3, PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::Marginal2D;
use crate::tensor::TensorFile;

/// A measured BRDF (RGL's `.bsdf` data).
#[derive(Clone, Debug)]
pub struct Measured {
    /// The file's description (for messages).
    pub description: String,
    ndf: Marginal2D,
    sigma: Marginal2D,
    vndf: Marginal2D,
    luminance: Marginal2D,
    /// `f cos θ` (divided by `D / 4σ` where `jacobian`) of each channel over the sample square,
    /// conditioned on `(φᵢ, θᵢ)`.
    rgb: [Marginal2D; 3],
    isotropic: bool,
    jacobian: bool,
    /// 1, 2 or 4: how many copies of the tabulated `φᵢ` range make up the circle (0 when
    /// isotropic).
    reduction: u32,
}

/// Elevation of a unit direction, `acos(z)` computed stably near the pole as Mitsuba does.
#[inline]
fn elevation(d: Vec3) -> f32 {
    let dist = (d.x * d.x + d.y * d.y + (d.z - 1.0) * (d.z - 1.0)).sqrt();
    2.0 * (0.5 * dist).min(1.0).asin()
}

#[inline]
fn theta_to_u(theta: f32) -> f32 {
    (theta * (2.0 / PI)).sqrt()
}

#[inline]
fn u_to_theta(u: f32) -> f32 {
    u * u * (PI / 2.0)
}

#[inline]
fn phi_to_u(phi: f32) -> f32 {
    (phi + PI) * (0.5 / PI)
}

#[inline]
fn u_to_phi(u: f32) -> f32 {
    (2.0 * u - 1.0) * PI
}

/// `a` negated when `b ≥ 0` (DrJit's `mulsign_neg`).
#[inline]
fn mulsign_neg(a: f32, b: f32) -> f32 {
    if b.is_sign_negative() {
        a
    } else {
        -a
    }
}

/// The viewer direction as the tables see it, mirrored into the tabulated range of `φᵢ`, and
/// its elevation and azimuth.
struct Incident {
    wo: Vec3,
    /// The signs that mirror directions into the range and back: `(x, y)`.
    signs: (f32, f32),
    theta: f32,
    phi: f32,
}

impl Incident {
    /// `w` mirrored as the viewer direction was (an involution: also back).
    #[inline]
    fn mirror(&self, w: Vec3) -> Vec3 {
        Vec3::new(mulsign_neg(w.x, self.signs.0), mulsign_neg(w.y, self.signs.1), w.z)
    }
}

impl Measured {
    /// The BRDF in a tensor file's fields; an error names the field that is missing or has the
    /// wrong type or shape.
    pub fn from_tensor_file(file: &TensorFile) -> Result<Measured, String> {
        let field = |name: &str| {
            file.field(name).ok_or_else(|| format!("the file has no field '{name}' (not a measured BSDF?)"))
        };
        let floats = |name: &str, dims: usize| -> Result<(Vec<f32>, &[usize]), String> {
            let f = field(name)?;
            match f.f32s() {
                Some(v) if f.shape.len() == dims => Ok((v, &f.shape[..])),
                _ => Err(format!("field '{name}' is {}, expected float32 with {dims} dimension(s)", f.describe())),
            }
        };
        let (theta_i, _) = floats("theta_i", 1)?;
        let (phi_i, _) = floats("phi_i", 1)?;
        let description = field("description")?;
        let description = match description.u8s() {
            Some(b) if description.shape.len() == 1 => String::from_utf8_lossy(b).into_owned(),
            _ => return Err(format!("field 'description' is {}, expected uint8 text", description.describe())),
        };
        let jacobian = match field("jacobian")?.u8s() {
            Some([j]) => *j != 0,
            _ => return Err(format!("field 'jacobian' is {}, expected one uint8", field("jacobian")?.describe())),
        };
        let (ndf, ndf_shape) = floats("ndf", 2)?;
        let (sigma, sigma_shape) = floats("sigma", 2)?;
        let (vndf, vndf_shape) = floats("vndf", 4)?;
        let (luminance, lum_shape) = floats("luminance", 4)?;
        let (np, nt) = (phi_i.len(), theta_i.len());
        let table = |name: &str, shape: &[usize]| {
            if shape[0] != np || shape[1] != nt {
                return Err(format!(
                    "field '{name}' is tabulated over {}×{} incident directions, 'phi_i' and 'theta_i' have {np}×{nt}",
                    shape[0], shape[1]
                ));
            }
            Ok(())
        };
        table("vndf", vndf_shape)?;
        table("luminance", lum_shape)?;
        let (colour, colour_shape, spectral) = match file.field("wavelengths") {
            Some(w) => {
                let lambdas = w.f32s().filter(|_| w.shape.len() == 1).ok_or_else(|| {
                    format!("field 'wavelengths' is {}, expected float32 with 1 dimension", w.describe())
                })?;
                let (spectra, shape) = floats("spectra", 5)?;
                table("spectra", shape)?;
                if shape[2] != lambdas.len() {
                    return Err(format!(
                        "field 'spectra' has {} wavelengths, 'wavelengths' {}",
                        shape[2],
                        lambdas.len()
                    ));
                }
                (spectra_to_rgb(&spectra, shape, &lambdas)?, shape.to_vec(), true)
            }
            None => {
                let (rgb, shape) = floats("rgb", 5)?;
                table("rgb", shape)?;
                if shape[2] != 3 {
                    return Err(format!("field 'rgb' has {} channels, expected 3", shape[2]));
                }
                (rgb, shape.to_vec(), false)
            }
        };
        let colour_name = if spectral { "spectra" } else { "rgb" };
        if lum_shape[2] != lum_shape[3] || colour_shape[3] != colour_shape[4] || lum_shape[2..] != colour_shape[3..] {
            return Err(format!(
                "fields 'luminance' ({}) and '{colour_name}' ({}) must share one square sample grid",
                field("luminance")?.describe(),
                field(colour_name)?.describe()
            ));
        }
        let isotropic = np <= 2;
        let reduction = if isotropic {
            0
        } else {
            let span = phi_i[np - 1] - phi_i[0];
            match (2.0 * PI / span).round() {
                r @ (1.0 | 2.0 | 4.0) => r as u32,
                r => {
                    return Err(format!(
                        "'phi_i' spans {span} rad, 1/{r} of the circle (a whole, half or quarter circle expected)"
                    ))
                }
            }
        };
        let named = |name: &'static str| move |e: String| format!("field '{name}': {e}");
        let params = || vec![phi_i.clone(), theta_i.clone()];
        Ok(Measured {
            description,
            ndf: Marginal2D::new(&ndf, ndf_shape[1], ndf_shape[0], vec![], false).map_err(named("ndf"))?,
            sigma: Marginal2D::new(&sigma, sigma_shape[1], sigma_shape[0], vec![], false).map_err(named("sigma"))?,
            vndf: Marginal2D::new(&vndf, vndf_shape[3], vndf_shape[2], params(), true).map_err(named("vndf"))?,
            luminance: Marginal2D::new(&luminance, lum_shape[3], lum_shape[2], params(), true)
                .map_err(named("luminance"))?,
            rgb: channels(&colour, colour_shape[3] * colour_shape[4])
                .map(|c| Marginal2D::new(&c, colour_shape[4], colour_shape[3], params(), false))
                .into_iter()
                .collect::<Result<Vec<_>, _>>()
                .map_err(named(colour_name))?
                .try_into()
                .expect("three channels"),
            isotropic,
            jacobian,
            reduction,
        })
    }

    /// `wo` mirrored into the tabulated azimuths, with its angles.
    #[inline]
    fn incident(&self, mut wo: Vec3) -> Incident {
        let mut signs = (-1.0, -1.0);
        if self.reduction >= 2 {
            let sy = wo.y;
            let sx = if self.reduction == 4 { wo.x } else { sy };
            signs = (sx, sy);
            wo.x = mulsign_neg(wo.x, sx);
            wo.y = mulsign_neg(wo.y, sy);
        }
        Incident { wo, signs, theta: elevation(wo), phi: wo.y.atan2(wo.x) }
    }

    /// The unit coordinates of the half vector `m` (seen from `inc`).
    #[inline]
    fn u_m(&self, inc: &Incident, m: Vec3) -> Vec2 {
        let phi_m = m.y.atan2(m.x);
        let u = phi_to_u(if self.isotropic { phi_m - inc.phi } else { phi_m });
        Vec2::new(theta_to_u(elevation(m)), u - u.floor())
    }

    /// The viewer side of `wo`, and the half vector of `wo` and `wi` (mirrored alike) with its unit
    /// coordinates: what `eval` and `pdf` look the tables up by.
    #[inline]
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> (Incident, Vec3, Vec2) {
        let inc = self.incident(wo);
        let m = (inc.wo + inc.mirror(wi)).normalize();
        let u_m = self.u_m(&inc, m);
        (inc, m, u_m)
    }

    /// The tabulated `f cos θ` at sample-square point `s`, times `D / 4σ` where the file asks.
    #[inline]
    fn value(&self, inc: &Incident, s: Vec2, u_m: Vec2) -> Rgb {
        let params = [inc.phi, inc.theta];
        // Measured data holds small negative values; a reflectance below zero is taken as 0 (as
        // pbrt-v4 does; Mitsuba keeps the sign).
        let mut v = Rgb::new(self.rgb[0].eval(s, &params), self.rgb[1].eval(s, &params), self.rgb[2].eval(s, &params))
            .max(Rgb::ZERO);
        if self.jacobian {
            let u_wo = Vec2::new(theta_to_u(inc.theta), phi_to_u(inc.phi));
            v *= self.ndf.eval(u_m, &[]) / (4.0 * self.sigma.eval(u_wo, &[]));
        }
        v
    }

    /// The Jacobian from the unit square of `u_m` to the reflected direction.
    #[inline]
    fn jacobian_factor(u_theta: f32, sin_theta_m: f32, wo_dot_m: f32) -> f32 {
        (2.0 * PI * PI * u_theta * sin_theta_m).max(1e-6) * 4.0 * wo_dot_m
    }

    /// `f(wo, wi) cos θᵢ`; 0 unless both directions are above the surface.
    pub fn eval(&self, _: &BsdfContext, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let (inc, _, u_m) = self.half_vector(wo, wi);
        let (s, _) = self.vndf.invert(u_m, &[inc.phi, inc.theta]);
        finite_or_zero(self.value(&inc, s, u_m))
    }

    /// Density of [`Measured::sample`] choosing `wi` (per unit solid angle).
    pub fn pdf(&self, _: &BsdfContext, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let (inc, m, u_m) = self.half_vector(wo, wi);
        let (s, vndf_pdf) = self.vndf.invert(u_m, &[inc.phi, inc.theta]);
        self.density(&inc, m, u_m, s, vndf_pdf)
    }

    /// [`Measured::eval`] and [`Measured::pdf`] at once (the same bits), inverting the
    /// visible-normal warp once.
    pub fn eval_pdf(&self, _: &BsdfContext, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (Rgb::ZERO, 0.0);
        }
        let (inc, m, u_m) = self.half_vector(wo, wi);
        let (s, vndf_pdf) = self.vndf.invert(u_m, &[inc.phi, inc.theta]);
        (finite_or_zero(self.value(&inc, s, u_m)), self.density(&inc, m, u_m, s, vndf_pdf))
    }

    /// The density of the half vector `m` (sample-square point `u_m`, luminance-square point
    /// `s`, visible-normal density `vndf_pdf` there) as a reflected direction; 0 where it is
    /// not finite and positive.
    fn density(&self, inc: &Incident, m: Vec3, u_m: Vec2, s: Vec2, vndf_pdf: f32) -> f32 {
        let lum_pdf = self.luminance.eval(s, &[inc.phi, inc.theta]);
        // x² + y², not 1 − z² (which loses everything near the pole), as Mitsuba's `Frame3f`.
        let sin_theta_m = (m.x * m.x + m.y * m.y).sqrt();
        let pdf = vndf_pdf * lum_pdf / Self::jacobian_factor(u_m.x, sin_theta_m, inc.wo.dot(m));
        if pdf.is_finite() && pdf > 0.0 {
            pdf
        } else {
            0.0
        }
    }

    /// Samples the luminance in the sample square, maps it through the visible normals to `m`
    /// and reflects `wo` about it (`u1` unused).
    pub fn sample(&self, _: &BsdfContext, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let inc = self.incident(wo);
        let params = [inc.phi, inc.theta];
        let (s, lum_pdf) = self.luminance.sample(Vec2::new(u.y, u.x), &params);
        let (u_m, vndf_pdf) = self.vndf.sample(s, &params);
        let mut phi_m = u_to_phi(u_m.y);
        if self.isotropic {
            phi_m += inc.phi;
        }
        let (sin_theta, cos_theta) = u_to_theta(u_m.x).sin_cos();
        let m = spherical_direction(sin_theta, cos_theta, phi_m);
        let wo_dot_m = inc.wo.dot(m);
        let wi = m * (2.0 * wo_dot_m) - inc.wo;
        let pdf = vndf_pdf * lum_pdf / Self::jacobian_factor(u_m.x, sin_theta, wo_dot_m);
        let value = self.value(&inc, s, u_m);
        let wi = inc.mirror(wi);
        if wi.z <= 0.0 || !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let weight = value / pdf;
        weight.is_finite().then_some(BsdfSample { wi, pdf, weight, delta: false, null: false, eta: 1.0 })
    }

    /// Mitsuba's `measured`: `filename`, a `.bsdf` tensor file of the RGL material database
    /// (its RGB or spectral version).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let file = b.tensor_file(o, "filename")?;
        let m = Measured::from_tensor_file(&file).map_err(|e| o.error_at("filename", e))?;
        Ok(Bsdf::Measured(Box::new(m)))
    }
}

/// The three channels of `[φᵢ][θᵢ][3][y][x]` data with `grid` values per `[y][x]`, each as
/// `[φᵢ][θᵢ][y][x]`.
fn channels(rgb: &[f32], grid: usize) -> [Vec<f32>; 3] {
    std::array::from_fn(|c| {
        rgb.chunks_exact(3 * grid).flat_map(|block| &block[c * grid..(c + 1) * grid]).copied().collect()
    })
}

/// The `spectra` field (`[φᵢ][θᵢ][λ][y][x]`) reduced to RGB (`[φᵢ][θᵢ][3][y][x]`): each spectrum,
/// linear between the wavelengths, as a reflectance under D65 in linear sRGB (not clamped).
fn spectra_to_rgb(spectra: &[f32], shape: &[usize], lambdas: &[f32]) -> Result<Vec<f32>, String> {
    if lambdas.iter().any(|l| !l.is_finite()) || lambdas.windows(2).any(|w| w[0] >= w[1]) {
        return Err("field 'wavelengths' is not finite and increasing".into());
    }
    // The reduction is linear in the values: the colour of each wavelength's hat function, once.
    let weights: Vec<Rgb> = (0..lambdas.len())
        .map(|k| {
            let mut hat: Vec<(f32, f32)> = Vec::with_capacity(3);
            if k > 0 {
                hat.push((lambdas[k - 1], 0.0));
            }
            hat.push((lambdas[k], 1.0));
            if k + 1 < lambdas.len() {
                hat.push((lambdas[k + 1], 0.0));
            }
            crate::math::spectrum::reflectance_to_rgb_linear(&hat)
        })
        .collect();
    let (nl, grid) = (shape[2], shape[3] * shape[4]);
    let mut out = Vec::with_capacity(spectra.len() / nl * 3);
    for block in spectra.chunks_exact(nl * grid) {
        for c in 0..3 {
            out.extend(
                (0..grid)
                    .map(|i| weights.iter().enumerate().map(|(k, w)| w[c] * block[k * grid + i]).sum::<f32>().max(0.0)),
            );
        }
    }
    Ok(out)
}

/// `v`, or 0 where a channel is not finite.
#[inline]
fn finite_or_zero(v: Rgb) -> Rgb {
    if v.is_finite() {
        v
    } else {
        Rgb::ZERO
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::material::tests::{assert_matches_mitsuba, MitsubaRow};

    const CTX: BsdfContext = BsdfContext { uv: Vec2::ZERO, mesh: None, textures: None, si: None, memo: None };

    /// The synthetic materials of `scenes/assets` (tools/mitsuba/make_measured.py): `I` isotropic,
    /// `A` anisotropic, tabulated over a quarter circle of incident azimuths.
    pub(crate) fn synthetic(k: char) -> Measured {
        let bytes: &[u8] = match k {
            'I' => include_bytes!("../../scenes/assets/measured_iso.bsdf"),
            _ => include_bytes!("../../scenes/assets/measured_aniso.bsdf"),
        };
        Measured::from_tensor_file(&crate::load::tensor_file::parse_tensor_file(bytes).unwrap()).unwrap()
    }

    /// `eval` and `pdf` equal Mitsuba 3.9.1's (scalar_rgb) on the same files for the same
    /// directions (its `si.wi` is our `wo`): directions in every quadrant, so the anisotropic
    /// material's mirroring into its quarter circle is exercised, and a nearly head-on view.
    /// (Exactly head-on, or with `wi` the mirror image of `wo` so that `m` is the normal, an
    /// azimuth is undefined, `atan2(0, 0)`: neumann takes 0, the limit along φ = 0, where Mitsuba
    /// 3.9.1 returns a value 8–12 % above the two limits measured. Those directions are a set of
    /// measure zero.)
    #[test]
    fn matches_mitsuba() {
        let rows: &[MitsubaRow] = &[
            (
                'I',
                [0.3007679, 0.200512, 0.9323806],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.7724946, 0.5222433, 0.4410284],
                1.51147,
            ),
            (
                'I',
                [0.3007679, 0.200512, 0.9323806],
                [0.7419985, 0.6359987, 0.2119996],
                [0.01424717, 0.006418338, 0.006692059],
                0.01560437,
            ),
            (
                'I',
                [0.3007679, 0.200512, 0.9323806],
                [-0.3504559, -0.1001303, 0.9312114],
                [0.7890901, 0.5315282, 0.4463005],
                1.197046,
            ),
            (
                'I',
                [0.3007679, 0.200512, 0.9323806],
                [0.1154701, -0.5773503, 0.8082904],
                [0.1895968, 0.1033491, 0.06790591],
                0.2274769,
            ),
            (
                'I',
                [-0.8601653, 0.161281, 0.483843],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.06221396, 0.0402068, 0.03508841],
                0.06979109,
            ),
            (
                'I',
                [-0.8601653, 0.161281, 0.483843],
                [0.7419985, 0.6359987, 0.2119996],
                [0.02832056, 0.01880284, 0.0188474],
                0.03244527,
            ),
            (
                'I',
                [-0.8601653, 0.161281, 0.483843],
                [-0.3504559, -0.1001303, 0.9312114],
                [0.05303087, 0.03424706, 0.0305525],
                0.05709778,
            ),
            (
                'I',
                [-0.8601653, 0.161281, 0.483843],
                [0.1154701, -0.5773503, 0.8082904],
                [0.09335797, 0.06015395, 0.05116937],
                0.09821387,
            ),
            (
                'I',
                [0.5976143, -0.7171372, 0.3585686],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.08573522, 0.06244818, 0.05555284],
                0.1011331,
            ),
            (
                'I',
                [0.5976143, -0.7171372, 0.3585686],
                [0.7419985, 0.6359987, 0.2119996],
                [0.02099793, 0.01562359, 0.01590839],
                0.02549573,
            ),
            (
                'I',
                [0.5976143, -0.7171372, 0.3585686],
                [-0.3504559, -0.1001303, 0.9312114],
                [0.1193625, 0.08713004, 0.07644717],
                0.1296141,
            ),
            (
                'I',
                [0.5976143, -0.7171372, 0.3585686],
                [0.1154701, -0.5773503, 0.8082904],
                [0.03644292, 0.02681883, 0.02568335],
                0.04257837,
            ),
            (
                'I',
                [0.001999995, -0.0009999975, 0.9999975],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.4281217, 0.273946, 0.2128903],
                0.5827457,
            ),
            (
                'I',
                [0.001999995, -0.0009999975, 0.9999975],
                [0.7419985, 0.6359987, 0.2119996],
                [0.02656398, 0.01166167, 0.0116178],
                0.02886497,
            ),
            (
                'I',
                [0.001999995, -0.0009999975, 0.9999975],
                [-0.3504559, -0.1001303, 0.9312114],
                [0.3714146, 0.2320386, 0.1741547],
                0.5020574,
            ),
            (
                'I',
                [0.001999995, -0.0009999975, 0.9999975],
                [0.1154701, -0.5773503, 0.8082904],
                [0.1744741, 0.09246388, 0.059348],
                0.2104929,
            ),
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.3886591, 0.6006404, 0.9658581],
                1.871683,
            ),
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [0.7419985, 0.6359987, 0.2119996],
                [0.001077756, 0.001114406, 0.002434971],
                0.0030439,
            ),
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [-0.3504559, -0.1001303, 0.9312114],
                [0.433864, 0.672662, 1.086226],
                1.796079,
            ),
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [0.1154701, -0.5773503, 0.8082904],
                [0.03675621, 0.0399628, 0.0558902],
                0.09948123,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.002269219, 0.00229522, 0.003325376],
                0.004557467,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [0.7419985, 0.6359987, 0.2119996],
                [0.05104712, 0.05145567, 0.06914476],
                0.074142,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [-0.3504559, -0.1001303, 0.9312114],
                [0.00180779, 0.001826599, 0.002551916],
                0.003470131,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [0.1154701, -0.5773503, 0.8082904],
                [0.006250727, 0.006308432, 0.008907665],
                0.01164556,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.06964397, 0.07158887, 0.07929918],
                0.1156724,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [0.7419985, 0.6359987, 0.2119996],
                [0.0006806696, 0.0006861, 0.0008699532],
                0.00125018,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [-0.3504559, -0.1001303, 0.9312114],
                [0.1227477, 0.1285041, 0.1400552],
                0.1891983,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [0.1154701, -0.5773503, 0.8082904],
                [0.01780439, 0.01792746, 0.02140708],
                0.03055043,
            ),
            (
                'A',
                [0.001999995, -0.0009999975, 0.9999975],
                [-0.2500864, -0.2000691, 0.9473274],
                [0.1185317, 0.1515804, 0.1920428],
                0.3432173,
            ),
            (
                'A',
                [0.001999995, -0.0009999975, 0.9999975],
                [0.7419985, 0.6359987, 0.2119996],
                [0.002826401, 0.002918179, 0.006416467],
                0.008357875,
            ),
            (
                'A',
                [0.001999995, -0.0009999975, 0.9999975],
                [-0.3504559, -0.1001303, 0.9312114],
                [0.0483949, 0.0538309, 0.07227629],
                0.1221696,
            ),
            (
                'A',
                [0.001999995, -0.0009999975, 0.9999975],
                [0.1154701, -0.5773503, 0.8082904],
                [0.1114563, 0.1435773, 0.1825758],
                0.374536,
            ),
        ];
        assert_matches_mitsuba(rows, |k| Bsdf::Measured(Box::new(synthetic(k))), |_, _, pdf| pdf);
    }

    /// `sample` maps the same random numbers to the same direction, weight and density as
    /// Mitsuba's (its `sample2`; `sample1` unused).
    #[test]
    fn samples_as_mitsuba_does() {
        #[allow(clippy::type_complexity)]
        let rows: &[(char, [f32; 3], [f32; 2], [f32; 3], [f32; 3], f32)] = &[
            (
                'I',
                [0.3007679, 0.200512, 0.9323806],
                [0.3, 0.7],
                [0.3799339, -0.4692624, 0.7971468],
                [0.9242562, 0.4664963, 0.3136435],
                0.1262672,
            ),
            (
                'I',
                [0.3007679, 0.200512, 0.9323806],
                [0.9, 0.15],
                [-0.4776154, -0.1844691, 0.8589847],
                [0.6754289, 0.4507508, 0.3727149],
                1.062911,
            ),
            (
                'I',
                [-0.8601653, 0.161281, 0.483843],
                [0.3, 0.7],
                [0.345802, 0.4684381, 0.8130109],
                [0.9473869, 0.620012, 0.524308],
                0.1051995,
            ),
            (
                'I',
                [-0.8601653, 0.161281, 0.483843],
                [0.9, 0.15],
                [0.8757122, -0.2477788, 0.4144078],
                [0.7916138, 0.5751284, 0.4986818],
                1.663006,
            ),
            (
                'I',
                [0.5976143, -0.7171372, 0.3585686],
                [0.3, 0.7],
                [-0.5197707, -0.1865901, 0.83368],
                [0.8724239, 0.6383457, 0.5741959],
                0.09539795,
            ),
            (
                'I',
                [0.5976143, -0.7171372, 0.3585686],
                [0.9, 0.15],
                [-0.5396862, 0.7726327, 0.3343315],
                [0.915813, 0.6946108, 0.6159768],
                1.753033,
            ),
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [0.3, 0.7],
                [-0.4325972, 0.6491328, 0.6256886],
                [0.3371926, 0.3897632, 0.4933288],
                0.2676304,
            ),
            (
                'A',
                [0.3007679, 0.200512, 0.9323806],
                [0.9, 0.15],
                [-0.2302385, -0.3376248, 0.9126882],
                [0.2450346, 0.3766644, 0.5995327],
                1.746768,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [0.3, 0.7],
                [0.889269, 0.3239483, 0.3228903],
                [0.5536423, 0.5797065, 0.6678024],
                0.4024357,
            ),
            (
                'A',
                [-0.8601653, 0.161281, 0.483843],
                [0.9, 0.15],
                [0.8066998, -0.2442755, 0.5381125],
                [0.385862, 0.5129336, 0.7252058],
                2.425359,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [0.3, 0.7],
                [-0.4894364, -0.3870398, 0.7814424],
                [0.6521689, 0.6707138, 0.744846],
                0.1658483,
            ),
            (
                'A',
                [0.5976143, -0.7171372, 0.3585686],
                [0.9, 0.15],
                [-0.5889577, 0.7666172, 0.2557866],
                [0.51065, 0.6413332, 0.8585613],
                3.075838,
            ),
        ];
        for &(k, wo, u, wi, weight, pdf) in rows {
            let s = synthetic(k).sample(&CTX, Vec3::from_array(wo), Vec2::from_array(u)).unwrap();
            assert!((s.wi - Vec3::from_array(wi)).abs().max_element() < 2e-5, "{k} {wo:?} {u:?}: {} vs {wi:?}", s.wi);
            assert!((s.pdf / pdf - 1.0).abs() < 2e-4, "{k} {wo:?} {u:?}: pdf {} vs {pdf}", s.pdf);
            assert!((s.weight - Rgb::from_array(weight)).abs().max_element() < 2e-4, "{k}: {} vs {weight:?}", s.weight);
        }
    }

    /// Black from below, and a file that is not a measured BSDF is an error naming the field.
    #[test]
    fn one_sided_and_bad_files() {
        let m = synthetic('A');
        let (up, down) = (Vec3::new(0.3, 0.2, 0.93).normalize(), Vec3::new(0.3, 0.2, -0.93).normalize());
        assert_eq!(m.eval(&CTX, down, up), Rgb::ZERO);
        assert_eq!(m.eval(&CTX, up, down), Rgb::ZERO);
        assert_eq!(m.pdf(&CTX, down, up), 0.0);
        assert!(m.sample(&CTX, down, Vec2::splat(0.5)).is_none());
        let file = |edit: &dyn Fn(&mut TensorFile)| {
            let bytes: &[u8] = include_bytes!("../../scenes/assets/measured_aniso.bsdf");
            let mut t = crate::load::tensor_file::parse_tensor_file(bytes).unwrap();
            edit(&mut t);
            Measured::from_tensor_file(&t).unwrap_err()
        };
        assert!(file(&|t| drop(t.fields.remove("vndf"))).contains("no field 'vndf'"));
        let e = file(&|t| {
            t.fields.insert("sigma".into(), crate::tensor::TensorField::from_u8(&[4], &[0; 4]));
        });
        assert!(e.contains("'sigma' is uint8[4], expected float32 with 2"), "{e}");
        let e = file(&|t| {
            t.fields.insert("theta_i".into(), crate::tensor::TensorField::from_f32(&[2], &[0.0, 1.0]));
        });
        assert!(e.contains("'vndf' is tabulated over 3×5 incident directions, 'phi_i' and 'theta_i' have 3×2"), "{e}");
        let e = file(&|t| {
            t.fields.insert("phi_i".into(), crate::tensor::TensorField::from_f32(&[3], &[-3.0, -2.5, -2.0]));
        });
        assert!(e.contains("a whole, half or quarter circle"), "{e}");
    }

    /// A spectral file reduces to the RGB of its spectra: a flat spectrum of `v` at every point
    /// gives the grey `v` (the reduction's white is D65), one at 450 nm only a blue.
    #[test]
    fn spectral_files_reduce_to_rgb() {
        let lambdas: Vec<f32> = (0..17).map(|i| 360.0 + 30.0 * i as f32).collect();
        let shape = [1, 1, lambdas.len(), 2, 2];
        let flat = vec![0.5; 4 * lambdas.len()];
        let rgb = spectra_to_rgb(&flat, &shape, &lambdas).unwrap();
        assert_eq!(rgb.len(), 12);
        assert!(rgb.iter().all(|v| (v - 0.5).abs() < 2e-3), "{rgb:?}");
        let mut blue = vec![0.0; 4 * lambdas.len()];
        blue[3 * 4..][..4].fill(1.0); // 450 nm
        let rgb = spectra_to_rgb(&blue, &shape, &lambdas).unwrap();
        assert!(rgb[8] > 3.0 * rgb[4] && rgb[0] < rgb[8], "{rgb:?}");
    }
}
