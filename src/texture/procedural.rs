//! pbrt-v4's procedural textures and texture mappings.
//!
//! - Mappings from the shading point to 2D texture coordinates (s, t) other than the surface's
//!   uv ([`Projection`]): `spherical` (s = θ/π, t = φ/2π of the point in texture space, θ from
//!   +z, φ from +x toward +y), `cylindrical` (s = (π + atan2(y, x))/2π, t = z) and `planar`
//!   (s = ds + p·v1, t = dt + p·v2), texture space being the space the texture was defined in
//!   (its `to_world`).
//! - Patterns ([`Procedural`]): `bilerp` (a bilinear patch of four values over (s, t)), polka
//!   `dots` (pbrt's: one dot of radius 0.35 per unit cell where the noise says so, its centre
//!   jittered by up to 0.15), the 3D checkerboard, and the noise textures `fbm`, `wrinkled`
//!   (turbulence), `windy` and `marble`, all in texture space (the point transformed by the
//!   inverse of the texture's `to_world`).
//!
//! Values are pbrt-v4's; where pbrt narrows noise sums to a pixel footprint, neumann sums
//! every octave (see [`super::noise`]).

use super::noise::{fbm, noise, turbulence};
use super::{Texture, TextureSource};
use crate::math::spectrum::SpectrumKind;
use crate::math::{Mat3, Mat4, Rgb, Vec2, Vec3};
use crate::props::{Obj, Result as PropResult};
use std::f32::consts::PI;

/// How a texture's 2D coordinates are computed from the shading point.
#[derive(Clone, Debug)]
pub enum Projection {
    /// The surface's uv after an affine map (homogeneous 2D; pbrt's `uscale`, `udelta`, …).
    Uv(Mat3),
    /// pbrt-v4's spherical mapping about texture space's origin: s = θ/π, t = φ/2π.
    Spherical {
        /// World → texture space.
        from_world: Mat4,
    },
    /// pbrt-v4's cylindrical mapping about texture space's z axis: s = (π + atan2(y, x))/2π,
    /// t = z.
    Cylindrical {
        /// World → texture space.
        from_world: Mat4,
    },
    /// pbrt-v4's planar mapping: s = ds + p·vs, t = dt + p·vt (p in texture space).
    Planar {
        /// World → texture space.
        from_world: Mat4,
        /// The s axis.
        vs: Vec3,
        /// The t axis.
        vt: Vec3,
        /// Offset of s.
        ds: f32,
        /// Offset of t.
        dt: f32,
    },
}

impl Projection {
    /// The (s, t) coordinates of the point `p` (world space) with surface coordinates `uv`.
    pub fn st(&self, uv: Vec2, p: Vec3) -> Vec2 {
        match self {
            Projection::Uv(m) => m.transform_point2(uv),
            Projection::Spherical { from_world } => {
                let v = from_world.transform_point3(p).normalize_or_zero();
                let theta = v.z.clamp(-1.0, 1.0).acos();
                let mut phi = v.y.atan2(v.x);
                if phi < 0.0 {
                    phi += 2.0 * PI;
                }
                Vec2::new(theta / PI, phi / (2.0 * PI))
            }
            Projection::Cylindrical { from_world } => {
                let q = from_world.transform_point3(p);
                Vec2::new((PI + q.y.atan2(q.x)) / (2.0 * PI), q.z)
            }
            Projection::Planar { from_world, vs, vt, ds, dt } => {
                let q = from_world.transform_point3(p);
                Vec2::new(ds + q.dot(*vs), dt + q.dot(*vt))
            }
        }
    }

    /// Whether (s, t) depends on the point's position (not only on its uv).
    pub fn uses_position(&self) -> bool {
        !matches!(self, Projection::Uv(_))
    }
}

