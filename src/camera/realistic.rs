//! pbrt-v4's `realistic` camera: a lens system of spherical glass surfaces and an aperture stop
//! (Kolb, Mitchell and Hanrahan 1995), through which each camera ray is traced from a point on
//! the film to the scene, as pbrt-v4's `RealisticCamera` traces it.
//!
//! Lens space, as pbrt's: the film at z = 0, the scene toward −z, the rear element at
//! z = −(its thickness), the front one at z = −Σ thicknesses; camera space (pbrt's: +x right,
//! +y up, +z toward the scene) is lens space with z negated. All lengths in metres.
//!
//! A camera ray starts at the film point of the sample (the film is `diagonal` across, its
//! aspect the image's, and the image is inverted by the lens: film x is negated), aims at a
//! point sampled uniformly in a box bounding the *exit pupil* (the part of the rear element
//! through which light from that film point passes; 64 boxes by distance from the film's
//! centre, rotated to the point's azimuth), and is traced through every element; rays stopped by
//! an element's rim, the stop or total internal reflection carry nothing. The ray's weight is
//! pbrt-v4's `cos⁴θ / (p(pupil point) · z_rear²)` (θ from the axis on the film side, `p` the
//! density over the box, `z_rear` the film-to-rear-element distance), times the aperture
//! image's value at the stop where one is given: a pixel measures the irradiance on the film in
//! units of the radiance (pbrt-v4's film then scales it by its imaging ratio, as neumann's
//! pbrt reader scales the lights).

use crate::image::Image;
use crate::math::{Vec2, Vec3};

/// One refracting surface of a lens system, or its aperture stop (metres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensElement {
    /// Radius of curvature: > 0 for a surface whose centre lies behind it (toward the film), < 0
    /// for one whose centre lies in front; 0 marks the aperture stop (a plane).
    pub curvature_radius: f32,
    /// Distance along the axis to the next element toward the film (for the last: to the film).
    pub thickness: f32,
    /// Index of refraction of the medium behind the surface (toward the film); 0 or 1 is air.
    pub eta: f32,
    /// Radius of the element's clear aperture.
    pub aperture_radius: f32,
}

/// An aperture stop's shape and transmission: a square image over the stop's disk's bounding
/// square (pbrt-v4's `aperture`), read bilinearly, black outside, scaled so that its mean is
/// π/4 (a full disk's), so that its light matches a circular stop of the same radius.
#[derive(Clone, Debug, PartialEq)]
pub struct ApertureImage {
    width: usize,
    height: usize,
    /// Values row by row, the first row at the stop's −y edge (pbrt flips the image's rows).
    values: Vec<f32>,
}

/// Resolution of the built-in aperture shapes (pbrt-v4's).
const BUILTIN_RES: usize = 256;

/// Names of the built-in aperture shapes (anything else names an image file).
pub const BUILTIN_APERTURES: &[&str] = &["gaussian", "square", "pentagon", "star"];

impl ApertureImage {
    /// A built-in shape by its pbrt-v4 name: `gaussian` (exp(−r²) − exp(−1) over the disk),
    /// `square` (the middle half of each side), `pentagon` (a regular pentagon, 0.8 of the
    /// disk), `star` (a five-pointed star); `None` for another name.
    pub fn builtin(name: &str) -> Option<ApertureImage> {
        let res = BUILTIN_RES;
        let centre = |i: usize| -1.0 + 2.0 * (i as f32 + 0.5) / res as f32;
        let values: Vec<f32> = match name {
            "gaussian" => (0..res * res)
                .map(|k| {
                    let (x, y) = (centre(k % res), centre(k / res));
                    ((-(x * x + y * y)).exp() - (-1.0f32).exp()).max(0.0)
                })
                .collect(),
            "square" => (0..res * res)
                .map(|k| {
                    let inside = |i: usize| (res / 4..res * 3 / 4).contains(&i);
                    if inside(k % res) && inside(k / res) {
                        4.0
                    } else {
                        0.0
                    }
                })
                .collect(),
            "pentagon" => {
                let (c1, c2) = ((5f32.sqrt() - 1.0) / 4.0, (5f32.sqrt() + 1.0) / 4.0);
                let s1 = (10.0 + 2.0 * 5f32.sqrt()).sqrt() / 4.0;
                let s2 = (10.0 - 2.0 * 5f32.sqrt()).sqrt() / 4.0;
                let v = [
                    Vec2::new(0.0, 1.0),
                    Vec2::new(s1, c1),
                    Vec2::new(s2, -c2),
                    Vec2::new(-s2, -c2),
                    Vec2::new(-s1, c1),
                ];
                rasterize(&v.map(|p| p * 0.8), res)
            }
            "star" => {
                let inner = 72f32.to_radians().cos() / 36f32.to_radians().cos();
                let mut v: Vec<Vec2> = (0..10)
                    .map(|i| {
                        let r = if i % 2 == 1 { 1.0 } else { inner };
                        let a = std::f32::consts::PI * i as f32 / 5.0;
                        Vec2::new(r * a.cos(), r * a.sin())
                    })
                    .collect();
                v.reverse();
                rasterize(&v, res)
            }
            _ => return None,
        };
        Some(ApertureImage::normalised(res, res, values))
    }

