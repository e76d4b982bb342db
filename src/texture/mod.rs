//! Textures: spatially varying parameters of materials, looked up at a surface point (its uv,
//! and for pbrt-v4's projections and 3D patterns its position and normal: [`TexPoint`]).
//!
//! Mitsuba 3's plugins: `bitmap` (an image; bilinear or nearest filtering; repeat, mirror or
//! clamp wrapping; sRGB-decoded unless `raw`), `checkerboard` (`color0`, `color1`),
//! `rawconstant` and constant values; pbrt-v4's `scale` (the product of two textures) and
//! neumann's `threshold` (a step of a texture's value), which glTF's materials need; pbrt-v4's
//! `mix`, `directionmix`, `bilerp`, `dots`, 3D checkerboard, `fbm`, `wrinkled`, `windy`, `marble`
//! and its spherical, cylindrical and planar mappings ([`procedural`], on Perlin's [`noise`]).
//! Every texture takes an optional `to_uv` 2D affine transform of the uv coordinates.
//! Image convention (Mitsuba 3's, checked against it): uv (0, 0) is the *top-left* corner of the
//! image (its first row) and v grows downward to the last row at v = 1. Mitsuba's OBJ loader flips
//! OBJ's v-up texture coordinates by default (`flip_tex_coords`), which the XML loader does too.

use crate::geometry::mesh::MeshPoint;
use crate::image::{Image, ImageSource, VolumeSource};
use crate::math::spectrum::SpectrumKind;
use crate::math::{floor, Mat3, Rgb, Vec2, Vec3};
use crate::props::{Obj, Result as PropResult};
use std::sync::Arc;

pub mod attributes;
pub mod blackbody;
pub mod cloud;
pub mod noise;
pub mod procedural;
pub mod volume;

pub use attributes::TextureAttributes;
pub use procedural::{Procedural, Projection};

/// Where a texture is looked up.
#[derive(Clone, Copy, Debug)]
pub struct TexPoint<'a> {
    /// Surface texture coordinates.
    pub uv: Vec2,
    /// Position (world space), for projections and 3D patterns.
    pub p: Vec3,
    /// Unit geometric normal (world space), for `directionmix`.
    pub n: Vec3,
    /// The mesh point, for `mesh_attribute` textures (None off meshes with attributes).
    pub mesh: Option<&'a MeshPoint<'a>>,
    /// The shape's texture attributes, which `mesh_attribute` textures read after the mesh's
    /// (None on shapes without them).
    pub textures: Option<&'a TextureAttributes>,
}

impl TexPoint<'_> {
    /// A lookup by texture coordinates alone (position at the origin, normal +z): right for
    /// every texture that does not [`Texture::uses_position`].
    pub fn at_uv(uv: Vec2) -> TexPoint<'static> {
        TexPoint { uv, p: Vec3::ZERO, n: Vec3::Z, mesh: None, textures: None }
    }
}

/// How lookups between texel centres are filtered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// Bilinear interpolation of the four nearest texels.
    Bilinear,
    /// The nearest texel.
    Nearest,
}

/// What happens outside [0, 1)².
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// Tile the image.
    Repeat,
    /// Tile with every other copy mirrored.
    Mirror,
    /// Repeat the edge texels.
    Clamp,
    /// Black (0) outside the image (pbrt-v4's `black` wrap; neumann's `wrap_mode` `black`).
    Black,
    /// pbrt-v4's `octahedralsphere`, for images in the equal-area octahedral layout: a texel
    /// beyond an edge is the one the sphere puts there (mirrored across that edge and across
    /// the middle of the other axis). Both axes together; neumann's `wrap_mode`
    /// `octahedral_sphere`.
    OctahedralSphere,
}

/// An image texture.
#[derive(Clone, Debug)]
pub struct Bitmap {
    /// The (linear RGB) image.
    pub image: Arc<Image>,
    /// Filtering.
    pub filter: Filter,
    /// Wrapping along u and along v (Mitsuba's `wrap_mode` sets both; glTF's samplers set
    /// each).
    pub wrap: [Wrap; 2],
}

/// A texture (closed set).
#[derive(Clone, Debug)]
pub enum Texture {
    /// The same value everywhere.
    Constant(Rgb),
    /// An image lookup after the uv transform.
    Bitmap {
        /// The image.
        bitmap: Bitmap,
        /// uv transform (homogeneous 2D affine).
        to_uv: Mat3,
    },
    /// Mitsuba's `mesh_attribute`: the named attribute of the mesh at the shading point
    /// (per-vertex values interpolated, or the triangle's), times `scale`.
    MeshAttribute {
        /// The attribute's name (`vertex_color`, `face_color`, …).
        name: String,
        /// A factor on the value.
        scale: f32,
    },
    /// A texture looked up at texture coordinates read from a mesh attribute instead of the
    /// surface's uv (glTF's second and later `TEXCOORD_n` sets, kept as the attributes
    /// `vertex_texcoordN`); the surface's uv where there is no mesh.
    AttributeUv {
        /// The attribute holding (u, v, 0) per vertex.
        attribute: String,
        /// The texture.
        texture: Box<Texture>,
    },
    /// The product of two textures (pbrt-v4's `scale` texture: `tex` × `scale`; glTF's factors
    /// times its textures times vertex colours).
    Scale(Box<[Texture; 2]>),
    /// 1 where the texture's scalar value (luminance) reaches `threshold`, else 0 (glTF's
    /// `alphaMode` `MASK` with its `alphaCutoff`).
    Threshold {
        /// The thresholded texture.
        texture: Box<Texture>,
        /// The least value that gives 1.
        threshold: f32,
    },
    /// Mitsuba's `checkerboard`: `color0` where the fractional parts of u and v (after `to_uv`)
    /// lie on the same side of 1/2, `color1` elsewhere; the colours are textures themselves,
    /// looked up at the untransformed point.
    Checkerboard {
        /// First colour.
        color0: Box<Texture>,
        /// Second colour.
        color1: Box<Texture>,
        /// uv transform.
        to_uv: Mat3,
    },
    /// A texture looked up at the (s, t) a projection computes from the point, as its uv
    /// (pbrt-v4's 2D mappings; the uv mapping of 2D patterns).
    Projected {
        /// The mapping.
        projection: Projection,
        /// The texture.
        texture: Box<Texture>,
    },
    /// pbrt-v4's `mix`: `(1 − a) tex[0] + a tex[1]`, `a` the luminance of `amount`'s value
    /// (its colour lookup, so that a checkerboard amount keeps its colour order).
    Mix {
        /// The blend amount.
        amount: Box<Texture>,
        /// The two textures.
        tex: Box<[Texture; 2]>,
    },
    /// pbrt-v4's `directionmix`: `a tex[0] + (1 − a) tex[1]`, `a = |n · dir|` with `n` the
    /// geometric normal.
    DirectionMix {
        /// Unit direction (world space).
        dir: Vec3,
        /// The two textures.
        tex: Box<[Texture; 2]>,
    },
    /// A procedural pattern (2D ones at the uv, 3D ones at the position).
    Procedural(Procedural),
    /// The square root of a texture's value per channel (of its scalar as a scalar; negative
    /// values give 0): pbrt-v4's roughness remapping α = √roughness of a textured roughness.
    Sqrt(Box<Texture>),
    /// One minus a texture's value per channel, negative results giving 0 (of its scalar as a
    /// scalar): pbrt-v4's `invert` of image textures, `max(0, 1 − scale · v)`.
    Invert(Box<Texture>),
    /// pbrt-v4's conductor of a given reflectance r at normal incidence: the extinction
    /// `k = 2√r / √(1 − r)` (with η = 1) of a texture's value per channel, r clamped to
    /// [0, 0.9999] (of its scalar as a scalar).
    ConductorK(Box<Texture>),
    /// Mitsuba's `volume`: a volume texture ([`volume::Volume`]: `gridvolume`, `constvolume`)
    /// looked up at the point's world position; its scalar is the mean of its channels, as
    /// Mitsuba's `eval_1`.
    Volume(Arc<volume::Volume>),
}