/// A procedural pattern (closed set). 2D patterns are looked up at (s, t) — the uv a
/// [`Texture::Projected`] around them supplies —, 3D ones at the world point.
#[derive(Clone, Debug)]
pub enum Procedural {
    /// `(1−s)(1−t) v00 + (1−s) t v01 + s (1−t) v10 + s t v11`, values in the order
    /// `[v00, v01, v10, v11]`.
    Bilerp([Rgb; 4]),
    /// 1 inside one of pbrt-v4's polka dots at (s, t), 0 outside.
    PolkaDots,
    /// 1 where ⌊x⌋ + ⌊y⌋ + ⌊z⌋ of the texture-space point is odd, 0 where even.
    Checker3d {
        /// World → texture space.
        from_world: Mat4,
    },
    /// Fractional Brownian motion of Perlin noise (grey; about [−1, 1] for ω ≤ ½).
    Fbm {
        /// World → texture space.
        from_world: Mat4,
        /// Amplitude ratio of successive octaves (pbrt's `roughness`).
        omega: f32,
        /// Number of octaves.
        octaves: u32,
    },
    /// Turbulence (sum of |noise| octaves; grey, non-negative).
    Wrinkled {
        /// World → texture space.
        from_world: Mat4,
        /// Amplitude ratio of successive octaves.
        omega: f32,
        /// Number of octaves.
        octaves: u32,
    },
    /// pbrt's wind-swept waves: |fbm(p/10, ½, 3)| · fbm(p, ½, 6) (grey).
    Windy {
        /// World → texture space.
        from_world: Mat4,
    },
    /// pbrt's marble: a colour spline indexed by ½ + ½ sin(y + variation · fbm) of the scaled
    /// texture-space point.
    Marble {
        /// World → texture space.
        from_world: Mat4,
        /// Amplitude ratio of successive octaves.
        omega: f32,
        /// Number of octaves.
        octaves: u32,
        /// Frequency scale of the point.
        scale: f32,
        /// Amplitude of the noise's perturbation of the bands.
        variation: f32,
    },
}

/// Whether (s, t) lies in one of pbrt-v4's polka dots: each unit cell around integer (s, t)
/// holds a dot where the noise at its centre is positive, of radius 0.35, its centre shifted by
/// up to 0.15 along each axis by two more noise lookups.
pub fn in_polka_dot(st: Vec2) -> bool {
    let (sc, tc) = (crate::math::floor(st.x + 0.5), crate::math::floor(st.y + 0.5));
    if noise(Vec3::new(sc + 0.5, tc + 0.5, 0.5)) <= 0.0 {
        return false;
    }
    const RADIUS: f32 = 0.35;
    let shift = 0.5 - RADIUS;
    let centre = Vec2::new(
        sc + shift * noise(Vec3::new(sc + 1.5, tc + 2.8, 0.5)),
        tc + shift * noise(Vec3::new(sc + 4.5, tc + 9.8, 0.5)),
    );
    (st - centre).length_squared() < RADIUS * RADIUS
}

/// pbrt-v4's marble colours: nine control points of six cubic Bézier segments.
const MARBLE: [[f32; 3]; 9] = [
    [0.58, 0.58, 0.6],
    [0.58, 0.58, 0.6],
    [0.58, 0.58, 0.6],
    [0.5, 0.5, 0.5],
    [0.6, 0.59, 0.58],
    [0.58, 0.58, 0.6],
    [0.58, 0.58, 0.6],
    [0.2, 0.2, 0.33],
    [0.58, 0.58, 0.6],
];

/// The cubic Bézier curve of control points `c` at `t` ∈ [0, 1] (de Casteljau).
fn bezier(c: [Rgb; 4], t: f32) -> Rgb {
    let l = |a: Rgb, b: Rgb| a + (b - a) * t;
    let (a, b, d) = (l(c[0], c[1]), l(c[1], c[2]), l(c[2], c[3]));
    l(l(a, b), l(b, d))
}