    /// An aperture from an image (its red, green and blue averaged, as pbrt-v4 does); an error
    /// for an image whose mean is not positive.
    pub fn from_image(image: &Image) -> Result<ApertureImage, String> {
        let values = image.pixels.iter().map(|p| (p.x + p.y + p.z) / 3.0).collect();
        let a = ApertureImage::normalised(image.width as usize, image.height as usize, values);
        if a.values.iter().all(|v| v.is_finite()) && a.values.iter().any(|&v| v > 0.0) {
            Ok(a)
        } else {
            Err("the aperture image must have a positive mean and finite values".into())
        }
    }

    /// Rows flipped (pbrt's `FlipY`) and values scaled to mean π/4.
    fn normalised(width: usize, height: usize, values: Vec<f32>) -> ApertureImage {
        let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / (width * height) as f64;
        let scale = (std::f64::consts::FRAC_PI_4 / mean) as f32;
        let values = values.chunks(width).rev().flatten().map(|v| v * scale).collect();
        ApertureImage { width, height, values }
    }

    /// The bilinear value at `uv` ∈ [0, 1]² (black outside), pbrt's `BilerpChannel`.
    fn bilerp(&self, uv: Vec2) -> f32 {
        let (x, y) = (uv.x * self.width as f32 - 0.5, uv.y * self.height as f32 - 0.5);
        let (xi, yi) = (x.floor(), y.floor());
        let (dx, dy) = (x - xi, y - yi);
        let texel = |i: f32, j: f32| {
            if i >= 0.0 && j >= 0.0 && (i as usize) < self.width && (j as usize) < self.height {
                self.values[j as usize * self.width + i as usize]
            } else {
                0.0
            }
        };
        (1.0 - dx) * (1.0 - dy) * texel(xi, yi)
            + dx * (1.0 - dy) * texel(xi + 1.0, yi)
            + (1.0 - dx) * dy * texel(xi, yi + 1.0)
            + dx * dy * texel(xi + 1.0, yi + 1.0)
    }

    /// The mean value (π/4 by construction).
    pub fn mean(&self) -> f32 {
        (self.values.iter().map(|&v| f64::from(v)).sum::<f64>() / self.values.len() as f64) as f32
    }
}

/// 1 inside the polygon `v`, 0 outside (non-zero winding), at the centres of a `res × res` grid
/// over [−1, 1]², rows by increasing y (pbrt-v4's rasterization of its aperture shapes).
fn rasterize(v: &[Vec2], res: usize) -> Vec<f32> {
    let centre = |i: usize| -1.0 + 2.0 * (i as f32 + 0.5) / res as f32;
    (0..res * res)
        .map(|k| {
            let p = Vec2::new(centre(k % res), centre(k / res));
            let mut winding = 0i32;
            for i in 0..v.len() {
                let (a, b) = (v[i], v[(i + 1) % v.len()]);
                let e = (p.x - a.x) * (b.y - a.y) - (p.y - a.y) * (b.x - a.x);
                if a.y <= p.y {
                    if b.y > p.y && e > 0.0 {
                        winding += 1;
                    }
                } else if b.y <= p.y && e < 0.0 {
                    winding -= 1;
                }
            }
            if winding == 0 {
                0.0
            } else {
                1.0
            }
        })
        .collect()
}

/// The numbers of a lens description file, as pbrt-v4's `ReadFloatFile` reads it: numbers
/// separated by white space, `#` starting a comment to the end of the line. An error names the
/// line of anything that is not a number.
pub fn parse_lens_file(text: &str) -> Result<Vec<f32>, String> {
    let mut values = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("");
        for token in line.split_whitespace() {
            let v: f32 = token.parse().map_err(|_| format!("line {}: '{token}' is not a number", n + 1))?;
            if !v.is_finite() {
                return Err(format!("line {}: '{token}' is not a finite number", n + 1));
            }
            values.push(v);
        }
    }
    if values.is_empty() {
        return Err("the lens file holds no numbers".into());
    }
    if values.len() % 4 != 0 {
        return Err(format!(
            "a lens file holds four numbers per element (curvature radius, thickness, index of refraction, aperture diameter; millimetres), read {}",
            values.len()
        ));
    }
    Ok(values)
}

