//! What a radiance sample becomes before it reaches the film: pbrt-v4's pixel-sensor steps that
//! neumann's RGB films can take — white balance, a named camera's colour response, and the clamp
//! of a sample's largest component.
//!
//! **White balance** (pbrt-v4's `whitebalance` of its `cie1931` sensor): the image is adapted
//! from a source white — CIE daylight (the D series) of the given correlated colour
//! temperature, or a black body below 4000 K where the D series is not defined, as pbrt
//! chooses — to the output colour space's white (sRGB's D65) by the von Kries transform in
//! Bradford's cone space: `RGB ← RGB_from_XYZ · B⁻¹ diag(L_dst/L_src) B · XYZ_from_RGB`.
//!
//! **Named camera sensors** (pbrt-v4's `"string sensor"`, seventeen cameras whose spectral
//! responses were measured, [`camera`]): pbrt-v4 maps a camera's raw RGB to XYZ by a 3 × 3
//! matrix fitted by least squares on the 24 ColorChecker swatches seen under CIE daylight of the
//! white-balance temperature (6500 K unless given), so that a white lit by that light comes out
//! as the output space's white. pbrt renders spectra and applies the camera's curves to them;
//! neumann renders linear sRGB, so the camera becomes one matrix on linear sRGB, fitted the same
//! way: the best linear map (least squares, with D65's white mapped exactly) from the sRGB
//! neumann renders for the swatches, under D65 and under the white-balance light, to the sRGB
//! pbrt's camera gives for their spectra. How close that comes to the spectral answer is
//! measured in the tests (`camera_matrices_reproduce_the_spectral_pipeline`).
//!
//! **Clamp** (pbrt-v4's `maxcomponentvalue`): a sample whose largest RGB component exceeds the
//! bound is scaled down to it (biased, as pbrt's is; off by default; neumann clamps the output
//! RGB, pbrt the sensor's RGB before its colour matrix, the same where there is no matrix).

use super::sensor_data::{CAMERAS, CAMERA_LAMBDA_START, SWATCHES, SWATCH_LAMBDA_START};
use crate::math::spectrum::{cie_xyz_d65, daylight, sample_at};
use glam::{DMat3, DVec3};

use crate::math::{Mat3, Rgb, Vec3};

/// The per-sample transform (identity by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleTransform {
    /// A colour matrix applied to every sample (white balance), if any.
    pub matrix: Option<Mat3>,
    /// The largest value a sample's largest component may take (∞: no clamp).
    pub max_component: f32,
    /// Where the clamp measures that component: `None`, in the output RGB (neumann's
    /// `max_component`); `Some(S)`, in `S ×` the sample as rendered — pbrt-v4 clamps its
    /// sensor's RGB before the colour matrix: XYZ for `cie1931`, a named camera's raw RGB
    /// ([`camera_sensor_basis`]).
    pub clamp_basis: Option<Mat3>,
}

impl Default for SampleTransform {
    fn default() -> Self {
        SampleTransform { matrix: None, max_component: f32::INFINITY, clamp_basis: None }
    }
}

/// pbrt-v4's sensor RGB of a rendered linear sRGB sample for the `cie1931` sensor (with or
/// without white balance): the sample's CIE XYZ.
pub fn cie1931_sensor_basis() -> Mat3 {
    xyz_from_rgb()
}

/// Bradford's cone-response matrix (XYZ → LMS), rows as published.
fn bradford() -> Mat3 {
    Mat3::from_cols(
        Vec3::new(0.8951, -0.7502, 0.0389),
        Vec3::new(0.2664, 1.7135, -0.0685),
        Vec3::new(-0.1614, 0.0367, 1.0296),
    )
}

/// Linear sRGB → CIE XYZ (D65).
fn xyz_from_rgb() -> Mat3 {
    Mat3::from_cols(
        Vec3::new(0.412_456_4, 0.212_672_9, 0.019_333_9),
        Vec3::new(0.357_576_1, 0.715_152_2, 0.119_192),
        Vec3::new(0.180_437_5, 0.072_175, 0.950_304_1),
    )
}