/// The marble spline at `t` ∈ [0, 1], times 1.5 (pbrt-v4's).
pub fn marble_colour(t: f32) -> Rgb {
    let segments = MARBLE.len() - 3;
    let x = t.clamp(0.0, 1.0) * segments as f32;
    let first = (crate::math::floor(x) as usize).min(segments - 1);
    let c = |i: usize| Rgb::from_array(MARBLE[first + i]);
    1.5 * bezier([c(0), c(1), c(2), c(3)], x - first as f32)
}

impl Procedural {
    /// The value at texture coordinates `st` (2D patterns) or world point `p` (3D ones).
    pub fn eval(&self, st: Vec2, p: Vec3) -> Rgb {
        match self {
            Procedural::Bilerp([v00, v01, v10, v11]) => {
                let (s, t) = (st.x, st.y);
                *v00 * ((1.0 - s) * (1.0 - t)) + *v01 * ((1.0 - s) * t) + *v10 * (s * (1.0 - t)) + *v11 * (s * t)
            }
            Procedural::PolkaDots => Rgb::splat(if in_polka_dot(st) { 1.0 } else { 0.0 }),
            Procedural::Checker3d { from_world } => {
                let q = from_world.transform_point3(p).map(crate::math::floor);
                let odd = (q.x as i64).wrapping_add(q.y as i64).wrapping_add(q.z as i64).rem_euclid(2) == 1;
                Rgb::splat(if odd { 1.0 } else { 0.0 })
            }
            Procedural::Fbm { from_world, omega, octaves } => {
                Rgb::splat(fbm(from_world.transform_point3(p), *omega, *octaves))
            }
            Procedural::Wrinkled { from_world, omega, octaves } => {
                Rgb::splat(turbulence(from_world.transform_point3(p), *omega, *octaves))
            }
            Procedural::Windy { from_world } => {
                let q = from_world.transform_point3(p);
                Rgb::splat(fbm(0.1 * q, 0.5, 3).abs() * fbm(q, 0.5, 6))
            }
            Procedural::Marble { from_world, omega, octaves, scale, variation } => {
                let q = from_world.transform_point3(p) * *scale;
                let marble = q.y + variation * fbm(q, *omega, *octaves);
                marble_colour(0.5 + 0.5 * marble.sin())
            }
        }
    }

    /// Whether the value depends on the point's position (3D patterns).
    pub fn uses_position(&self) -> bool {
        !matches!(self, Procedural::Bilerp(_) | Procedural::PolkaDots)
    }

    /// Whether every value lies in [0, 1].
    pub fn is_reflectance(&self) -> bool {
        match self {
            Procedural::Bilerp(v) => v.iter().all(|c| c.min_element() >= 0.0 && c.max_element() <= 1.0),
            Procedural::PolkaDots | Procedural::Checker3d { .. } | Procedural::Marble { .. } => true,
            Procedural::Fbm { .. } | Procedural::Wrinkled { .. } | Procedural::Windy { .. } => false,
        }
    }

    /// The average value over the unit square (2D) or the unit cube of world space (3D), by a
    /// fixed 256-point rule: an estimate for sampling weights.
    pub fn mean(&self) -> Rgb {
        const N: usize = 256;
        // The R2/R3 low-discrepancy sequences (Roberts): deterministic and even.
        let (g2, g3) = (1.324_718_f32, 1.220_744_f32);
        let (a2, a3) = ([1.0 / g2, 1.0 / (g2 * g2)], [1.0 / g3, 1.0 / (g3 * g3), 1.0 / (g3 * g3 * g3)]);
        let frac = |x: f32| x - crate::math::floor(x);
        (0..N)
            .map(|i| {
                let k = i as f32 + 0.5;
                let st = Vec2::new(frac(k * a2[0]), frac(k * a2[1]));
                let p = Vec3::new(frac(k * a3[0]), frac(k * a3[1]), frac(k * a3[2]));
                self.eval(st, p)
            })
            .sum::<Rgb>()
            / N as f32
    }
}