impl Texture {
    /// A checkerboard of two colours (or textures) after the uv transform `to_uv`.
    pub fn checkerboard(color0: impl Into<Texture>, color1: impl Into<Texture>, to_uv: Mat3) -> Texture {
        Texture::Checkerboard { color0: Box::new(color0.into()), color1: Box::new(color1.into()), to_uv }
    }

    /// The product of two textures per channel (pbrt-v4's `scale`): a constant when both are.
    pub fn times(self, other: Texture) -> Texture {
        match (self, other) {
            (Texture::Constant(a), Texture::Constant(b)) => Texture::Constant(a * b),
            (a, b) => Texture::Scale(Box::new([a, b])),
        }
    }

    /// Whether `uv` lies in a `color0` cell of a checkerboard with uv transform `to_uv`.
    #[inline]
    fn checker_cell0(to_uv: &Mat3, uv: Vec2) -> bool {
        let p = to_uv.transform_point2(uv);
        let (fu, fv) = (p.x - floor(p.x), p.y - floor(p.y));
        (fu > 0.5) == (fv > 0.5)
    }
}

/// A texel index from a whole number of texels: the number itself within ±2⁶², beyond it the
/// nearest bound, so that the neighbours, mirrors and wraps of an index computed from it never
/// overflow (a lookup at a coordinate near f32's limits, where no texel is meant anyway).
#[inline]
fn texel_index(x: f32) -> i64 {
    (x as i64).clamp(-(1 << 62), 1 << 62)
}

/// The texture coordinates the mesh attribute `attribute` holds at `mesh` (its x and y), or `uv`.
#[inline]
fn attribute_uv(attribute: &str, uv: Vec2, mesh: Option<&MeshPoint>) -> Vec2 {
    mesh.and_then(|m| m.attribute(attribute)).map_or(uv, |v| Vec2::new(v.x, v.y))
}

impl From<Rgb> for Texture {
    fn from(c: Rgb) -> Texture {
        Texture::Constant(c)
    }
}

impl Bitmap {
    fn texel(&self, x: i64, y: i64) -> Rgb {
        if self.octahedral() {
            return self.octahedral_texel(x, y);
        }
        self.wrapped_texel(self.wrap_index(x, 0), self.wrap_index(y, 1))
    }

    /// Whether either axis wraps octahedrally (which couples the axes: [`Bitmap::octahedral_texel`]).
    #[inline]
    fn octahedral(&self) -> bool {
        self.wrap[0] == Wrap::OctahedralSphere || self.wrap[1] == Wrap::OctahedralSphere
    }

    /// Texel index `i` along `axis` after that axis's wrap (not octahedral): `None` outside a
    /// black border. Indices inside the image are their own wrap in every mode.
    #[inline]
    fn wrap_index(&self, i: i64, axis: usize) -> Option<i64> {
        let n = if axis == 0 { self.image.width } else { self.image.height } as i64;
        if (0..n).contains(&i) {
            return Some(i);
        }
        match self.wrap[axis] {
            Wrap::Repeat => Some(i.rem_euclid(n)),
            Wrap::Clamp => Some(i.clamp(0, n - 1)),
            Wrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                Some(if m < n { m } else { 2 * n - 1 - m })
            }
            Wrap::Black => None,
            // Not reached (octahedral images take `octahedral_texel`): the nearest texel.
            Wrap::OctahedralSphere => Some(i.clamp(0, n - 1)),
        }
    }

    /// The texel at wrapped indices, black where either is outside a black border.
    #[inline]
    fn wrapped_texel(&self, x: Option<i64>, y: Option<i64>) -> Rgb {
        // Row 0 of the image is its top: v = 0.
        match (x, y) {
            (Some(i), Some(j)) => self.image.get(i, j),
            _ => Rgb::ZERO,
        }
    }

    /// Texel `(x, y)` with pbrt-v4's octahedral-sphere wrap (its `RemapPixelCoords`): beyond
    /// the left or right edge, mirrored across it and across the middle row; beyond the top or
    /// bottom, mirrored across it and across the middle column.
    fn octahedral_texel(&self, mut x: i64, mut y: i64) -> Rgb {
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        if x < 0 {
            (x, y) = (-x, h - 1 - y);
        } else if x >= w {
            (x, y) = (2 * w - 1 - x, h - 1 - y);
        }
        if y < 0 {
            (x, y) = (w - 1 - x, -y);
        } else if y >= h {
            (x, y) = (w - 1 - x, 2 * h - 1 - y);
        }
        // Far outside (not a bilinear neighbour) or a one-texel axis: the nearest texel.
        self.image.get(x.clamp(0, w - 1), y.clamp(0, h - 1))
    }

    /// The bilinear cell holding `uv`: the texel whose centre is its lower corner, and `uv`'s
    /// position in the cell.
    #[inline]
    fn bilinear_cell(&self, uv: Vec2) -> (i64, i64, f32, f32) {
        let (x, y) = (uv.x * self.image.width as f32 - 0.5, uv.y * self.image.height as f32 - 0.5);
        let (x0, y0) = (floor(x), floor(y));
        (texel_index(x0), texel_index(y0), x - x0, y - y0)
    }

    /// The filtered value at `uv` (v down the rows).
    pub fn eval(&self, uv: Vec2) -> Rgb {
        match self.filter {
            Filter::Nearest => {
                let (w, h) = (self.image.width as f32, self.image.height as f32);
                self.texel(texel_index(floor(uv.x * w)), texel_index(floor(uv.y * h)))
            }
            Filter::Bilinear => {
                let (x0, y0, fx, fy) = self.bilinear_cell(uv);
                let [t00, t10, t01, t11] = if self.octahedral() {
                    [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| self.octahedral_texel(x0 + dx, y0 + dy))
                } else {
                    // Each axis wrapped once for the two texels along it.
                    let (xa, xb) = (self.wrap_index(x0, 0), self.wrap_index(x0 + 1, 0));
                    let (ya, yb) = (self.wrap_index(y0, 1), self.wrap_index(y0 + 1, 1));
                    [(xa, ya), (xb, ya), (xa, yb), (xb, yb)].map(|(x, y)| self.wrapped_texel(x, y))
                };
                t00 * ((1.0 - fx) * (1.0 - fy)) + t10 * (fx * (1.0 - fy)) + t01 * ((1.0 - fx) * fy) + t11 * (fx * fy)
            }
        }
    }
}