/// Boxes bounding the exit pupil, by distance from the film's centre (pbrt-v4's count).
const PUPIL_BOXES: usize = 64;

/// Rear-element points tried per exit-pupil box. pbrt-v4 tries 2²⁰; fewer change only how
/// tightly the box fits (it is widened by two sample spacings, so it still holds the pupil),
/// hence the noise and not the expected image.
const PUPIL_SAMPLES: u32 = 1 << 16;

/// A lens system focused for a film: pbrt-v4's `RealisticCamera` without its transform.
#[derive(Clone, Debug)]
pub struct LensSystem {
    /// Front (scene side) to rear; the last one's thickness is the film distance that focuses.
    elements: Vec<LensElement>,
    /// The film's diagonal (metres).
    diagonal: f32,
    /// Exit pupil bounds `[min x, min y, max x, max y]` in the rear element's plane, for film
    /// points on +x at distances `[k, k + 1) · diagonal / 2 / 64`; `None` where no ray passes.
    pupils: Vec<Option<[f32; 4]>>,
    /// The stop's shape, if not a disk.
    aperture: Option<ApertureImage>,
}

impl LensSystem {
    /// The lens of `values` (a lens file's numbers: per element its curvature radius, thickness,
    /// index of refraction and aperture diameter, millimetres, front to rear), its stop's
    /// diameter set to `aperture_diameter` (millimetres; clamped to the stop's own, with a
    /// warning returned, as pbrt-v4 does), focused at `focus_distance` (metres, from the film)
    /// by pbrt-v4's thick-lens approximation, for a film `diagonal` millimetres across.
    pub fn new(
        values: &[f32],
        aperture_diameter: f32,
        focus_distance: f32,
        diagonal: f32,
        aperture: Option<ApertureImage>,
    ) -> Result<(LensSystem, Option<String>), String> {
        if values.is_empty() || !values.len().is_multiple_of(4) {
            return Err("a lens needs four numbers per element".into());
        }
        if !(diagonal > 0.0 && diagonal.is_finite()) {
            return Err(format!("the film diagonal must be positive, got {diagonal} mm"));
        }
        if !(aperture_diameter > 0.0 && aperture_diameter.is_finite()) {
            return Err(format!("the aperture diameter must be positive, got {aperture_diameter} mm"));
        }
        if !(focus_distance > 0.0 && focus_distance.is_finite()) {
            return Err(format!("the focus distance must be positive, got {focus_distance}"));
        }
        let mut warning = None;
        let mut elements = Vec::with_capacity(values.len() / 4);
        for (k, e) in values.chunks(4).enumerate() {
            let (radius, thickness, eta, mut diameter) = (e[0] / 1000.0, e[1] / 1000.0, e[2], e[3] / 1000.0);
            if !(thickness >= 0.0 && eta >= 0.0 && diameter > 0.0) {
                return Err(format!(
                    "lens element {}: needs a thickness ≥ 0, an index of refraction ≥ 0 and an aperture diameter > 0, got {}, {} and {}",
                    k + 1,
                    e[1],
                    e[2],
                    e[3]
                ));
            }
            if radius == 0.0 {
                let wanted = aperture_diameter / 1000.0;
                if wanted > diameter {
                    warning = Some(format!(
                        "the aperture diameter {aperture_diameter} mm is greater than the lens's largest, {} mm: clamped to it (as pbrt-v4)",
                        e[3]
                    ));
                } else {
                    diameter = wanted;
                }
            }
            elements.push(LensElement { curvature_radius: radius, thickness, eta, aperture_radius: diameter / 2.0 });
        }
        let mut lens = LensSystem { elements, diagonal: diagonal / 1000.0, pupils: Vec::new(), aperture };
        let film_distance = lens.focus_thick_lens(focus_distance)?;
        if !(film_distance > 0.0 && film_distance.is_finite()) {
            return Err(format!(
                "the lens cannot focus at {focus_distance}: the film would sit {film_distance} m behind its rear element"
            ));
        }
        lens.elements.last_mut().expect("at least one element").thickness = film_distance;
        lens.pupils = lens.exit_pupils();
        if lens.pupils.iter().all(Option::is_none) {
            return Err("no ray from the film passes through the lens (is its aperture stop too small?)".into());
        }
        Ok((lens, warning))
    }

    /// The elements, front to rear (the last one's thickness focused).
    pub fn elements(&self) -> &[LensElement] {
        &self.elements
    }

    /// Distance from the film to the rear element.
    fn rear_z(&self) -> f32 {
        self.elements.last().map_or(0.0, |e| e.thickness)
    }