/// sRGB's white point (D65) chromaticity.
pub const D65_XY: [f32; 2] = [0.3127, 0.3290];

/// XYZ of chromaticity `xy` at Y = 1.
fn xyz_of(xy: [f32; 2]) -> Vec3 {
    Vec3::new(xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1])
}

/// The chromaticity of pbrt-v4's white for a colour temperature of `kelvin`: CIE daylight of
/// that correlated colour temperature (on the 1968 Planck constant, T · 1.4388/1.4380), by the
/// CIE's closed form for its x and `y = −3x² + 2.870x − 0.275`; below 4000 K, where the D series
/// is not defined, a black body's (of that correlated temperature, as pbrt's `Spectra::D`).
pub fn white_chromaticity(kelvin: f32) -> [f32; 2] {
    match crate::math::spectrum::daylight_chromaticity(kelvin) {
        Some(xy) => xy.map(|c| c as f32),
        None => {
            // Below 4000 K `daylight` is the black body.
            let xyz = crate::math::spectrum::spectrum_to_xyz(&daylight(kelvin));
            let s = xyz.x + xyz.y + xyz.z;
            [xyz.x / s, xyz.y / s]
        }
    }
}

/// The names of pbrt-v4's measured camera sensors, in its order.
pub fn camera_names() -> impl Iterator<Item = &'static str> {
    CAMERAS.iter().map(|c| c.0)
}

/// The camera sensor `name` (one of [`camera_names`]) white-balanced for CIE daylight of
/// `kelvin` (pbrt's `whitebalance`; pbrt-v4 uses 6500 K when a named sensor is given none), as a
/// matrix on linear sRGB samples; `None` for an unknown name. See the module's notes.
pub fn camera(name: &str, kelvin: f32) -> Option<Mat3> {
    Some(camera_fit(&camera_response(name)?, kelvin).1.as_mat3())
}

/// pbrt-v4's sensor RGB of a rendered linear sRGB sample for the camera `name` balanced for
/// `kelvin` (what its `maxcomponentvalue` clamps): `(RGB_from_XYZ · XYZ_from_sensor)⁻¹` times
/// [`camera`]'s matrix, the raw RGB whose image is the camera's output.
pub fn camera_sensor_basis(name: &str, kelvin: f32) -> Option<Mat3> {
    let (xyz_from_camera, output) = camera_fit(&camera_response(name)?, kelvin);
    Some((xyz_from_camera.inverse() * xyz_from_rgb().as_dmat3() * output).as_mat3())
}

/// The camera `name`'s r̄, ḡ, b̄ at a wavelength (nm): linear between the table's samples, zero
/// outside them.
fn camera_response(name: &str) -> Option<impl Fn(f32) -> [f64; 3]> {
    let (_, curves) = CAMERAS.iter().find(|c| c.0 == name)?;
    let tables: Vec<Vec<(f32, f32)>> = curves
        .iter()
        .map(|c| c.iter().enumerate().map(|(i, &v)| (CAMERA_LAMBDA_START + 10.0 * i as f32, v)).collect())
        .collect();
    Some(move |l| [0, 1, 2].map(|c| sample_at(&tables[c], l) as f64))
}

/// The outer product `u vᵀ`.
fn outer(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}

/// Spectra on pbrt-v4's integration grid: every nanometre from 360 to 830 nm (its
/// `Lambda_min`…`Lambda_max`, summed as pbrt sums).
struct Grid {
    /// x̄, ȳ, z̄ and D65 at each wavelength.
    cie: Vec<[f64; 4]>,
    /// The camera's r̄, ḡ, b̄.
    camera: Vec<[f64; 3]>,
    /// The white-balance illuminant (CIE daylight).
    light: Vec<f64>,
    /// The swatches' reflectances, swatch by swatch.
    swatches: Vec<Vec<f64>>,
}