impl Texture {
    /// The value at surface coordinates `uv` (0 for a `mesh_attribute`, which needs a mesh
    /// point, and the origin's value for textures that [`Texture::uses_position`]: those need
    /// [`Texture::eval_at`]).
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        self.eval_at(&TexPoint::at_uv(uv))
    }

    /// The value at the surface point `at`.
    pub fn eval_at(&self, at: &TexPoint) -> Rgb {
        let uv = at.uv;
        match self {
            Texture::MeshAttribute { name, scale } => at
                .mesh
                .and_then(|m| m.attribute(name))
                .or_else(|| at.textures.and_then(|t| t.eval(name, at)))
                .map_or(Rgb::ZERO, |v| v * *scale),
            Texture::Constant(c) => *c,
            Texture::Bitmap { bitmap, to_uv } => bitmap.eval(to_uv.transform_point2(uv)),
            Texture::Scale(t) => t[0].eval_at(at) * t[1].eval_at(at),
            Texture::AttributeUv { attribute, texture } => {
                texture.eval_at(&TexPoint { uv: attribute_uv(attribute, uv, at.mesh), ..*at })
            }
            Texture::Threshold { texture, threshold } => {
                Rgb::splat(if texture.eval_scalar(at) >= *threshold { 1.0 } else { 0.0 })
            }
            Texture::Checkerboard { color0, color1, to_uv } => {
                if Texture::checker_cell0(to_uv, uv) {
                    color0.eval_at(at)
                } else {
                    color1.eval_at(at)
                }
            }
            Texture::Projected { projection, texture } => {
                texture.eval_at(&TexPoint { uv: projection.st(uv, at.p), ..*at })
            }
            Texture::Mix { tex, .. } | Texture::DirectionMix { tex, .. } => {
                Self::blend(self.mix_weight(at), tex, |t| t.eval_at(at))
            }
            Texture::Procedural(p) => p.eval(uv, at.p),
            Texture::Sqrt(t) => t.eval_at(at).max(Rgb::ZERO).powf(0.5),
            Texture::Invert(t) => (Rgb::ONE - t.eval_at(at)).max(Rgb::ZERO),
            Texture::ConductorK(t) => t.eval_at(at).map(conductor_k),
            Texture::Volume(v) => v.eval(at.p),
        }
    }

    /// The weight of `tex[1]` of a `Mix` (the luminance of its amount) or a `DirectionMix`
    /// (1 − |n · dir|) at `at`; 0 for other textures.
    #[inline]
    fn mix_weight(&self, at: &TexPoint) -> f32 {
        match self {
            Texture::Mix { amount, .. } => crate::math::luminance(amount.eval_at(at)),
            Texture::DirectionMix { dir, .. } => 1.0 - at.n.dot(*dir).abs().min(1.0),
            _ => 0.0,
        }
    }

    /// `(1 − a) f(tex[0]) + a f(tex[1])`, looking up only the textures with non-zero weight
    /// (as pbrt-v4 does).
    #[inline]
    fn blend<T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>>(
        a: f32,
        tex: &[Texture; 2],
        f: impl Fn(&Texture) -> T,
    ) -> T {
        if a == 0.0 {
            f(&tex[0]) * 1.0
        } else if a == 1.0 {
            f(&tex[1]) * 1.0
        } else {
            f(&tex[0]) * (1.0 - a) + f(&tex[1]) * a
        }
    }

    /// The texture as a scalar (roughness, blend weight, opacity): the luminance of its value,
    /// as Mitsuba's `eval_1`. Measured against Mitsuba 3.9.1: its checkerboard's scalar lookup
    /// swaps the two colours relative to its colour lookup (`color1` where the fractional parts
    /// of u and v lie on the same side of ½), and so does this one, so that scenes render as
    /// there.
    pub fn eval_scalar(&self, at: &TexPoint) -> f32 {
        match self {
            // A mesh's attribute as a scalar is its luminance; a shape's texture attribute, its
            // own scalar lookup (Mitsuba's `eval_attribute_1`).
            Texture::MeshAttribute { name, scale } => match at.mesh.and_then(|m| m.attribute(name)) {
                Some(v) => crate::math::luminance(v * *scale),
                None => at.textures.and_then(|t| t.eval_scalar(name, at)).map_or(0.0, |v| v * scale),
            },
            Texture::Checkerboard { color0, color1, to_uv } => {
                if Texture::checker_cell0(to_uv, at.uv) {
                    color1.eval_scalar(at)
                } else {
                    color0.eval_scalar(at)
                }
            }
            Texture::AttributeUv { attribute, texture } => {
                texture.eval_scalar(&TexPoint { uv: attribute_uv(attribute, at.uv, at.mesh), ..*at })
            }
            Texture::Projected { projection, texture } => {
                texture.eval_scalar(&TexPoint { uv: projection.st(at.uv, at.p), ..*at })
            }
            Texture::Mix { tex, .. } | Texture::DirectionMix { tex, .. } => {
                Self::blend(self.mix_weight(at), tex, |t| t.eval_scalar(at))
            }
            Texture::Sqrt(t) => t.eval_scalar(at).max(0.0).sqrt(),
            Texture::Invert(t) => (1.0 - t.eval_scalar(at)).max(0.0),
            Texture::ConductorK(t) => conductor_k(t.eval_scalar(at)),
            Texture::Volume(v) => {
                let c = v.eval(at.p);
                (c.x + c.y + c.z) / 3.0
            }
            t => crate::math::luminance(t.eval_at(at)),
        }
    }

    /// Whether the value depends on the point's position or normal (pbrt-v4's projections, 3D
    /// patterns, `directionmix`), so that a lookup by uv alone ([`Texture::eval`]) is not
    /// enough.
    pub fn uses_position(&self) -> bool {
        match self {
            Texture::Constant(_) | Texture::Bitmap { .. } | Texture::MeshAttribute { .. } => false,
            Texture::AttributeUv { texture, .. } | Texture::Threshold { texture, .. } => texture.uses_position(),
            Texture::Sqrt(t) | Texture::Invert(t) | Texture::ConductorK(t) => t.uses_position(),
            Texture::Scale(t) => t[0].uses_position() || t[1].uses_position(),
            Texture::Checkerboard { color0, color1, .. } => color0.uses_position() || color1.uses_position(),
            Texture::Projected { projection, texture } => projection.uses_position() || texture.uses_position(),
            Texture::Mix { amount, tex } => amount.uses_position() || tex[0].uses_position() || tex[1].uses_position(),
            Texture::DirectionMix { .. } | Texture::Volume(_) => true,
            Texture::Procedural(p) => p.uses_position(),
        }
    }

    /// The gradient `(∂f/∂u, ∂f/∂v)` of the texture as a scalar (its luminance) at `uv`, as
    /// Mitsuba's `eval_1_grad` computes it for a bitmap: the slopes of the bilinear interpolant
    /// in texels, taken through the transpose of the uv transform's linear part and scaled by
    /// the resolution (zero for nearest filtering). Other textures have no gradient (zero; the
    /// bump map, its only user, accepts bitmaps only).
    pub fn eval_scalar_grad(&self, uv: Vec2) -> Vec2 {
        let Texture::Bitmap { bitmap, to_uv } = self else { return Vec2::ZERO };
        if bitmap.filter == Filter::Nearest {
            return Vec2::ZERO;
        }
        let (x0, y0, fx, fy) = bitmap.bilinear_cell(to_uv.transform_point2(uv));
        let (w, h) = (bitmap.image.width as f32, bitmap.image.height as f32);
        let f = |dx: i64, dy: i64| crate::math::luminance(bitmap.texel(x0 + dx, y0 + dy));
        let (f00, f10, f01, f11) = (f(0, 0), f(1, 0), f(0, 1), f(1, 1));
        let dfx = (1.0 - fy) * (f10 - f00) + fy * (f11 - f01);
        let dfy = (1.0 - fx) * (f01 - f00) + fx * (f11 - f10);
        let m = to_uv;
        Vec2::new(m.x_axis.x * dfx + m.x_axis.y * dfy, m.y_axis.x * dfx + m.y_axis.y * dfy) * Vec2::new(w, h)
    }

    /// Average value (over the image, or the two checker colours).
    pub fn mean(&self) -> Rgb {
        match self {
            Texture::Constant(c) => *c,
            Texture::Bitmap { bitmap, .. } => {
                bitmap.image.pixels.iter().copied().sum::<Rgb>() / bitmap.image.pixels.len().max(1) as f32
            }
            Texture::Checkerboard { color0, color1, .. } => 0.5 * (color0.mean() + color1.mean()),
            // Exact when the two are independent (a factor times a texture); an estimate for
            // sampling weights otherwise.
            Texture::Scale(t) => t[0].mean() * t[1].mean(),
            Texture::AttributeUv { texture, .. } => texture.mean(),
            Texture::Threshold { texture, threshold } => {
                Rgb::splat(if crate::math::luminance(texture.mean()) >= *threshold { 1.0 } else { 0.0 })
            }
            // Unknown without the mesh: an estimate for sampling weights only.
            Texture::MeshAttribute { scale, .. } => Rgb::splat(0.5 * scale),
            // Estimates for sampling weights: the pattern's own average, equal weights.
            Texture::Projected { texture, .. } => texture.mean(),
            Texture::Mix { amount, tex } => {
                let a = crate::math::luminance(amount.mean()).clamp(0.0, 1.0);
                tex[0].mean() * (1.0 - a) + tex[1].mean() * a
            }
            Texture::DirectionMix { tex, .. } => 0.5 * (tex[0].mean() + tex[1].mean()),
            Texture::Procedural(p) => p.mean(),
            Texture::Sqrt(t) => t.mean().max(Rgb::ZERO).powf(0.5),
            // Exact where the texture stays within [0, 1] (no clamping).
            Texture::Invert(t) => (Rgb::ONE - t.mean()).max(Rgb::ZERO),
            Texture::ConductorK(t) => t.mean().map(conductor_k),
            // The average over the volume's box (its grid's values).
            Texture::Volume(v) => v.mean(),
        }
    }

    /// Whether [`Texture::mean`] is the exact average over the texture's domain (a constant, an
    /// image, or one of them scaled by a constant), not an estimate.
    pub fn mean_is_exact(&self) -> bool {
        match self {
            Texture::Constant(_) | Texture::Bitmap { .. } => true,
            Texture::Scale(t) => match &**t {
                [Texture::Constant(_), o] | [o, Texture::Constant(_)] => o.mean_is_exact(),
                _ => false,
            },
            _ => false,
        }
    }

    /// Whether every value lies in [0, 1] (valid as a reflectance).
    pub fn is_reflectance(&self) -> bool {
        let ok = |c: Rgb| c.min_element() >= 0.0 && c.max_element() <= 1.0;
        match self {
            Texture::Constant(c) => ok(*c),
            Texture::Bitmap { bitmap, .. } => bitmap.image.pixels.iter().all(|c| ok(*c)),
            Texture::Checkerboard { color0, color1, .. } => color0.is_reflectance() && color1.is_reflectance(),
            Texture::MeshAttribute { .. } | Texture::Threshold { .. } => true,
            Texture::AttributeUv { texture, .. } | Texture::Projected { texture, .. } => texture.is_reflectance(),
            Texture::Mix { amount, tex } => amount.is_reflectance() && tex[0].is_reflectance() && tex[1].is_reflectance(),
            Texture::DirectionMix { tex, .. } => tex[0].is_reflectance() && tex[1].is_reflectance(),
            Texture::Procedural(p) => p.is_reflectance(),
            Texture::Sqrt(t) | Texture::Invert(t) => t.is_reflectance(),
            Texture::ConductorK(_) => false,
            Texture::Volume(v) => v.min() >= 0.0 && v.max() <= 1.0,
            Texture::Scale(t) => {
                let bound = |t: &Texture| match t {
                    Texture::Constant(c) => c.max_element(),
                    Texture::Bitmap { bitmap, .. } => {
                        bitmap.image.pixels.iter().map(|c| c.max_element()).fold(0.0, f32::max)
                    }
                    Texture::Threshold { .. } | Texture::MeshAttribute { .. } => 1.0,
                    _ => f32::INFINITY,
                };
                let non_negative = |t: &Texture| match t {
                    Texture::Constant(c) => c.min_element() >= 0.0,
                    _ => t.is_reflectance(),
                };
                non_negative(&t[0]) && non_negative(&t[1]) && bound(&t[0]) * bound(&t[1]) <= 1.0
            }
        }
    }
}