    /// Distance from the film to the front element.
    fn front_z(&self) -> f32 {
        self.elements.iter().map(|e| e.thickness).sum()
    }

    /// The camera-space ray (origin on the front element, unit direction) and its weight for
    /// film position `film` (pixels) of a `size` film and pupil sample `u`; `None` where the
    /// pupil box is empty or the lens stops the ray.
    pub fn ray(&self, film: Vec2, size: Vec2, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        let aspect = size.y / size.x;
        let x = (self.diagonal * self.diagonal / (1.0 + aspect * aspect)).sqrt();
        let extent = Vec2::new(x, aspect * x);
        let p = (film / size - Vec2::splat(0.5)) * extent;
        let p_film = Vec3::new(-p.x, p.y, 0.0);
        let (p_pupil, pdf) = self.sample_exit_pupil(Vec2::new(p_film.x, p_film.y), u)?;
        let d_film = p_pupil - p_film;
        let (o, d, transmission) = self.trace_from_film(p_film, d_film)?;
        let cos = d_film.normalize().z;
        let weight = transmission * (cos * cos) * (cos * cos) / (pdf * self.rear_z() * self.rear_z());
        let d = d.normalize();
        (weight.is_finite() && d.is_finite() && o.is_finite()).then_some((o, d, weight))
    }

    /// A point of the exit pupil box of film point `p` (rotated to its azimuth) and its density
    /// per unit area (pbrt-v4's `SampleExitPupil`).
    fn sample_exit_pupil(&self, p: Vec2, u: Vec2) -> Option<(Vec3, f32)> {
        let r = p.length();
        let k = ((r / (self.diagonal / 2.0) * PUPIL_BOXES as f32) as usize).min(PUPIL_BOXES - 1);
        let [x0, y0, x1, y1] = self.pupils[k]?;
        let q = Vec2::new(x0 + u.x * (x1 - x0), y0 + u.y * (y1 - y0));
        let pdf = 1.0 / ((x1 - x0) * (y1 - y0));
        let (sin, cos) = if r != 0.0 { (p.y / r, p.x / r) } else { (0.0, 1.0) };
        Some((Vec3::new(cos * q.x - sin * q.y, sin * q.x + cos * q.y, self.rear_z()), pdf))
    }

    /// Traces the camera-space ray (`o`, `d`) from the film through the elements, rear to front:
    /// the camera-space ray leaving the front element and the aperture image's transmission
    /// (1 without one), or `None` if an element's rim, the stop or total internal reflection
    /// stops it (pbrt-v4's `TraceLensesFromFilm`).
    fn trace_from_film(&self, o: Vec3, d: Vec3) -> Option<(Vec3, Vec3, f32)> {
        let (mut o, mut d) = (Vec3::new(o.x, o.y, -o.z), Vec3::new(d.x, d.y, -d.z));
        let (mut z, mut weight) = (0.0f32, 1.0f32);
        for i in (0..self.elements.len()).rev() {
            let e = &self.elements[i];
            z -= e.thickness;
            let stop = e.curvature_radius == 0.0;
            let (t, n) = hit_element(e, z, o, d)?;
            let p = o + d * t;
            match (&self.aperture, stop) {
                (Some(image), true) => {
                    let uv = (Vec2::new(p.x, p.y) / e.aperture_radius + Vec2::ONE) / 2.0;
                    weight = image.bilerp(uv);
                    if weight == 0.0 {
                        return None;
                    }
                }
                _ => {
                    if p.x * p.x + p.y * p.y > e.aperture_radius * e.aperture_radius {
                        return None;
                    }
                }
            }
            o = p;
            if !stop {
                let eta_i = air_if_zero(e.eta);
                let eta_t = if i > 0 { air_if_zero(self.elements[i - 1].eta) } else { 1.0 };
                d = refract(-d.normalize(), n, eta_t / eta_i)?;
            }
        }
        Some((Vec3::new(o.x, o.y, -o.z), Vec3::new(d.x, d.y, -d.z), weight))
    }

    /// Traces the camera-space ray (`o`, `d`) from the scene through the elements, front to
    /// rear, to the camera-space ray leaving the rear element (pbrt-v4's
    /// `TraceLensesFromScene`; the stop's disk, not its image).
    fn trace_from_scene(&self, o: Vec3, d: Vec3) -> Option<(Vec3, Vec3)> {
        let (mut o, mut d) = (Vec3::new(o.x, o.y, -o.z), Vec3::new(d.x, d.y, -d.z));
        let mut z = -self.front_z();
        for (i, e) in self.elements.iter().enumerate() {
            let stop = e.curvature_radius == 0.0;
            let (t, n) = hit_element(e, z, o, d)?;
            let p = o + d * t;
            if p.x * p.x + p.y * p.y > e.aperture_radius * e.aperture_radius {
                return None;
            }
            o = p;
            if !stop {
                let eta_i = if i == 0 { 1.0 } else { air_if_zero(self.elements[i - 1].eta) };
                let eta_t = air_if_zero(e.eta);
                d = refract(-d.normalize(), n, eta_t / eta_i)?;
            }
            z += e.thickness;
        }
        Some((Vec3::new(o.x, o.y, -o.z), Vec3::new(d.x, d.y, -d.z)))
    }