impl Grid {
    fn new(response: &dyn Fn(f32) -> [f64; 3], kelvin: f32) -> Grid {
        let lambdas: Vec<f32> = (360..=830).map(|l| l as f32).collect();
        let light = daylight(kelvin);
        let swatches = SWATCHES
            .iter()
            .map(|s| {
                let t: Vec<(f32, f32)> =
                    s.iter().enumerate().map(|(i, &v)| (SWATCH_LAMBDA_START + 10.0 * i as f32, v)).collect();
                lambdas.iter().map(|&l| sample_at(&t, l) as f64).collect()
            })
            .collect();
        Grid {
            cie: lambdas.iter().map(|&l| cie_xyz_d65(l).map(|v| v as f64)).collect(),
            camera: lambdas.iter().map(|&l| response(l)).collect(),
            light: lambdas.iter().map(|&l| sample_at(&light, l) as f64).collect(),
            swatches,
        }
    }

    /// `Σ_λ f(λ) · basis(λ)` for the three functions of `basis` (the CIE functions or the
    /// camera's curves), over the grid's wavelengths `k`.
    fn project(&self, f: impl Fn(usize) -> f64, basis: impl Fn(usize) -> [f64; 3]) -> DVec3 {
        (0..self.cie.len()).fold(DVec3::ZERO, |acc, k| acc + DVec3::from_array(basis(k)) * f(k))
    }

    fn xyz(&self, f: impl Fn(usize) -> f64) -> DVec3 {
        self.project(f, |k| [self.cie[k][0], self.cie[k][1], self.cie[k][2]])
    }

    fn raw(&self, f: impl Fn(usize) -> f64) -> DVec3 {
        self.project(f, |k| self.camera[k])
    }
}

/// The matrix M minimising `Σᵢ |M aᵢ − bᵢ|²` (pbrt's `LinearLeastSquares`).
fn least_squares(pairs: &[(DVec3, DVec3)]) -> DMat3 {
    let aa = pairs.iter().fold(DMat3::ZERO, |m, &(a, _)| m + outer(a, a));
    let ba = pairs.iter().fold(DMat3::ZERO, |m, &(a, b)| m + outer(b, a));
    ba * aa.inverse()
}

/// The fit for response curves `response` (per nanometre) and white balance `kelvin`: pbrt-v4's
/// `XYZFromSensorRGB` and neumann's matrix on linear sRGB (module notes).
fn camera_fit(response: &dyn Fn(f32) -> [f64; 3], kelvin: f32) -> (DMat3, DMat3) {
    let grid = Grid::new(response, kelvin);
    let d65 = |k: usize| grid.cie[k][3];
    let light = |k: usize| grid.light[k];
    // pbrt-v4: each swatch's camera RGB under the light, over the light's green; its XYZ under
    // the output space's illuminant (D65) over D65's Y, scaled by the light's Y over its green.
    let light_g = grid.raw(light).y;
    let light_y = grid.xyz(light).y;
    let d65_y = grid.xyz(d65).y;
    let pairs: Vec<(DVec3, DVec3)> = grid
        .swatches
        .iter()
        .map(|s| {
            let camera = grid.raw(|k| s[k] * light(k)) / light_g;
            let xyz = grid.xyz(|k| s[k] * d65(k)) / d65_y * (light_y / light_g);
            (camera, xyz)
        })
        .collect();
    let xyz_from_camera = least_squares(&pairs);
    // neumann: linear sRGB of a spectrum L (luminance-normalised by its illuminant), and what
    // pbrt's camera makes of L in the same space.
    let rgb_from_xyz = xyz_from_rgb().as_dmat3().inverse();
    let seen = |l: &dyn Fn(usize) -> f64, norm: f64| {
        let rendered = rgb_from_xyz * grid.xyz(l) / norm;
        let camera = rgb_from_xyz * xyz_from_camera * grid.raw(l) / norm;
        (rendered, camera)
    };
    let mut pairs = Vec::new();
    for illuminant in [&d65 as &dyn Fn(usize) -> f64, &light] {
        let norm = grid.xyz(illuminant).y;
        for s in &grid.swatches {
            pairs.push(seen(&|k| s[k] * illuminant(k), norm));
        }
    }
    let (white, white_out) = seen(&d65, d65_y);
    // Row by row: least squares under the constraint that D65's white maps exactly,
    // a = a₀ − G⁻¹w (w·a₀ − t) / (w·G⁻¹w) with G = Σ xxᵀ, a₀ = G⁻¹ Σ x yᵣ.
    let g_inv = pairs.iter().fold(DMat3::ZERO, |m, &(x, _)| m + outer(x, x)).inverse();
    let gw = g_inv * white;
    let rows: Vec<DVec3> = (0..3)
        .map(|r| {
            let a0 = g_inv * pairs.iter().fold(DVec3::ZERO, |acc, &(x, y)| acc + x * y[r]);
            a0 - gw * ((white.dot(a0) - white_out[r]) / white.dot(gw))
        })
        .collect();
    (xyz_from_camera, DMat3::from_cols(rows[0], rows[1], rows[2]).transpose())
}