/// Where plugins get their texturable parameters: a nested or referenced `<texture>` (built
/// by the loader, which holds the scene's objects), or a constant colour. Images come through
/// the [`ImageSource`] it extends.
pub trait TextureSource: ImageSource + VolumeSource {
    /// The parameter `name` of `o` as a texture: a nested or referenced `<texture>`, or a
    /// constant colour (`default` if absent) whose spectra reduce to RGB as `kind` says.
    fn texture_of(&mut self, o: &Obj, name: &str, default: Rgb, kind: SpectrumKind) -> PropResult<Texture>;

    /// [`TextureSource::texture_of`] for a reflectance-like parameter.
    fn texture(&mut self, o: &Obj, name: &str, default: Rgb) -> PropResult<Texture> {
        self.texture_of(o, name, default, SpectrumKind::Reflectance)
    }

    /// [`TextureSource::texture_of`] without a default: `None` if `o` has no parameter `name`.
    fn texture_opt(&mut self, o: &Obj, name: &str, kind: SpectrumKind) -> PropResult<Option<Texture>> {
        if o.has(name) {
            self.texture_of(o, name, Rgb::ONE, kind).map(Some)
        } else {
            Ok(None)
        }
    }
}

impl Texture {
    /// Mitsuba's `resolution()`: an image's size in texels, (1, 1) for procedural textures.
    pub fn resolution(&self) -> (u32, u32) {
        match self {
            Texture::Bitmap { bitmap, .. } => (bitmap.image.width, bitmap.image.height),
            _ => (1, 1),
        }
    }
}