    /// The film distance (the last element's thickness) that focuses at `focus_distance`, from
    /// the principal planes and focal points of rays parallel to the axis traced both ways
    /// (pbrt-v4's `FocusThickLens`).
    fn focus_thick_lens(&self, focus_distance: f32) -> Result<f32, String> {
        let x = 0.001 * self.diagonal;
        let cardinal = |o_in: Vec3, (o, d): (Vec3, Vec3)| {
            let tf = -o.x / d.x;
            let tp = (o_in.x - o.x) / d.x;
            (-(o.z + tf * d.z), -(o.z + tp * d.z))
        };
        let o_scene = Vec3::new(x, 0.0, self.front_z() + 1.0);
        let through = self
            .trace_from_scene(o_scene, -Vec3::Z)
            .ok_or("a ray parallel to the axis does not pass through the lens from the scene (is its aperture stop extremely small?)")?;
        let (f0, p0) = cardinal(o_scene, through);
        let o_film = Vec3::new(x, 0.0, self.rear_z() - 1.0);
        let (o, d, _) = self
            .trace_from_film(o_film, Vec3::Z)
            .ok_or("a ray parallel to the axis does not pass through the lens from the film (is its aperture stop extremely small?)")?;
        let (_, p1) = cardinal(o_film, (o, d));
        if !(f0.is_finite() && p0.is_finite() && p1.is_finite()) {
            return Err("the lens does not bend rays parallel to its axis: it has no focal length to focus with".into());
        }
        let f = f0 - p0;
        let z = -focus_distance;
        let c = (p1 - z - p0) * (p1 - z - 4.0 * f - p0);
        if c.is_nan() || c <= 0.0 {
            return Err(format!("the focus distance {focus_distance} is too short for this lens (pbrt-v4's thick-lens focusing has no solution)"));
        }
        let delta = (p1 - z + p0 - c.sqrt()) / 2.0;
        Ok(self.rear_z() + delta)
    }

    /// The exit pupil's bounds for each of the 64 rings of the film (pbrt-v4's
    /// `BoundExitPupil`: rear-element points of a Halton sequence over 1.5 × the rear
    /// element's radius, kept where a ray from a film point of the ring passes; widened by two
    /// sample spacings), computed on every core.
    fn exit_pupils(&self) -> Vec<Option<[f32; 4]>> {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(PUPIL_BOXES);
        let mut pupils = vec![None; PUPIL_BOXES];
        let per = PUPIL_BOXES.div_ceil(threads);
        std::thread::scope(|s| {
            for (c, chunk) in pupils.chunks_mut(per).enumerate() {
                s.spawn(move || {
                    for (j, b) in chunk.iter_mut().enumerate() {
                        let k = c * per + j;
                        let r = |k: usize| k as f32 / PUPIL_BOXES as f32 * self.diagonal / 2.0;
                        *b = self.bound_exit_pupil(r(k), r(k + 1));
                    }
                });
            }
        });
        pupils
    }

    /// Bounds of the rear-element points through which rays from film points on +x between
    /// `x0` and `x1` pass.
    fn bound_exit_pupil(&self, x0: f32, x1: f32) -> Option<[f32; 4]> {
        let r = 1.5 * self.elements.last()?.aperture_radius;
        let n = PUPIL_SAMPLES;
        let mut b = [f32::INFINITY, f32::INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY];
        for i in 0..n {
            let t = (i as f32 + 0.5) / n as f32;
            let p_film = Vec3::new(x0 + t * (x1 - x0), 0.0, 0.0);
            let q = Vec2::new(-r + radical_inverse(2, i) * 2.0 * r, -r + radical_inverse(3, i) * 2.0 * r);
            let inside = q.x >= b[0] && q.x <= b[2] && q.y >= b[1] && q.y <= b[3];
            if !inside && self.trace_from_film(p_film, Vec3::new(q.x, q.y, self.rear_z()) - p_film).is_some() {
                b = [b[0].min(q.x), b[1].min(q.y), b[2].max(q.x), b[3].max(q.y)];
            }
        }
        if b[0] > b[2] || b[1] > b[3] {
            return None;
        }
        let widen = 2.0 * (2.0 * r * std::f32::consts::SQRT_2) / (n as f32).sqrt();
        Some([b[0] - widen, b[1] - widen, b[2] + widen, b[3] + widen])
    }
}