/// A texture's 2D mapping from its properties: `mapping` (`uv`, the default; `spherical`,
/// `cylindrical`, `planar`), with `to_world` (texture space → world) for the projections and
/// `v1` ((1, 0, 0)), `v2` ((0, 1, 0)), `udelta`, `vdelta` (0) for `planar`. `None` for `uv`: the
/// texture reads the surface's uv (through its own `to_uv`).
pub fn projection_from_props(o: &Obj) -> PropResult<Option<Projection>> {
    let mapping = o.choice("mapping", &["uv", "spherical", "cylindrical", "planar"])?;
    if mapping == "uv" {
        return Ok(None);
    }
    let from_world = *o.transform("to_world")?.inverse_matrix();
    Ok(Some(match mapping.as_str() {
        "spherical" => Projection::Spherical { from_world },
        "cylindrical" => Projection::Cylindrical { from_world },
        _ => {
            let axis = |name: &str, default: Vec3| -> PropResult<Vec3> {
                let v = o.point_opt(name)?.unwrap_or(default);
                if !v.is_finite() {
                    return Err(o.error_at(name, format!("'{name}' must be finite")));
                }
                Ok(v)
            };
            Projection::Planar {
                from_world,
                vs: axis("v1", Vec3::X)?,
                vt: axis("v2", Vec3::Y)?,
                ds: o.float_checked("udelta", 0.0, f32::is_finite, "a number")?,
                dt: o.float_checked("vdelta", 0.0, f32::is_finite, "a number")?,
            }
        }
    }))
}

/// `texture` looked up through the 2D mapping `o` names (unchanged for `uv`); the texture's
/// own `to_uv` then applies to the (s, t) the mapping gives.
pub fn projected(o: &Obj, texture: Texture) -> PropResult<Texture> {
    Ok(match projection_from_props(o)? {
        None => texture,
        Some(projection) => Texture::Projected { projection, texture: Box::new(texture) },
    })
}

/// A 2D pattern under the mapping `o` names, its `to_uv` applied to the (s, t) the mapping
/// gives (to the surface's uv for `uv`).
fn pattern_2d(o: &Obj, pattern: Procedural) -> PropResult<Texture> {
    let inner = Texture::Projected {
        projection: Projection::Uv(super::to_uv_from_props(o)?),
        texture: Box::new(Texture::Procedural(pattern)),
    };
    projected(o, inner)
}

/// The inverse of a texture's `to_world` (texture space → world), as its 3D patterns need.
fn from_world(o: &Obj) -> PropResult<Mat4> {
    Ok(*o.transform("to_world")?.inverse_matrix())
}

/// Octave count (`octaves`, 8; 1–32) and amplitude ratio (`roughness`, 0.5; finite) of a noise
/// texture.
fn octaves(o: &Obj) -> PropResult<(u32, f32)> {
    let n = o.int("octaves", 8)?;
    if !(1..=32).contains(&n) {
        return Err(o.error_at("octaves", format!("'octaves' must be 1–32, got {n}")));
    }
    Ok((n as u32, o.float_checked("roughness", 0.5, f32::is_finite, "a number")?))
}

/// A pair of textures `tex1`, `tex2` (defaults `d1`, `d2`).
fn pair(o: &Obj, b: &mut dyn TextureSource, d1: f32, d2: f32) -> PropResult<Box<[Texture; 2]>> {
    let kind = SpectrumKind::Unbounded;
    Ok(Box::new([b.texture_of(o, "tex1", Rgb::splat(d1), kind)?, b.texture_of(o, "tex2", Rgb::splat(d2), kind)?]))
}

/// pbrt-v4's `mix`: `tex1` (0), `tex2` (1), `amount` (0.5), all texturable:
/// `(1 − amount) tex1 + amount tex2`, the amount's luminance where it is a colour.
pub fn mix_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    let tex = pair(o, b, 0.0, 1.0)?;
    let amount = Box::new(b.texture_of(o, "amount", Rgb::splat(0.5), SpectrumKind::Unbounded)?);
    Ok(Texture::Mix { amount, tex })
}