/// A texture plugin's constructor.
pub type TexturePlugin = fn(&Obj, &mut dyn TextureSource) -> PropResult<Texture>;

/// Every texture plugin by its (Mitsuba) name.
pub const TEXTURE_PLUGINS: &[(&str, TexturePlugin)] =
    &[
        ("bitmap", bitmap_from_props),
        ("checkerboard", checkerboard_from_props),
        ("rawconstant", rawconstant_from_props),
        ("srgb", srgb_from_props),
        ("mesh_attribute", mesh_attribute_from_props),
        ("scale", scale_from_props),
        ("threshold", threshold_from_props),
        ("sqrt", sqrt_from_props),
        ("invert", invert_from_props),
        ("conductor_k", conductor_k_from_props),
        ("mix", procedural::mix_from_props),
        ("directionmix", procedural::directionmix_from_props),
        ("bilerp", procedural::bilerp_from_props),
        ("dots", procedural::dots_from_props),
        ("checkerboard3d", procedural::checkerboard3d_from_props),
        ("fbm", procedural::fbm_from_props),
        ("wrinkled", procedural::wrinkled_from_props),
        ("windy", procedural::windy_from_props),
        ("marble", procedural::marble_from_props),
        ("volume", volume_from_props),
    ];

/// Mitsuba's `volume`: `volume`, a nested `<volume name="volume">` (`gridvolume` or
/// `constvolume`, see [`volume::Volume::from_props`]), looked up at the surface point's world
/// position.
fn volume_from_props(o: &Obj, src: &mut dyn TextureSource) -> PropResult<Texture> {
    o.check_children(&[])?;
    let v = match o.get("volume").map(|p| &p.value) {
        Some(crate::props::Value::Object(v)) if v.tag == "volume" => v.clone(),
        _ => return Err(o.error("the parameter 'volume' (a nested <volume name=\"volume\">) is required")),
    };
    v.built.set(true);
    let volume = volume::Volume::from_props(&v, SpectrumKind::Unbounded, src)?;
    if !volume.is_finite() {
        return Err(v.error("the volume holds values that are not finite"));
    }
    Ok(Texture::Volume(Arc::new(volume)))
}

/// The constructor of the texture plugin `name`.
pub fn texture_plugin(name: &str) -> Option<TexturePlugin> {
    TEXTURE_PLUGINS.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}

/// A texture's `to_uv` (a `<transform>`, identity if absent) as a homogeneous 2D affine map.
fn to_uv_from_props(o: &Obj) -> PropResult<Mat3> {
    let m = *o.transform("to_uv")?.matrix();
    Ok(Mat3::from_cols(
        Vec3::new(m.x_axis.x, m.x_axis.y, 0.0),
        Vec3::new(m.y_axis.x, m.y_axis.y, 0.0),
        Vec3::new(m.w_axis.x, m.w_axis.y, 1.0),
    ))
}