/// Where the lens-space ray (`o`, `d`) meets element `e` whose vertex lies at `z` on the axis:
/// its parameter and the unit normal facing the ray's origin side (zero for the stop, a plane);
/// `None` if it misses or the hit lies behind.
fn hit_element(e: &LensElement, z: f32, o: Vec3, d: Vec3) -> Option<(f32, Vec3)> {
    if e.curvature_radius == 0.0 {
        let t = (z - o.z) / d.z;
        return (t >= 0.0).then_some((t, Vec3::ZERO));
    }
    intersect_spherical_element(e.curvature_radius, z + e.curvature_radius, o, d)
}

/// An index of refraction of 0 (a lens file's mark of air next to the stop) as 1.
fn air_if_zero(eta: f32) -> f32 {
    if eta == 0.0 {
        1.0
    } else {
        eta
    }
}

/// The intersection of the ray (`o`, `d`) with the sphere of `radius` centred at (0, 0,
/// `z_centre`): the parameter of the hit on the element's side (the nearer one for a ray
/// travelling toward +z into a surface convex toward it, else the farther) and the unit normal
/// facing the ray's origin side; `None` if it misses or the hit lies behind.
fn intersect_spherical_element(radius: f32, z_centre: f32, o: Vec3, d: Vec3) -> Option<(f32, Vec3)> {
    let oc = o - Vec3::new(0.0, 0.0, z_centre);
    let (a, b) = (f64::from(d.dot(d)), 2.0 * f64::from(d.dot(oc)));
    let c = f64::from(oc.dot(oc)) - f64::from(radius) * f64::from(radius);
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 || a == 0.0 {
        return None;
    }
    let q = -0.5 * (b + disc.sqrt().copysign(b));
    let (t0, t1) = (q / a, c / q);
    let (t0, t1) = if t0 > t1 { (t1, t0) } else { (t0, t1) };
    let closer = (d.z > 0.0) ^ (radius < 0.0);
    let t = (if closer { t0 } else { t1 }) as f32;
    if t.is_nan() || t < 0.0 {
        return None;
    }
    let n = (oc + d * t).normalize();
    Some((t, if n.dot(-d) < 0.0 { -n } else { n }))
}

/// The direction refracted from the unit `wi` (pointing away from the surface) about the
/// normal `n`, for the relative index `eta` = η_t / η_i; `None` at total internal reflection
/// (pbrt-v4's `Refract`).
fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let (mut n, mut eta, mut cos_i) = (n, eta, n.dot(wi));
    if cos_i < 0.0 {
        (eta, cos_i, n) = (1.0 / eta, -cos_i, -n);
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    Some(-wi / eta + (cos_i / eta - cos_t) * n)
}