impl SampleTransform {
    /// pbrt-v4's white balance from the white of `kelvin` to sRGB's D65, as a matrix on linear
    /// sRGB.
    pub fn white_balance(kelvin: f32) -> Mat3 {
        let b = bradford();
        let src = b * xyz_of(white_chromaticity(kelvin));
        let dst = b * xyz_of(D65_XY);
        let adapt = b.inverse() * Mat3::from_diagonal(dst / src) * b;
        let m = xyz_from_rgb();
        m.inverse() * adapt * m
    }

    /// Whether every sample passes unchanged.
    pub fn is_identity(&self) -> bool {
        self.matrix.is_none() && self.max_component == f32::INFINITY
    }

    /// The sample `l` after the colour matrix and the clamp.
    #[inline]
    pub fn apply(&self, l: Rgb) -> Rgb {
        let out = self.matrix.map_or(l, |m| m * l);
        let max = self.clamp_basis.map_or(out, |s| s * l).max_element();
        if max > self.max_component {
            out * (self.max_component / max)
        } else {
            out
        }
    }

    /// A Neumann-series term of the sample: the colour matrix only (the clamp is of the whole
    /// sample).
    #[inline]
    pub fn apply_linear(&self, l: Rgb) -> Rgb {
        self.matrix.map_or(l, |m| m * l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The adaptation takes the source white to D65's white (sRGB (1, 1, 1)), is near the
    /// identity at 6500 K (D65's temperature), and warms a scene lit by a cooler white (a higher
    /// temperature leaves more blue to remove).
    #[test]
    fn white_balance_maps_the_source_white_to_d65() {
        let m_rgb_xyz = xyz_from_rgb().inverse();
        for kelvin in [2700.0, 3500.0, 5000.0, 6500.0, 9000.0] {
            let wb = SampleTransform::white_balance(kelvin);
            let src_white_rgb = m_rgb_xyz * xyz_of(white_chromaticity(kelvin));
            let out = wb * src_white_rgb;
            assert!((out - Vec3::ONE).abs().max_element() < 2e-3, "{kelvin} K: {out}");
        }
        let d65 = SampleTransform::white_balance(6504.0);
        assert!((d65 - Mat3::IDENTITY).abs_diff_eq(Mat3::ZERO, 5e-3), "{d65}");
        let cool = SampleTransform::white_balance(9000.0) * Vec3::ONE;
        assert!(cool.z < cool.x, "balancing for a bluish white takes blue out: {cool}");
        // Daylight's x: 0.3457 near 5000 K (D50), 0.3127 near 6500 K (D65).
        let d50 = white_chromaticity(5000.0 * 1.4380 / 1.4388);
        assert!((d50[0] - 0.3457).abs() < 1e-3 && (d50[1] - 0.3586).abs() < 1e-3, "{d50:?}");
        // A black body below 4000 K: 2856 K is CIE illuminant A, (0.4476, 0.4074).
        let a = white_chromaticity(2856.0);
        assert!((a[0] - 0.4476).abs() < 2e-3 && (a[1] - 0.4074).abs() < 2e-3, "{a:?}");
    }

    /// For spectrum `spd` (per grid index): the linear sRGB neumann renders for it (CIE 1931,
    /// luminance `norm` → 1) and the sRGB pbrt's camera makes of it.
    fn seen(grid: &Grid, xyz_from_camera: DMat3, spd: &dyn Fn(usize) -> f64, norm: f64) -> (DVec3, DVec3) {
        let rgb_from_xyz = xyz_from_rgb().as_dmat3().inverse();
        (rgb_from_xyz * grid.xyz(spd) / norm, rgb_from_xyz * xyz_from_camera * grid.raw(spd) / norm)
    }

    /// A "camera" whose curves are the CIE functions, balanced for D65's temperature, is the
    /// identity (pbrt's fit gives XYZ back, neumann's matrix changes nothing); balanced for a
    /// warm or cool light it is a white balance: the light's white comes out white (within
    /// pbrt's least-squares fit), as under the Bradford adaptation of the `cie1931` sensor.
    #[test]
    fn a_cie_camera_is_the_identity_or_a_white_balance() {
        let cie = |l: f32| {
            let c = cie_xyz_d65(l);
            [c[0] as f64, c[1] as f64, c[2] as f64]
        };
        let (m, a) = camera_fit(&cie, 6504.0);
        assert!(m.abs_diff_eq(DMat3::IDENTITY, 2e-3), "{m}");
        assert!(a.abs_diff_eq(DMat3::IDENTITY, 2e-3), "{a}");
        for kelvin in [3000.0, 5000.0, 9000.0] {
            let (_, a) = camera_fit(&cie, kelvin);
            let grid = Grid::new(&cie, kelvin);
            let light = |k: usize| grid.light[k];
            let rgb_from_xyz = xyz_from_rgb().as_dmat3().inverse();
            let white = rgb_from_xyz * grid.xyz(light) / grid.xyz(light).y;
            let ours = a * white;
            assert!((ours - DVec3::ONE).abs().max_element() < 0.02, "{kelvin} K: the light's white becomes {ours}");
            // The Bradford adaptation makes it exactly white: both balance the light.
            let bradford = SampleTransform::white_balance(kelvin).as_dmat3() * white;
            assert!((bradford - DVec3::ONE).abs().max_element() < 2e-3, "{kelvin} K: {bradford}");
        }
    }

    /// Every named camera, balanced for a light, shows a white lit by it as nearly neutral
    /// (pbrt's fit is least squares, not exact at white), and its matrix reproduces what pbrt's
    /// spectral camera makes of the swatches (under D65 and the balanced light: the fit's own
    /// data; under illuminant A and a 2000 K black body: held out) and of black-body emitters
    /// (1500–10000 K), within the bounds below and closer than the CIE observer with the
    /// same white balance would (the image neumann would make if it ignored the camera). The
    /// table (`--nocapture`) is the README's accuracy study.
    #[test]
    fn camera_matrices_reproduce_the_spectral_pipeline() {
        let lambdas = || (360..=830).map(|l| l as f32);
        let tabulate = |t: Vec<(f32, f32)>| lambdas().map(|l| sample_at(&t, l) as f64).collect::<Vec<f64>>();
        let blackbody = |t: f32| tabulate(crate::math::spectrum::blackbody(t, false));
        // (mean, max) relative error over all cameras and balances: [fit, held out, emitters]
        // for neumann's matrix, then for the CIE observer's white balance.
        let (mut sum, mut worst, mut count) = ([[0.0f64; 3]; 2], [[0.0f64; 3]; 2], [0usize; 3]);
        for name in camera_names() {
            for kelvin in [2700.0f32, 5000.0, 6500.0, 9000.0] {
                let response = camera_response(name).expect("listed");
                let (m, a) = camera_fit(&response, kelvin);
                let bradford = SampleTransform::white_balance(kelvin).as_dmat3();
                let grid = Grid::new(&response, kelvin);
                let (_, white) = seen(&grid, m, &|k| grid.light[k], grid.xyz(|k| grid.light[k]).y);
                let spread = white.max_element() / white.min_element() - 1.0;
                assert!(spread < 0.05, "{name} at {kelvin} K: white under its light is {white}");
                let d65: Vec<f64> = grid.cie.iter().map(|c| c[3]).collect();
                let sets: [Vec<Vec<f64>>; 3] = [
                    vec![d65, grid.light.clone()],
                    vec![blackbody(2856.0), blackbody(2000.0)],
                    [1500.0, 2000.0, 3000.0, 4000.0, 6000.0, 10000.0].map(blackbody).to_vec(),
                ];
                let mut line = String::new();
                for (set, illuminants) in sets.iter().enumerate() {
                    // Swatches under each illuminant, or the emitters themselves.
                    let mut spds: Vec<Box<dyn Fn(usize) -> f64 + '_>> = Vec::new();
                    for e in illuminants {
                        if set == 2 {
                            spds.push(Box::new(move |k| e[k]));
                        } else {
                            spds.extend(
                                grid.swatches
                                    .iter()
                                    .map(|s| Box::new(move |k| s[k] * e[k]) as Box<dyn Fn(usize) -> f64>),
                            );
                        }
                    }
                    let mut local = [0.0f64; 2];
                    for spd in &spds {
                        let (rendered, truth) = seen(&grid, m, spd, grid.xyz(spd).y.abs().max(1e-30));
                        for (i, approx) in [a * rendered, bradford * rendered].into_iter().enumerate() {
                            let e = (approx - truth).length() / truth.length();
                            sum[i][set] += e;
                            worst[i][set] = worst[i][set].max(e);
                            local[i] = local[i].max(e);
                        }
                        count[set] += 1;
                    }
                    line += &format!("  {:5.1} % ({:5.1} %)", 100.0 * local[0], 100.0 * local[1]);
                }
                println!("{name:20} {kelvin:5} K:{line}");
            }
        }
        let mean = |i: usize| [0, 1, 2].map(|s| sum[i][s] / count[s] as f64);
        println!("mean: matrix {:?}, CIE observer {:?}", mean(0), mean(1));
        println!("max:  matrix {:?}, CIE observer {:?}", worst[0], worst[1]);
        // The matrix: mean errors of a few percent (metamerism: an RGB renderer cannot tell
        // spectra of one colour apart, which a camera can), below the CIE observer's.
        let (ours, cie) = (mean(0), mean(1));
        for s in 0..3 {
            assert!(ours[s] < 0.06 && worst[0][s] < 0.21, "set {s}: mean {} max {}", ours[s], worst[0][s]);
            assert!(ours[s] < 0.8 * cie[s], "set {s}: the matrix ({}) against the CIE observer ({})", ours[s], cie[s]);
        }
    }

    #[test]
    fn clamp_scales_the_largest_component_down() {
        let t = SampleTransform { max_component: 2.0, ..Default::default() };
        assert_eq!(t.apply(Rgb::new(4.0, 1.0, 0.0)), Rgb::new(2.0, 0.5, 0.0));
        assert_eq!(t.apply(Rgb::new(1.0, 1.0, 0.0)), Rgb::new(1.0, 1.0, 0.0));
        assert!(SampleTransform::default().is_identity() && !t.is_identity());
    }
}