/// Mitsuba's `bitmap`: `filename` (PNG or EXR), `raw` (false: sRGB-decoded), `filter_type`
/// (`bilinear`, `nearest`), `wrap_mode` (`repeat`, `mirror`, `clamp`), `to_uv`, `format`
/// (`auto`, `variant`, `fp16`: texels rounded to half precision), `accel`; neumann's
/// `wrap_mode_u` / `wrap_mode_v` (one axis each), `gamma` (8-bit images decoded as v^gamma, not
/// sRGB: pbrt-v4's "gamma G" encoding), `uv_attribute` (look up at the texture
/// coordinates of that per-vertex mesh attribute) and `mapping` (pbrt-v4's 2D mappings,
/// [`procedural::projection_from_props`]).
fn bitmap_from_props(o: &Obj, images: &mut dyn TextureSource) -> PropResult<Texture> {
    let raw = o.bool("raw", false)?;
    // Mitsuba's `accel` (hardware texture lookups on GPUs) changes no value.
    o.bool("accel", true)?;
    // neumann's `gamma`: 8-bit images decoded as v^gamma instead of sRGB (pbrt-v4's "gamma G"
    // encoding); float images (EXR, HDR, PFM) are linear whatever it says, as in pbrt.
    let gamma = o.float_opt("gamma")?;
    if let Some(g) = gamma {
        if !(g > 0.0 && g.is_finite()) || raw {
            return Err(o.error_at("gamma", format!("'gamma' must be positive and without 'raw', got {g}")));
        }
    }
    // neumann's `pbrt_scalar`: the image read as pbrt-v4 reads a float texture (its alpha,
    // or the mean of its colour, decoded as `raw` and `gamma` say).
    let pbrt_scalar = o.bool("pbrt_scalar", false)?;
    let mut image = if pbrt_scalar {
        images.pbrt_scalar_image(o, "filename", raw, gamma)?
    } else {
        images.image(o, "filename", raw || gamma.is_some())?
    };
    if let (Some(g), false) = (gamma, pbrt_scalar) {
        let name = o.string("filename")?.to_ascii_lowercase();
        if ![".exr", ".hdr", ".pfm"].iter().any(|e| name.ends_with(e)) {
            let pixels = image.pixels.iter().map(|c| c.max(Rgb::ZERO).powf(g)).collect();
            image = Arc::new(Image { width: image.width, height: image.height, pixels });
        }
    }
    // Mitsuba's storage `format`: `auto` (half precision for images of 16 bits or fewer per
    // channel, in Mitsuba's GPU and spectral variants only; its scalar and LLVM RGB variants,
    // like neumann, keep single precision), `variant` or `fp16` (every texel rounded to half
    // precision after decoding, as Mitsuba stores it).
    if o.choice("format", &["auto", "variant", "fp16"])? == "fp16" {
        let pixels = image.pixels.iter().map(|c| c.map(crate::math::round_to_half)).collect();
        image = Arc::new(Image { width: image.width, height: image.height, pixels });
    }
    let filter = match o.choice("filter_type", &["bilinear", "nearest"])?.as_str() {
        "bilinear" => Filter::Bilinear,
        _ => Filter::Nearest,
    };
    let wrap_of = |choice: String| match choice.as_str() {
        "repeat" => Wrap::Repeat,
        "mirror" => Wrap::Mirror,
        "black" => Wrap::Black,
        "octahedral_sphere" => Wrap::OctahedralSphere,
        _ => Wrap::Clamp,
    };
    // Mitsuba's three wrap modes and neumann's `black` and `octahedral_sphere` (pbrt-v4's).
    const WRAPS: [&str; 5] = ["repeat", "mirror", "clamp", "black", "octahedral_sphere"];
    let wrap = wrap_of(o.choice("wrap_mode", &WRAPS)?);
    if wrap != Wrap::OctahedralSphere
        && ["wrap_mode_u", "wrap_mode_v"]
            .iter()
            .any(|n| o.string_opt(n).ok().flatten().as_deref() == Some("octahedral_sphere"))
    {
        return Err(o.error_at("wrap_mode", "the octahedral_sphere wrap joins both axes: give it as wrap_mode"));
    }
    // neumann's `wrap_mode_u` / `wrap_mode_v` set one axis each (glTF samplers do).
    let axis = |name: &str| -> PropResult<Wrap> {
        if !o.has(name) {
            return Ok(wrap);
        }
        Ok(wrap_of(o.choice(name, &WRAPS)?))
    };
    let wrap = [axis("wrap_mode_u")?, axis("wrap_mode_v")?];
    let texture = Texture::Bitmap { bitmap: Bitmap { image, filter, wrap }, to_uv: to_uv_from_props(o)? };
    // neumann's `uv_attribute`: texture coordinates from a mesh attribute (glTF's TEXCOORD_1…).
    Ok(match o.string_opt("uv_attribute")? {
        None => procedural::projected(o, texture)?,
        Some(attribute) if attribute.starts_with("vertex_") => Texture::AttributeUv { attribute, texture: Box::new(texture) },
        Some(a) => return Err(o.error_at("uv_attribute", format!("a uv attribute is per vertex ('vertex_…'), got '{a}'"))),
    })
}

/// pbrt-v4's `scale`: `tex` (1) times `scale` (1), both texturable; their product. glTF's
/// materials use it for factor × texture × vertex colour.
fn scale_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    let kind = SpectrumKind::Unbounded;
    let tex = b.texture_of(o, "tex", Rgb::ONE, kind)?;
    let scale = b.texture_of(o, "scale", Rgb::ONE, kind)?;
    Ok(tex.times(scale))
}

/// neumann's `threshold`: 1 where the texture `tex` (required) as a scalar reaches `threshold`
/// (0.5), else 0 (glTF's `alphaMode` `MASK` with `alphaCutoff`, as rasterizers apply it: after
/// filtering).
fn threshold_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    if !o.has("tex") {
        return Err(o.error("a threshold texture needs its 'tex'"));
    }
    let texture = Box::new(b.texture_of(o, "tex", Rgb::ONE, SpectrumKind::Unbounded)?);
    let threshold = o.float_checked("threshold", 0.5, f32::is_finite, "a number")?;
    Ok(Texture::Threshold { texture, threshold })
}

/// neumann's `sqrt`: the square root of `tex` (required) per channel, negative values giving 0
/// (pbrt-v4's `remaproughness` of a roughness texture: α = √roughness).
fn sqrt_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    if !o.has("tex") {
        return Err(o.error("a sqrt texture needs its 'tex'"));
    }
    Ok(match b.texture_of(o, "tex", Rgb::ONE, SpectrumKind::Unbounded)? {
        Texture::Constant(c) => Texture::Constant(c.max(Rgb::ZERO).powf(0.5)),
        t => Texture::Sqrt(Box::new(t)),
    })
}

/// neumann's `invert`: one minus `tex` (required) per channel, negative results giving 0
/// (pbrt-v4's `invert` of image textures).
fn invert_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    if !o.has("tex") {
        return Err(o.error("an invert texture needs its 'tex'"));
    }
    Ok(match b.texture_of(o, "tex", Rgb::ONE, SpectrumKind::Unbounded)? {
        Texture::Constant(c) => Texture::Constant((Rgb::ONE - c).max(Rgb::ZERO)),
        t => Texture::Invert(Box::new(t)),
    })
}

/// The extinction coefficient `2√r / √(1 − r)` of pbrt-v4's conductor of reflectance `r` at
/// normal incidence (with η = 1), `r` clamped to [0, 0.9999].
pub fn conductor_k(r: f32) -> f32 {
    let r = if r > 0.0 { r.min(0.9999) } else { 0.0 };
    2.0 * r.sqrt() / (1.0 - r).sqrt()
}

/// neumann's `conductor_k`: [`conductor_k`] of `tex` (required, a reflectance) per channel —
/// pbrt-v4's conductor given a (textured) `reflectance` instead of η and k.
fn conductor_k_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    if !o.has("tex") {
        return Err(o.error("a conductor_k texture needs its 'tex'"));
    }
    Ok(match b.texture_of(o, "tex", Rgb::ONE, SpectrumKind::Reflectance)? {
        Texture::Constant(c) => Texture::Constant(c.map(conductor_k)),
        t => Texture::ConductorK(Box::new(t)),
    })
}