/// The radical inverse of `i` in `base` (the Halton sequence's coordinates), in [0, 1).
fn radical_inverse(base: u32, mut i: u32) -> f32 {
    let inv = 1.0 / f64::from(base);
    let (mut reversed, mut scale) = (0.0f64, inv);
    while i > 0 {
        reversed += f64::from(i % base) * scale;
        i /= base;
        scale *= inv;
    }
    (reversed as f32).min(crate::math::ONE_MINUS_EPSILON)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A biconvex singlet (R = ±50 mm, 6 mm of glass of index 1.5, f ≈ 51 mm) with the aperture
    /// stop behind it, last: the film sees the stop directly, so the light reaching a film point
    /// is a disk's form factor.
    const SINGLET: &str = "# radius thickness eta aperture (mm)\n50 6 1.5 30\n-50 2 1 30\n0 40 0 20 # the stop\n";

    fn singlet(aperture_mm: f32, focus: f32) -> LensSystem {
        let values = parse_lens_file(SINGLET).unwrap();
        LensSystem::new(&values, aperture_mm, focus, 35.0, None).unwrap().0
    }

    /// The mean weight of the rays of film position `film` (64 × 64 film) over `n`² stratified
    /// pupil samples (stopped rays weigh 0).
    fn mean_weight(lens: &LensSystem, film: Vec2, n: usize) -> f64 {
        let mut sum = 0.0;
        for k in 0..n * n {
            let u = Vec2::new(((k % n) as f32 + 0.5) / n as f32, ((k / n) as f32 + 0.5) / n as f32);
            sum += lens.ray(film, Vec2::splat(64.0), u).map_or(0.0, |r| f64::from(r.2));
        }
        sum / (n * n) as f64
    }

    /// `∫ z² / (z² + |q − p|²)² dA` over the disk of radius `a` about the axis: the irradiance a
    /// film point at `p` (distance `z` from the stop's plane) receives through the stop from
    /// unit radiance, by midpoint quadrature in polar coordinates.
    fn disk_form_factor(a: f64, z: f64, p: (f64, f64)) -> f64 {
        let n = 600;
        let mut sum = 0.0;
        for i in 0..n {
            let r = (i as f64 + 0.5) / n as f64 * a;
            for j in 0..n {
                let phi = (j as f64 + 0.5) / n as f64 * std::f64::consts::TAU;
                let (dx, dy) = (r * phi.cos() - p.0, r * phi.sin() - p.1);
                let d2 = z * z + dx * dx + dy * dy;
                sum += z * z / (d2 * d2) * r;
            }
        }
        sum * (a / n as f64) * (std::f64::consts::TAU / n as f64)
    }

    #[test]
    fn lens_files_read_as_pbrt_reads_them() {
        assert_eq!(
            parse_lens_file("# a comment\n1 2\t3 4 # more\n\n-5e1 0 0 7").unwrap(),
            vec![1.0, 2.0, 3.0, 4.0, -50.0, 0.0, 0.0, 7.0]
        );
        let e = parse_lens_file("1 2 3 4\n5 6 x 8\n").unwrap_err();
        assert!(e.contains("line 2") && e.contains("'x'"), "{e}");
        let e = parse_lens_file("1 2 3 4 5\n").unwrap_err();
        assert!(e.contains("four numbers per element") && e.contains("read 5"), "{e}");
        assert!(parse_lens_file("# nothing\n").unwrap_err().contains("no numbers"));
        assert!(parse_lens_file("1 2 3 inf").unwrap_err().contains("finite"));
    }

    #[test]
    fn the_film_centre_sees_the_stop_disk() {
        // The form factor of the stop's disk seen from the film's centre: π a² / (z² + a²).
        let lens = singlet(10.0, 10.0);
        let (a, z) = (0.005f64, f64::from(lens.rear_z()));
        assert!((0.045..0.06).contains(&z), "a 51 mm lens focused at 10 m: film {z} m behind the stop");
        let want = std::f64::consts::PI * a * a / (z * z + a * a);
        let got = mean_weight(&lens, Vec2::splat(32.0), 128);
        assert!((got / want - 1.0).abs() < 2e-3, "{got} vs {want}");
        // The stop clamped to its own diameter (20 mm), with a warning.
        let values = parse_lens_file(SINGLET).unwrap();
        let (wide, warning) = LensSystem::new(&values, 30.0, 10.0, 35.0, None).unwrap();
        assert!(warning.unwrap().contains("clamped"));
        assert_eq!(wide.elements()[2].aperture_radius, 0.01);
    }

    #[test]
    fn off_axis_film_points_see_the_stop_obliquely() {
        // Film points off the axis, in every quadrant (the pupil boxes are rotated to the
        // point's azimuth): the disk's form factor from there.
        let lens = singlet(10.0, 10.0);
        let (a, z) = (0.005f64, f64::from(lens.rear_z()));
        let aspect = 1.0f64;
        let x = (0.035f64 * 0.035 / (1.0 + aspect * aspect)).sqrt();
        for film in [Vec2::new(52.0, 20.0), Vec2::new(7.0, 60.0), Vec2::new(40.0, 3.0), Vec2::new(1.0, 1.0)] {
            let p = ((f64::from(film.x) / 64.0 - 0.5) * x, (f64::from(film.y) / 64.0 - 0.5) * x);
            // pbrt's film point has x negated (the lens inverts the image).
            let want = disk_form_factor(a, z, (-p.0, p.1));
            let got = mean_weight(&lens, film, 128);
            assert!((got / want - 1.0).abs() < 3e-3, "film {film}: {got} vs {want}");
        }
    }

    #[test]
    fn rays_from_a_film_point_meet_at_the_focus_distance() {
        // A small stop (paraxial rays): the rays from the film's centre cross the axis at the
        // focus distance from the film, not at half or twice it.
        for focus in [2.0f32, 10.0] {
            let lens = singlet(1.0, focus);
            let spread = |z: f32| {
                let (mut worst, mut passed) = (0.0f32, 0);
                for k in 0..64 {
                    let u = Vec2::new((k % 8) as f32 / 8.0 + 0.06, (k / 8) as f32 / 8.0 + 0.06);
                    // (The pupil box's corners lie outside the stop's disk.)
                    let Some((o, d, _)) = lens.ray(Vec2::splat(32.0), Vec2::splat(64.0), u) else { continue };
                    let q = o + d * ((z - o.z) / d.z);
                    worst = worst.max(q.x.hypot(q.y));
                    passed += 1;
                }
                assert!(passed > 32, "{passed} of 64 rays pass");
                worst
            };
            let at = spread(focus);
            assert!(at < 0.1 * spread(focus / 2.0) && at < 0.1 * spread(2.0 * focus), "focus {focus}: spread {at}");
        }
        // Too close to focus (inside the focal length), or nothing to focus with: errors.
        let values = parse_lens_file(SINGLET).unwrap();
        assert!(LensSystem::new(&values, 10.0, 0.05, 35.0, None).unwrap_err().contains("too short"));
        let flat = parse_lens_file("0 5 1.5 30\n0 40 0 20").unwrap();
        assert!(LensSystem::new(&flat, 10.0, 10.0, 35.0, None).unwrap_err().contains("no focal length"));
    }

    #[test]
    fn aperture_shapes_let_through_a_disks_light() {
        for name in BUILTIN_APERTURES {
            let a = ApertureImage::builtin(name).unwrap();
            assert!((a.mean() - std::f32::consts::FRAC_PI_4).abs() < 1e-4, "{name}: {}", a.mean());
        }
        assert!(ApertureImage::builtin("hexagon").is_none());
        // Covered fractions of [−1, 1]²: a regular pentagon of circumradius 0.8 (area
        // 2.5 sin 72° · 0.64), a five-pointed star of radii 1 and cos 72° / cos 36°.
        let covered = |name: &str| {
            let a = ApertureImage::builtin(name).unwrap();
            a.values.iter().filter(|&&v| v > 0.0).count() as f64 / a.values.len() as f64
        };
        let pentagon = 2.5 * 72f64.to_radians().sin() * 0.64 / 4.0;
        let inner = 72f64.to_radians().cos() / 36f64.to_radians().cos();
        let star = 5.0 * inner * 36f64.to_radians().sin() / 4.0;
        assert!((covered("pentagon") - pentagon).abs() < 0.005, "{} vs {pentagon}", covered("pentagon"));
        assert!((covered("star") - star).abs() < 0.005, "{} vs {star}", covered("star"));
        assert!((covered("square") - 0.25).abs() < 1e-9);
        // A square stop of half the disk's width, its value π: the film centre receives π times
        // the square's form factor.
        let values = parse_lens_file(SINGLET).unwrap();
        let square = ApertureImage::builtin("square");
        let lens = LensSystem::new(&values, 10.0, 10.0, 35.0, square).unwrap().0;
        let (h, z) = (0.0025f64, f64::from(lens.rear_z()));
        let n = 400;
        let mut want = 0.0;
        for k in 0..n * n {
            let x = -h + 2.0 * h * ((k % n) as f64 + 0.5) / n as f64;
            let y = -h + 2.0 * h * ((k / n) as f64 + 0.5) / n as f64;
            let d2 = z * z + x * x + y * y;
            want += z * z / (d2 * d2);
        }
        want *= std::f64::consts::PI * (2.0 * h / n as f64).powi(2);
        let got = mean_weight(&lens, Vec2::splat(32.0), 128);
        assert!((got / want - 1.0).abs() < 0.01, "{got} vs {want}");
    }

    #[test]
    fn the_image_is_upright_and_not_mirrored() {
        // Through the camera (camera space +x left, +y up): the film's left edge looks left and
        // its top looks up, as a perspective camera's do.
        let lens = singlet(10.0, 10.0);
        let cam = crate::camera::Camera::realistic(crate::math::Transform::IDENTITY, lens, 64, 64).unwrap();
        let pinhole = crate::camera::Camera::perspective(
            crate::math::Transform::IDENTITY,
            40.0,
            crate::camera::FovAxis::X,
            64,
            64,
        )
        .unwrap();
        for film in [Vec2::new(4.0, 32.0), Vec2::new(60.0, 32.0), Vec2::new(32.0, 4.0), Vec2::new(32.0, 60.0)] {
            let (ray, w) = cam.sample_ray(film, Vec2::splat(0.5));
            let p = pinhole.generate_ray(film, Vec2::ZERO);
            assert!(w > 0.0 && ray.d.z > 0.0);
            assert!(ray.d.x * p.d.x >= 0.0 && ray.d.y * p.d.y >= 0.0, "film {film}: {} vs {}", ray.d, p.d);
            assert!(ray.d.x.abs() + ray.d.y.abs() > 0.1, "film {film}: {}", ray.d);
        }
        // A ray the lens stops weighs nothing and has no length.
        let (ray, w) = cam.sample_ray(Vec2::splat(32.0), Vec2::new(0.999, 0.999));
        assert_eq!((w, ray.t_max), (0.0, 0.0));
    }
}