/// pbrt-v4's `directionmix`: `tex1` (0), `tex2` (1) texturable, `dir` ((0, 1, 0), in texture
/// space, `to_world` taking it to world): `a tex1 + (1 − a) tex2`, a = |n · dir| with n the
/// surface's geometric normal.
pub fn directionmix_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    let tex = pair(o, b, 0.0, 1.0)?;
    let dir = o.point_opt("dir")?.unwrap_or(Vec3::Y);
    let dir = o.transform("to_world")?.apply_vector(dir).normalize_or_zero();
    if dir == Vec3::ZERO || !dir.is_finite() {
        return Err(o.error_at("dir", "'dir' must be a non-zero finite vector"));
    }
    Ok(Texture::DirectionMix { dir, tex })
}

/// pbrt-v4's `bilerp`: `v00` (0), `v01` (1), `v10` (0), `v11` (1), colours, over the texture's
/// 2D mapping.
pub fn bilerp_from_props(o: &Obj, _: &mut dyn TextureSource) -> PropResult<Texture> {
    let kind = SpectrumKind::Unbounded;
    let v = |name: &str, d: f32| -> PropResult<Rgb> {
        let c = o.rgb_opt(name, kind)?.unwrap_or(Rgb::splat(d));
        if !c.is_finite() {
            return Err(o.error_at(name, format!("'{name}' must be finite")));
        }
        Ok(c)
    };
    pattern_2d(o, Procedural::Bilerp([v("v00", 0.0)?, v("v01", 1.0)?, v("v10", 0.0)?, v("v11", 1.0)?]))
}

/// pbrt-v4's `dots`: `inside` (1) in the polka dots, `outside` (0) elsewhere, both texturable
/// (looked up at the surface's own coordinates), dots over the texture's 2D mapping.
pub fn dots_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    let kind = SpectrumKind::Unbounded;
    let inside = b.texture_of(o, "inside", Rgb::ONE, kind)?;
    let outside = b.texture_of(o, "outside", Rgb::ZERO, kind)?;
    let amount = Box::new(pattern_2d(o, Procedural::PolkaDots)?);
    Ok(Texture::Mix { amount, tex: Box::new([outside, inside]) })
}

/// pbrt-v4's 3D `checkerboard` as neumann's `checkerboard3d`: `tex1` (1) where ⌊x⌋ + ⌊y⌋ + ⌊z⌋
/// of the texture-space point is even, `tex2` (0) where odd; `to_world`.
pub fn checkerboard3d_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    let tex = pair(o, b, 1.0, 0.0)?;
    let amount = Box::new(Texture::Procedural(Procedural::Checker3d { from_world: from_world(o)? }));
    Ok(Texture::Mix { amount, tex })
}

/// pbrt-v4's `fbm`: `octaves` (8), `roughness` (0.5), `to_world`.
pub fn fbm_from_props(o: &Obj, _: &mut dyn TextureSource) -> PropResult<Texture> {
    let (octaves, omega) = octaves(o)?;
    Ok(Texture::Procedural(Procedural::Fbm { from_world: from_world(o)?, omega, octaves }))
}

/// pbrt-v4's `wrinkled`: `octaves` (8), `roughness` (0.5), `to_world`.
pub fn wrinkled_from_props(o: &Obj, _: &mut dyn TextureSource) -> PropResult<Texture> {
    let (octaves, omega) = octaves(o)?;
    Ok(Texture::Procedural(Procedural::Wrinkled { from_world: from_world(o)?, omega, octaves }))
}

/// pbrt-v4's `windy`: `to_world`.
pub fn windy_from_props(o: &Obj, _: &mut dyn TextureSource) -> PropResult<Texture> {
    Ok(Texture::Procedural(Procedural::Windy { from_world: from_world(o)? }))
}