/// Mitsuba's `checkerboard`: `color0` (0.4), `color1` (0.2), both texturable, `to_uv`; and
/// neumann's `mapping` (pbrt-v4's 2D mappings, [`procedural::projection_from_props`]).
fn checkerboard_from_props(o: &Obj, b: &mut dyn TextureSource) -> PropResult<Texture> {
    let color0 = b.texture(o, "color0", Rgb::splat(0.4))?;
    let color1 = b.texture(o, "color1", Rgb::splat(0.2))?;
    let to_uv = to_uv_from_props(o)?;
    Ok(match procedural::projection_from_props(o)? {
        None => Texture::checkerboard(color0, color1, to_uv),
        // Under a projection the cells follow (s, t) while the colours keep the surface's uv.
        Some(projection) => {
            let cells = Texture::checkerboard(Rgb::ZERO, Rgb::ONE, to_uv);
            let amount = Box::new(Texture::Projected { projection, texture: Box::new(cells) });
            Texture::Mix { amount, tex: Box::new([color0, color1]) }
        }
    })
}

/// Mitsuba's `mesh_attribute`: `name` (required: `vertex_…` or `face_…`, e.g. `vertex_color`
/// from a PLY file's vertex colours), `scale` (1). The shapes that use it must have the attribute.
fn mesh_attribute_from_props(o: &Obj, _: &mut dyn TextureSource) -> PropResult<Texture> {
    let name = o.string("name")?;
    if !(name.starts_with("vertex_") || name.starts_with("face_")) {
        return Err(o.error_at("name", format!("a mesh attribute's name starts with 'vertex_' or 'face_', got '{name}'")));
    }
    Ok(Texture::MeshAttribute { name, scale: o.float("scale", 1.0)? })
}

impl Texture {
    /// The mesh attributes this texture reads.
    pub fn mesh_attributes(&self) -> Vec<&str> {
        match self {
            Texture::MeshAttribute { name, .. } => vec![name.as_str()],
            Texture::Checkerboard { color0, color1, .. } => {
                let mut v = color0.mesh_attributes();
                v.extend(color1.mesh_attributes());
                v
            }
            Texture::Scale(t) => {
                let mut v = t[0].mesh_attributes();
                v.extend(t[1].mesh_attributes());
                v
            }
            Texture::Threshold { texture, .. } | Texture::Projected { texture, .. } => texture.mesh_attributes(),
            Texture::Sqrt(t) | Texture::Invert(t) | Texture::ConductorK(t) => t.mesh_attributes(),
            Texture::Mix { amount, tex } => {
                let mut v = amount.mesh_attributes();
                v.extend(tex[0].mesh_attributes());
                v.extend(tex[1].mesh_attributes());
                v
            }
            Texture::DirectionMix { tex, .. } => {
                let mut v = tex[0].mesh_attributes();
                v.extend(tex[1].mesh_attributes());
                v
            }
            Texture::AttributeUv { attribute, texture } => {
                let mut v = texture.mesh_attributes();
                v.push(attribute.as_str());
                v
            }
            _ => Vec::new(),
        }
    }
}

/// Mitsuba's `srgb`: `color` (required), a constant colour; in [0, 1] unless `unbounded`
/// (false), as Mitsuba checks.
fn srgb_from_props(o: &Obj, _: &mut dyn TextureSource) -> PropResult<Texture> {
    let unbounded = o.bool("unbounded", false)?;
    let c = o.rgb_opt("color", SpectrumKind::Unbounded)?.ok_or_else(|| o.error("srgb needs a 'color'"))?;
    if !(c.is_finite() && c.min_element() >= 0.0 && (unbounded || c.max_element() <= 1.0)) {
        let range = if unbounded { "≥ 0" } else { "in [0, 1] unless 'unbounded' is true" };
        return Err(o.error_at("color", format!("an srgb colour must be {range}, got {c}")));
    }
    Ok(Texture::Constant(c))
}

/// Mitsuba's `rawconstant`: `value` (required), a `<float>` or a `<vector>` (three channels),
/// used as given (no spectral conversion); Mitsuba refuses an `<rgb>` here, and so does neumann.
fn rawconstant_from_props(o: &Obj, _: &mut dyn TextureSource) -> PropResult<Texture> {
    use crate::props::Value;
    let p = o.get("value").ok_or_else(|| o.error("rawconstant needs a 'value' (a <float> or a <vector>)"))?;
    p.used.set(true);
    let v = match &p.value {
        Value::Float(f) => Rgb::splat(*f as f32),
        Value::Integer(i) => Rgb::splat(*i as f32),
        Value::Vector(v) => *v,
        other => {
            return Err(o.error_at("value", format!("'value' must be a <float> or a <vector>, not a <{}>", other.kind())))
        }
    };
    Ok(Texture::Constant(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image() -> Arc<Image> {
        // 2 × 2: top row red, green; bottom row blue, white.
        Arc::new(Image { width: 2, height: 2, pixels: vec![Rgb::X, Rgb::Y, Rgb::Z, Rgb::ONE] })
    }

    /// A grey ramp's gradient, as Mitsuba's eval_1_grad gives it: texel slopes through the
    /// transposed uv transform, times the resolution; zero for nearest filtering.
    #[test]
    fn bitmap_gradients() {
        let ramp = Arc::new(Image { width: 4, height: 1, pixels: [0.0, 0.25, 0.5, 0.75].map(Rgb::splat).to_vec() });
        let to_uv = Mat3::from_scale(Vec2::new(2.0, 3.0));
        let bilinear = Texture::Bitmap { bitmap: Bitmap { image: ramp.clone(), filter: Filter::Bilinear, wrap: [Wrap::Clamp; 2] }, to_uv };
        let g = bilinear.eval_scalar_grad(Vec2::new(0.25, 0.1));
        assert!((g - Vec2::new(2.0, 0.0)).length() < 1e-5, "{g}");
        let nearest = Texture::Bitmap { bitmap: Bitmap { image: ramp, filter: Filter::Nearest, wrap: [Wrap::Clamp; 2] }, to_uv };
        assert_eq!(nearest.eval_scalar_grad(Vec2::new(0.25, 0.1)), Vec2::ZERO);
        assert_eq!(Texture::Constant(Rgb::ONE).eval_scalar_grad(Vec2::ZERO), Vec2::ZERO);
    }

    #[test]
    fn bitmap_orientation_filtering_and_wrapping() {
        let nearest = Bitmap { image: image(), filter: Filter::Nearest, wrap: [Wrap::Repeat; 2] };
        assert_eq!(nearest.eval(Vec2::new(0.25, 0.25)), Rgb::X, "top-left texel at v near 0");
        assert_eq!(nearest.eval(Vec2::new(0.25, 0.75)), Rgb::Z, "bottom-left texel at v near 1");
        assert_eq!(nearest.eval(Vec2::new(1.25, -0.25)), Rgb::Z, "repeat");
        let bilinear = Bitmap { image: image(), filter: Filter::Bilinear, wrap: [Wrap::Clamp; 2] };
        assert_eq!(bilinear.eval(Vec2::new(0.25, 0.25)), Rgb::X, "texel centres are exact");
        let mid = bilinear.eval(Vec2::new(0.5, 0.5));
        assert!((mid - Rgb::new(0.5, 0.5, 0.5)).abs().max_element() < 1e-6, "{mid}");
        let mirror = Bitmap { image: image(), filter: Filter::Nearest, wrap: [Wrap::Mirror; 2] };
        assert_eq!(mirror.eval(Vec2::new(1.25, 0.25)), Rgb::Y, "mirrored copy");
        // pbrt's black wrap: texels outside the image are 0, so the border fades bilinearly.
        let black = Bitmap { image: image(), filter: Filter::Bilinear, wrap: [Wrap::Black, Wrap::Repeat] };
        assert_eq!(black.eval(Vec2::new(0.25, 0.25)), Rgb::X, "inside");
        assert_eq!(black.eval(Vec2::new(1.25, 0.25)), Rgb::ZERO, "outside along u");
        assert_eq!(black.eval(Vec2::new(0.0, 0.25)), Rgb::X * 0.5, "half the edge texel");
        assert_eq!(black.eval(Vec2::new(0.25, 1.25)), Rgb::X, "v still repeats");
        // pbrt's octahedral sphere: beyond the right edge, the texel mirrored across it and
        // across the middle row (pbrt maps column 2 to column 1 and row 0 to row 1); beyond the
        // bottom, mirrored across it and across the middle column.
        let octa = Bitmap { image: image(), filter: Filter::Nearest, wrap: [Wrap::OctahedralSphere; 2] };
        assert_eq!(octa.eval(Vec2::new(1.25, 0.25)), Rgb::ONE, "(2, 0) → (1, 1)");
        assert_eq!(octa.eval(Vec2::new(0.25, 1.25)), Rgb::ONE, "(0, 2) → (1, 1)");
        assert_eq!(octa.eval(Vec2::new(-0.25, 0.25)), Rgb::ONE, "(−1, 0) → (1, 1)");
        assert_eq!(octa.eval(Vec2::new(0.75, -0.25)), Rgb::Z, "(1, −1) → (0, 1)");
        assert_eq!(octa.eval(Vec2::new(0.75, 0.25)), Rgb::Y, "inside");
    }

    /// Bilinear lookups wrap each axis once for both texels along it: the same value as the
    /// four texels looked up one by one, in every wrap mode, inside, across and far beyond the
    /// edges.
    #[test]
    fn bilinear_is_the_weighted_texels_in_every_wrap() {
        let modes = [Wrap::Repeat, Wrap::Clamp, Wrap::Mirror, Wrap::Black];
        let mut wraps: Vec<[Wrap; 2]> = modes.iter().flat_map(|&a| modes.map(|b| [a, b])).collect();
        wraps.push([Wrap::OctahedralSphere; 2]);
        for wrap in wraps {
            let b = Bitmap { image: image(), filter: Filter::Bilinear, wrap };
            for k in 0..400 {
                let uv = Vec2::new(-3.1 + 0.0173 * k as f32, 2.7 - 0.0139 * k as f32);
                let (x0, y0, fx, fy) = b.bilinear_cell(uv);
                let expected = b.texel(x0, y0) * ((1.0 - fx) * (1.0 - fy))
                    + b.texel(x0 + 1, y0) * (fx * (1.0 - fy))
                    + b.texel(x0, y0 + 1) * ((1.0 - fx) * fy)
                    + b.texel(x0 + 1, y0 + 1) * (fx * fy);
                assert_eq!(b.eval(uv), expected, "{wrap:?} at {uv}");
            }
        }
    }

    #[test]
    fn checkerboard_and_uv_transform() {
        let t =
            Texture::checkerboard(Rgb::ONE, Rgb::ZERO, Mat3::from_scale(Vec2::splat(2.0)));
        assert_eq!(t.eval(Vec2::new(0.1, 0.1)), Rgb::ONE);
        assert_eq!(t.eval(Vec2::new(0.3, 0.1)), Rgb::ZERO);
        assert_eq!(t.eval(Vec2::new(0.3, 0.3)), Rgb::ONE);
        assert_eq!(t.mean(), Rgb::splat(0.5));
        assert!(t.is_reflectance());
        // As a scalar (Mitsuba's eval_1) the colours are swapped, as Mitsuba 3.9.1 has them.
        assert_eq!(t.eval_scalar(&TexPoint::at_uv(Vec2::new(0.1, 0.1))), 0.0);
        assert_eq!(t.eval_scalar(&TexPoint::at_uv(Vec2::new(0.3, 0.1))), 1.0);
        assert!(!Texture::Constant(Rgb::splat(1.5)).is_reflectance());
    }

    /// A checkerboard's colours may be textures, looked up at the untransformed point (as
    /// Mitsuba does; compared with Mitsuba 3.9.1 on a bitmap-and-checkerboard nest).
    #[test]
    fn nested_checkerboards() {
        let inner = Texture::checkerboard(Rgb::new(1.0, 0.0, 0.0), Rgb::new(0.0, 0.0, 1.0), Mat3::from_scale(Vec2::splat(8.0)));
        let t = Texture::checkerboard(Rgb::splat(0.5), inner.clone(), Mat3::from_scale(Vec2::splat(2.0)));
        // Outer color1 cell (u in [0.25, 0.5), v in [0, 0.25)): the inner board at the same uv.
        for uv in [Vec2::new(0.3, 0.01), Vec2::new(0.37, 0.01), Vec2::new(0.3, 0.07)] {
            assert_eq!(t.eval(uv), inner.eval(uv), "{uv}");
            assert_eq!(t.eval_scalar(&TexPoint::at_uv(uv)), 0.5, "{uv}: scalar lookups swap the outer colours");
        }
        assert_eq!(t.eval(Vec2::new(0.1, 0.1)), Rgb::splat(0.5));
        assert_eq!(t.eval_scalar(&TexPoint::at_uv(Vec2::new(0.1, 0.1))), inner.eval_scalar(&TexPoint::at_uv(Vec2::new(0.1, 0.1))));
        assert_eq!(t.mean(), 0.5 * (Rgb::splat(0.5) + inner.mean()));
    }
}