/// pbrt-v4's `marble`: `octaves` (8), `roughness` (0.5), `scale` (1), `variation` (0.2),
/// `to_world`.
pub fn marble_from_props(o: &Obj, _: &mut dyn TextureSource) -> PropResult<Texture> {
    let (octaves, omega) = octaves(o)?;
    let scale = o.float_checked("scale", 1.0, f32::is_finite, "a number")?;
    let variation = o.float_checked("variation", 0.2, f32::is_finite, "a number")?;
    Ok(Texture::Procedural(Procedural::Marble { from_world: from_world(o)?, omega, octaves, scale, variation }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::TexPoint;

    /// The three projections against their closed forms at hand-picked points.
    #[test]
    fn projections() {
        let id = Mat4::IDENTITY;
        let s = Projection::Spherical { from_world: id };
        // +y: θ = π/2, φ = π/2.
        assert!((s.st(Vec2::ZERO, Vec3::Y * 3.0) - Vec2::new(0.5, 0.25)).length() < 1e-6);
        // −z: θ = π; −y: φ = 3π/2.
        assert!((s.st(Vec2::ZERO, -Vec3::Z).x - 1.0).abs() < 1e-6);
        assert!((s.st(Vec2::ZERO, -Vec3::Y).y - 0.75).abs() < 1e-6);
        let c = Projection::Cylindrical { from_world: Mat4::from_translation(Vec3::new(0.0, 0.0, -1.0)) };
        // +x: atan2(0, 1) = 0 → s = ½; t = z − 1.
        assert!((c.st(Vec2::ZERO, Vec3::new(2.0, 0.0, 3.0)) - Vec2::new(0.5, 2.0)).length() < 1e-6);
        let p = Projection::Planar { from_world: id, vs: Vec3::X, vt: Vec3::Z, ds: 0.5, dt: -1.0 };
        assert!((p.st(Vec2::ZERO, Vec3::new(1.0, 7.0, 2.0)) - Vec2::new(1.5, 1.0)).length() < 1e-6);
        let uv = Projection::Uv(Mat3::from_scale(Vec2::new(2.0, 3.0)));
        assert_eq!(uv.st(Vec2::new(0.5, 0.5), Vec3::ZERO), Vec2::new(1.0, 1.5));
        assert!(!uv.uses_position() && s.uses_position());
    }

    #[test]
    fn bilerp_corners_and_centre() {
        let b = Procedural::Bilerp([Rgb::splat(0.0), Rgb::splat(1.0), Rgb::splat(2.0), Rgb::splat(4.0)]);
        let at = |s: f32, t: f32| b.eval(Vec2::new(s, t), Vec3::ZERO).x;
        assert_eq!((at(0.0, 0.0), at(0.0, 1.0), at(1.0, 0.0), at(1.0, 1.0)), (0.0, 1.0, 2.0, 4.0));
        assert!((at(0.5, 0.5) - 7.0 / 4.0).abs() < 1e-6);
        assert!((b.mean().x - 7.0 / 4.0).abs() < 0.02, "{}", b.mean());
    }

    /// Dots: about half the cells hold one (the noise's sign), each a disc of radius 0.35 whose
    /// centre stays within 0.15 of the cell's: area fraction ≈ ½ π 0.35² ≈ 0.19.
    #[test]
    fn polka_dots_cover_the_expected_area() {
        let n = 400;
        let mut inside = 0;
        for i in 0..n {
            for j in 0..n {
                let st = Vec2::new(i as f32 + 0.5, j as f32 + 0.5) * (40.0 / n as f32);
                if in_polka_dot(st) {
                    inside += 1;
                    // Inside a dot means within 0.35 + 0.15 of the cell centre.
                    let c = (st + Vec2::splat(0.5)).map(crate::math::floor);
                    assert!((st - c).length() < 0.5 + 1e-4, "{st}");
                }
            }
        }
        let fraction = inside as f32 / (n * n) as f32;
        let full = PI * 0.35 * 0.35;
        assert!(fraction > 0.3 * full && fraction < 0.7 * full, "dot area fraction {fraction} (full grid {full})");
    }

    #[test]
    fn checker3d_parity() {
        let c = Procedural::Checker3d { from_world: Mat4::from_scale(Vec3::splat(2.0)) };
        let at = |p: Vec3| c.eval(Vec2::ZERO, p).x;
        assert_eq!(at(Vec3::splat(0.1)), 0.0);
        assert_eq!(at(Vec3::new(0.6, 0.1, 0.1)), 1.0);
        assert_eq!(at(Vec3::new(0.6, 0.6, 0.1)), 0.0);
        assert_eq!(at(Vec3::new(-0.1, 0.1, 0.1)), 1.0, "negative cells");
    }

    /// The marble spline passes through its end control points and stays in their hull.
    #[test]
    fn marble_spline() {
        let first = Rgb::from_array(MARBLE[0]) * 1.5;
        let last = Rgb::from_array(MARBLE[8]) * 1.5;
        assert!((marble_colour(0.0) - first).abs().max_element() < 1e-6);
        assert!((marble_colour(1.0) - last).abs().max_element() < 1e-6);
        for i in 0..=600 {
            let c = marble_colour(i as f32 / 600.0);
            assert!(c.min_element() >= 0.2 * 1.5 - 1e-5 && c.max_element() <= 0.6 * 1.5 + 1e-5, "{c}");
        }
        // Without variation the bands are planes of constant y: ½ + ½ sin(scale · y).
        let plain =
            Procedural::Marble { from_world: Mat4::IDENTITY, omega: 0.5, octaves: 8, scale: 4.0, variation: 0.0 };
        let at = |m: &Procedural, p: Vec3| m.eval(Vec2::ZERO, p);
        for y in [0.1f32, 0.35, 0.8] {
            let v = at(&plain, Vec3::new(0.0, y, 0.0));
            assert!((at(&plain, Vec3::new(3.7, y, -1.2)) - v).abs().max_element() < 1e-6);
            assert!((v - marble_colour(0.5 + 0.5 * (4.0 * y).sin())).abs().max_element() < 1e-6);
        }
        // The noise bends them.
        let bent =
            Procedural::Marble { from_world: Mat4::IDENTITY, omega: 0.5, octaves: 8, scale: 4.0, variation: 2.0 };
        let differ = (0..50).filter(|i| {
            let y = 0.02 * *i as f32;
            (at(&bent, Vec3::new(0.0, y, 0.0)) - at(&bent, Vec3::new(1.3, y, 0.4))).abs().max_element() > 1e-3
        });
        assert!(differ.count() > 25);
    }

    /// Windy and wrinkled in texture space: moving the texture moves the pattern.
    #[test]
    fn noise_textures_follow_their_transform() {
        let shift = Vec3::new(3.0, -1.0, 0.5);
        let p = Vec3::new(0.37, 0.61, -0.2);
        for (a, b) in [
            (
                Procedural::Windy { from_world: Mat4::IDENTITY },
                Procedural::Windy { from_world: Mat4::from_translation(-shift) },
            ),
            (
                Procedural::Wrinkled { from_world: Mat4::IDENTITY, omega: 0.5, octaves: 8 },
                Procedural::Wrinkled { from_world: Mat4::from_translation(-shift), omega: 0.5, octaves: 8 },
            ),
        ] {
            assert!((a.eval(Vec2::ZERO, p) - b.eval(Vec2::ZERO, p + shift)).abs().max_element() < 1e-5);
            assert!(a.uses_position());
        }
        let w = Procedural::Wrinkled { from_world: Mat4::IDENTITY, omega: 0.5, octaves: 8 };
        assert!(w.eval(Vec2::ZERO, p).x > 0.0);
        let _ = TexPoint::at_uv(Vec2::ZERO);
    }
}
