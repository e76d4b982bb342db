//! glTF materials as neumann's plugins, following Blender's importer where glTF leaves a choice:
//!
//! - metallic–roughness on Mitsuba's `principled` BSDF: `base_color` = `baseColorFactor` ×
//!   `baseColorTexture` (sRGB) × `COLOR_0`; `metallic` = `metallicFactor` × the texture's blue
//!   channel; `roughness` = `roughnessFactor` × its green channel (both renderers square it);
//!   `KHR_materials_ior` → `eta`; `KHR_materials_specular` → `specular` = F0 / 0.08 with
//!   F0 = ((ior − 1)/(ior + 1))² × `specularFactor` × max(`specularColorFactor`);
//!   `KHR_materials_transmission` → `spec_trans` (× the texture's red channel), on
//!   `principledthin` when the material has no volume (glTF's transmission is thin-walled
//!   then: light passes straight through; no metallic or clearcoat lobes there, a warning);
//!   `KHR_materials_clearcoat` → `clearcoat` (× red) and `clearcoat_gloss` chosen so that the
//!   coat's GGX α = roughness² (α ≥ 0.001, the principled coat's range: roughness ≤ 0.316);
//!   `KHR_materials_sheen` → `sheen` = max(`sheenColorFactor`) (the principled sheen is white or
//!   base-colour tinted; its roughness is fixed);
//! - `KHR_materials_volume` (with transmission, a finite `attenuationDistance`): an absorbing
//!   `homogeneous` interior medium, σₐ = −ln(`attenuationColor`) / `attenuationDistance`;
//! - `normalTexture` → `normalmap` (with its `scale`), in the tangent frame of ∂p/∂u;
//! - `emissiveFactor` × `emissiveTexture` × `KHR_materials_emissive_strength` → an `area`
//!   emitter (front side, as Mitsuba's);
//! - `alphaMode` `MASK` → `mask` with opacity 1 where alpha ≥ `alphaCutoff`; `BLEND` → `mask`
//!   with opacity alpha (stochastic transparency, which is what blending converges to);
//! - `doubleSided` → `twosided` (not for transmissive materials, which have two sides already);
//!   single-sided materials are black from behind, as Mitsuba's BSDFs;
//! - samplers: `magFilter` `NEAREST` → nearest lookups, else bilinear; `wrapS` / `wrapT` → each
//!   axis's wrap mode; `KHR_texture_transform` → the bitmap's `to_uv`.
//!
//! `occlusionTexture` is not used: a path tracer computes the occlusion it approximates.

use super::{Result, Translator};
use crate::math::Rgb;
use crate::props::{Obj, Value};
use std::rc::Rc;

/// A material's plugin objects.
#[derive(Clone)]
pub struct Built {
    /// The BSDF.
    pub bsdf: Rc<Obj>,
    /// The area emitter, if it emits.
    pub emitter: Option<Rc<Obj>>,
    /// The interior medium, if it has a volume.
    pub interior: Option<Rc<Obj>>,
}

/// A texture reference: `textureInfo` with its `KHR_texture_transform`.
struct TexRef {
    texture: usize,
    tex_coord: u32,
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    path: String,
}

impl TexRef {
    /// From a `textureInfo` JSON object at `path` (`None` if absent).
    fn from_json(v: Option<&serde_json::Value>, path: String) -> Option<TexRef> {
        let v = v?;
        let texture = v.get("index")?.as_u64()? as usize;
        let mut r = TexRef {
            texture,
            tex_coord: v.get("texCoord").and_then(|t| t.as_u64()).unwrap_or(0) as u32,
            offset: [0.0, 0.0],
            rotation: 0.0,
            scale: [1.0, 1.0],
            path,
        };
        if let Some(t) = v.pointer("/extensions/KHR_texture_transform") {
            let pair = |key: &str, default: [f32; 2]| {
                t.get(key).and_then(|a| a.as_array()).filter(|a| a.len() == 2).map_or(default, |a| {
                    [
                        a[0].as_f64().unwrap_or(default[0] as f64) as f32,
                        a[1].as_f64().unwrap_or(default[1] as f64) as f32,
                    ]
                })
            };
            r.offset = pair("offset", [0.0, 0.0]);
            r.scale = pair("scale", [1.0, 1.0]);
            r.rotation = t.get("rotation").and_then(|x| x.as_f64()).unwrap_or(0.0) as f32;
            if let Some(tc) = t.get("texCoord").and_then(|x| x.as_u64()) {
                r.tex_coord = tc as u32;
            }
        }
        Some(r)
    }
}

/// The raw JSON of image `index` (null if absent).
fn image_json(root: &serde_json::Value, index: usize) -> serde_json::Value {
    root.get("images").and_then(|i| i.get(index)).cloned().unwrap_or(serde_json::Value::Null)
}

/// The raw JSON of material `index` (the typed API lacks some extensions).
fn material_json(root: &serde_json::Value, index: Option<usize>) -> Option<&serde_json::Value> {
    root.get("materials")?.get(index?)
}

impl Translator<'_> {
    /// Every texture a material uses, with the JSON path of its `textureInfo`.
    fn texture_refs(&self, index: Option<usize>) -> Vec<TexRef> {
        let Some(m) = material_json(self.json, index) else { return Vec::new() };
        let base = format!("materials[{}]", index.unwrap_or(0));
        let mut out = Vec::new();
        let mut add = |v: Option<&serde_json::Value>, rel: &str| {
            if let Some(r) = TexRef::from_json(v, format!("{base}.{rel}")) {
                out.push(r);
            }
        };
        add(m.pointer("/pbrMetallicRoughness/baseColorTexture"), "pbrMetallicRoughness.baseColorTexture");
        add(
            m.pointer("/pbrMetallicRoughness/metallicRoughnessTexture"),
            "pbrMetallicRoughness.metallicRoughnessTexture",
        );
        add(m.get("normalTexture"), "normalTexture");
        add(m.get("emissiveTexture"), "emissiveTexture");
        for (ext, keys) in [
            ("KHR_materials_transmission", &["transmissionTexture"][..]),
            ("KHR_materials_clearcoat", &["clearcoatTexture"][..]),
            ("KHR_materials_sheen", &["sheenColorTexture"][..]),
            ("KHR_materials_specular", &["specularTexture", "specularColorTexture"][..]),
        ] {
            for key in keys {
                add(m.pointer(&format!("/extensions/{ext}/{key}")), &format!("extensions.{ext}.{key}"));
            }
        }
        out
    }

    /// The texture-coordinate sets a material's textures use: the mesh's uv set and the others,
    /// which the mesh keeps as `vertex_texcoordN` attributes. The mesh's set is the emissive
    /// texture's (area emitters look up the surface's uv only), else the normal map's (it also
    /// orients the shading frame), else the first texture's, 0 without textures.
    pub(super) fn uv_sets(&self, m: &gltf::Material) -> (u32, Vec<u32>) {
        let refs = self.texture_refs(m.index());
        let find = |suffix: &str| refs.iter().find(|r| r.path.ends_with(suffix));
        let primary = find("emissiveTexture").or(find("normalTexture")).or(refs.first()).map_or(0, |r| r.tex_coord);
        let mut others: Vec<u32> = refs.iter().map(|r| r.tex_coord).filter(|&t| t != primary).collect();
        others.sort_unstable();
        others.dedup();
        (primary, others)
    }

    /// A `texture` object of type `ty` at `path`.
    fn texture_obj(&self, ty: &str, path: &str) -> Obj {
        self.obj("texture", ty, path)
    }

    /// A bitmap of `r`'s image: the colour (`channel` `None`; sRGB-decoded unless `raw`) or one
    /// channel (`r`, `g`, `b`, `a`).
    fn bitmap(&mut self, r: &TexRef, channel: Option<&str>, raw: bool) -> Result<Obj> {
        let tex = self
            .doc
            .textures()
            .nth(r.texture)
            .ok_or_else(|| self.src.err(&r.path, format!("texture {} does not exist", r.texture)))?;
        let image = tex.source();
        let name = format!("images[{}]", image.index());
        if !self.memory.images.contains_key(&name) {
            // From the JSON itself: the `gltf` crate's accessor panics on an image with neither
            // `bufferView` nor `uri`, which its validation lets through.
            let json = &image_json(self.json, image.index());
            let view = json.get("bufferView").and_then(|v| v.as_u64());
            let bytes = match (view, json.get("uri").and_then(|u| u.as_str())) {
                (Some(v), _) => {
                    let view = self
                        .doc
                        .views()
                        .nth(v as usize)
                        .ok_or_else(|| self.src.err(&name, "bufferView out of range"))?;
                    super::data::view_bytes(self.src, self.buffers, &view)?.to_vec()
                }
                (None, Some(uri)) => super::data::read_uri(self.src, &format!("{name}.uri"), uri, &self.resolver)?,
                (None, None) => return Err(self.src.err(&name, "an image needs a 'uri' or a 'bufferView'")),
            };
            let decoded = crate::load::image::decode_encoded(std::path::Path::new(&name), &bytes)
                .map_err(|e| self.src.err(&name, format!("cannot decode the image: {e}")))?;
            self.memory.images.insert(name.clone(), decoded);
        }
        let mut o = self.texture_obj("bitmap", &r.path);
        let file = match channel {
            Some(c) => format!("{name}#{c}"),
            None => name,
        };
        self.set(&mut o, "filename", Value::String(file), &r.path);
        if r.tex_coord != self.primary_uv {
            self.set(&mut o, "uv_attribute", Value::String(format!("vertex_texcoord{}", r.tex_coord)), &r.path);
        }
        self.set(&mut o, "raw", Value::Bool(raw || channel.is_some()), &r.path);
        let sampler = tex.sampler();
        let spath = sampler.index().map_or(r.path.clone(), |i| format!("samplers[{i}]"));
        if sampler.mag_filter() == Some(gltf::texture::MagFilter::Nearest) {
            self.set(&mut o, "filter_type", Value::String("nearest".into()), &spath);
        }
        let wrap = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::ClampToEdge => "clamp",
            gltf::texture::WrappingMode::MirroredRepeat => "mirror",
            gltf::texture::WrappingMode::Repeat => "repeat",
        };
        self.set(&mut o, "wrap_mode_u", Value::String(wrap(sampler.wrap_s()).into()), &spath);
        self.set(&mut o, "wrap_mode_v", Value::String(wrap(sampler.wrap_t()).into()), &spath);
        if r.offset != [0.0, 0.0] || r.rotation != 0.0 || r.scale != [1.0, 1.0] {
            // KHR_texture_transform: uv' = offset + R(rotation) · (scale ⊙ uv), R turning the uv
            // axes counter-clockwise as the image appears (v points down).
            let (s, c) = r.rotation.sin_cos();
            let m = crate::math::Mat4::from_cols(
                crate::math::Vec4::new(c * r.scale[0], -s * r.scale[0], 0.0, 0.0),
                crate::math::Vec4::new(s * r.scale[1], c * r.scale[1], 0.0, 0.0),
                crate::math::Vec4::Z,
                crate::math::Vec4::new(r.offset[0], r.offset[1], 0.0, 1.0),
            );
            let t = crate::math::Transform::from_matrix(m)
                .ok_or_else(|| self.src.err(&r.path, "KHR_texture_transform: the scale must not be zero"))?;
            self.set(&mut o, "to_uv", Value::Transform(t), &r.path);
        }
        Ok(o)
    }

    /// The product of constant `factor` (left out if 1), the optional texture and the optional
    /// vertex colours, as a property value.
    fn product(&self, factor: Rgb, texture: Option<Obj>, vertex_color: bool, path: &str) -> Value {
        let mut parts: Vec<Value> = Vec::new();
        if factor != Rgb::ONE || (texture.is_none() && !vertex_color) {
            parts.push(Value::Rgb(factor));
        }
        if let Some(t) = texture {
            parts.push(Value::Object(Rc::new(t)));
        }
        if vertex_color {
            let mut a = self.texture_obj("mesh_attribute", path);
            self.set(&mut a, "name", Value::String("vertex_color".into()), path);
            parts.push(Value::Object(Rc::new(a)));
        }
        let mut value = parts.remove(0);
        for next in parts {
            let mut s = self.texture_obj("scale", path);
            self.set(&mut s, "tex", value, path);
            self.set(&mut s, "scale", next, path);
            value = Value::Object(Rc::new(s));
        }
        value
    }

    /// `factor` × the optional texture's channel (raw) as a scalar property value, or `None`
    /// when it is the constant 0.
    fn scalar(&mut self, factor: f32, texture: Option<TexRef>, channel: &str, path: &str) -> Result<Option<Value>> {
        if factor == 0.0 {
            return Ok(None);
        }
        let t = match texture {
            Some(r) => Some(self.bitmap(&r, Some(channel), true)?),
            None => None,
        };
        Ok(Some(match t {
            None => Value::Float(factor as f64),
            Some(t) => self.product(Rgb::splat(factor), Some(t), false, path),
        }))
    }

    /// The plugin objects of material `m` (`None`: glTF's default material) for meshes with or
    /// without vertex colours.
    pub(super) fn material(&mut self, m: &gltf::Material, uv_set: u32, vertex_color: bool) -> Result<Built> {
        let key = (m.index(), uv_set, vertex_color);
        if let Some(b) = self.materials.get(&key) {
            return Ok(b.clone());
        }
        self.primary_uv = uv_set;
        let built = self.build_material(m, vertex_color)?;
        self.materials.insert(key, built.clone());
        Ok(built)
    }

    fn build_material(&mut self, m: &gltf::Material, vertex_color: bool) -> Result<Built> {
        let path = m.index().map_or(String::new(), |i| format!("materials[{i}]"));
        let json = material_json(self.json, m.index()).cloned().unwrap_or(serde_json::Value::Null);
        let tex = |rel: &str, p: &str| TexRef::from_json(json.pointer(rel), format!("{path}.{p}"));
        let number = |ptr: &str, default: f64| json.pointer(ptr).and_then(|v| v.as_f64()).unwrap_or(default) as f32;
        let pbr = m.pbr_metallic_roughness();
        // Transmission without a volume is thin-walled in glTF (light passes straight through):
        // Mitsuba's `principledthin`; with a volume it refracts into it: `principled`.
        let transmission = number("/extensions/KHR_materials_transmission/transmissionFactor", 0.0);
        let transmissive = transmission > 0.0;
        let thick = number("/extensions/KHR_materials_volume/thicknessFactor", 0.0) > 0.0;
        let thin = transmissive && !thick;
        let mut p = self.obj("bsdf", if thin { "principledthin" } else { "principled" }, &path);
        // Base colour.
        let [r, g, b, alpha] = pbr.base_color_factor();
        let base_tex = match tex("/pbrMetallicRoughness/baseColorTexture", "pbrMetallicRoughness.baseColorTexture") {
            Some(t) => Some(self.bitmap(&t, None, false)?),
            None => None,
        };
        let bc = self.product(Rgb::new(r, g, b), base_tex, vertex_color, &format!("{path}.pbrMetallicRoughness"));
        self.set(&mut p, "base_color", bc, &format!("{path}.pbrMetallicRoughness.baseColorFactor"));
        // Metallic and roughness.
        let mr =
            || tex("/pbrMetallicRoughness/metallicRoughnessTexture", "pbrMetallicRoughness.metallicRoughnessTexture");
        let mpath = format!("{path}.pbrMetallicRoughness.metallicFactor");
        if let Some(v) = self.scalar(pbr.metallic_factor(), mr(), "b", &mpath)? {
            if thin {
                self.warn(
                    &mpath,
                    "a thin-walled transmissive material has no metallic lobe in neumann (principledthin): ignored",
                );
            } else {
                self.set(&mut p, "metallic", v, &mpath);
            }
        }
        let rpath = format!("{path}.pbrMetallicRoughness.roughnessFactor");
        let rough = self.scalar(pbr.roughness_factor(), mr(), "g", &rpath)?.unwrap_or(Value::Float(0.0));
        self.set(&mut p, "roughness", rough, &rpath);
        // Transmission.
        let ttex = tex(
            "/extensions/KHR_materials_transmission/transmissionTexture",
            "extensions.KHR_materials_transmission.transmissionTexture",
        );
        let tpath = format!("{path}.extensions.KHR_materials_transmission");
        if let Some(v) = self.scalar(transmission, ttex, "r", &tpath)? {
            self.set(&mut p, "spec_trans", v, &tpath);
        }
        // Index of refraction and specular.
        let ior = m.ior().unwrap_or(1.5);
        let ipath = format!("{path}.extensions.KHR_materials_ior.ior");
        if !(ior >= 1.0 && ior.is_finite()) {
            return Err(self.src.err(&ipath, format!("neumann needs an ior ≥ 1, got {ior}")));
        }
        let specular = json.pointer("/extensions/KHR_materials_specular");
        if let (Some(s), false) = (specular, transmissive) {
            let factor = s.get("specularFactor").and_then(|v| v.as_f64()).unwrap_or(1.0) as f32;
            let color = s
                .get("specularColorFactor")
                .and_then(|v| v.as_array())
                .map_or(1.0, |a| a.iter().filter_map(|x| x.as_f64()).fold(0.0, f64::max) as f32);
            let f0 = ((ior - 1.0) / (ior + 1.0)).powi(2) * factor * color;
            let spath = format!("{path}.extensions.KHR_materials_specular");
            self.set(&mut p, "specular", Value::Float((f0 / 0.08).clamp(0.0, 12.0) as f64), &spath);
            if s.get("specularTexture").is_some() || s.get("specularColorTexture").is_some() {
                self.warn(&spath, "the specular textures are not applied (their factors are)");
            }
        } else if m.ior().is_some() || thin {
            self.set(&mut p, "eta", Value::Float(ior.max(1.0001) as f64), &ipath);
        }
        // Clearcoat.
        let cc = format!("{path}.extensions.KHR_materials_clearcoat");
        let coat = number("/extensions/KHR_materials_clearcoat/clearcoatFactor", 0.0);
        let ctex = tex(
            "/extensions/KHR_materials_clearcoat/clearcoatTexture",
            "extensions.KHR_materials_clearcoat.clearcoatTexture",
        );
        let coat_value = self.scalar(coat, ctex, "r", &cc)?;
        if coat_value.is_some() && thin {
            self.warn(&cc, "a thin-walled transmissive material has no clearcoat in neumann (principledthin): ignored");
        }
        if let Some(v) = coat_value.filter(|_| !thin) {
            self.set(&mut p, "clearcoat", v, &cc);
            let rough = number("/extensions/KHR_materials_clearcoat/clearcoatRoughnessFactor", 0.0);
            let gloss = ((0.1 - rough * rough) / 0.099).clamp(0.0, 1.0);
            self.set(&mut p, "clearcoat_gloss", Value::Float(gloss as f64), &cc);
            let c = json.pointer("/extensions/KHR_materials_clearcoat").expect("has clearcoat");
            if c.get("clearcoatRoughnessTexture").is_some() || c.get("clearcoatNormalTexture").is_some() {
                self.warn(&cc, "the clearcoat roughness and normal textures are not applied");
            }
        }
        // Sheen.
        if let Some(s) = json.pointer("/extensions/KHR_materials_sheen") {
            let color = s
                .get("sheenColorFactor")
                .and_then(|v| v.as_array())
                .map_or(0.0, |a| a.iter().filter_map(|x| x.as_f64()).fold(0.0, f64::max) as f32);
            if color > 0.0 {
                let spath = format!("{path}.extensions.KHR_materials_sheen");
                self.set(&mut p, "sheen", Value::Float(color.min(1.0) as f64), &spath);
            }
        }
        let mut bsdf = p;
        // Normal map.
        if let Some(n) = m.normal_texture() {
            let npath = format!("{path}.normalTexture");
            let r = tex("/normalTexture", "normalTexture").expect("the typed API found it");
            let map = self.bitmap(&r, None, true)?;
            let mut o = self.obj("bsdf", "normalmap", &npath);
            self.set(&mut o, "normalmap", Value::Object(Rc::new(map)), &npath);
            if n.scale() != 1.0 {
                self.set(&mut o, "scale", Value::Float(n.scale() as f64), &npath);
            }
            o.children.push(Rc::new(bsdf));
            bsdf = o;
        }
        if m.double_sided() && !transmissive {
            let mut o = self.obj("bsdf", "twosided", &format!("{path}.doubleSided"));
            o.children.push(Rc::new(bsdf));
            bsdf = o;
        }
        // Alpha.
        let apath = format!("{path}.alphaMode");
        let opacity = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => None,
            mode => {
                let atex = match tex("/pbrMetallicRoughness/baseColorTexture", "pbrMetallicRoughness.baseColorTexture")
                {
                    Some(t) => Some(self.bitmap(&t, Some("a"), true)?),
                    None => None,
                };
                let has_tex = atex.is_some();
                let a = self.product(Rgb::splat(alpha), atex, false, &apath);
                match mode {
                    gltf::material::AlphaMode::Mask => {
                        let cutoff = m.alpha_cutoff().unwrap_or(0.5);
                        if has_tex {
                            let mut t = self.texture_obj("threshold", &apath);
                            self.set(&mut t, "tex", a, &apath);
                            self.set(&mut t, "threshold", Value::Float(cutoff as f64), &format!("{path}.alphaCutoff"));
                            Some(Value::Object(Rc::new(t)))
                        } else if alpha >= cutoff {
                            None
                        } else {
                            Some(Value::Float(0.0))
                        }
                    }
                    _ if !has_tex && alpha >= 1.0 => None,
                    _ => Some(a),
                }
            }
        };
        if let Some(a) = opacity {
            let mut o = self.obj("bsdf", "mask", &apath);
            self.set(&mut o, "opacity", a, &apath);
            o.children.push(Rc::new(bsdf));
            bsdf = o;
        }
        // Emission.
        let strength = m.emissive_strength().unwrap_or(1.0);
        let [er, eg, eb] = m.emissive_factor();
        let e = Rgb::new(er, eg, eb) * strength;
        if !(e.is_finite() && e.min_element() >= 0.0) {
            return Err(self.src.err(&format!("{path}.emissiveFactor"), "the emission must be finite and ≥ 0"));
        }
        let emitter = if e.max_element() > 0.0 {
            let epath = format!("{path}.emissiveFactor");
            let etex = match tex("/emissiveTexture", "emissiveTexture") {
                Some(t) => Some(self.bitmap(&t, None, false)?),
                None => None,
            };
            let mut o = self.obj("emitter", "area", &epath);
            let radiance = self.product(e, etex, false, &epath);
            self.set(&mut o, "radiance", radiance, &epath);
            if m.double_sided() {
                // A double-sided material emits from both faces (the glTF specification).
                self.set(&mut o, "two_sided", Value::Bool(true), &format!("{path}.doubleSided"));
            }
            self.has_emission = true;
            Some(Rc::new(o))
        } else {
            None
        };
        // Volume.
        let interior = match json.pointer("/extensions/KHR_materials_volume") {
            Some(v) if transmissive => {
                let vpath = format!("{path}.extensions.KHR_materials_volume");
                let distance = v.get("attenuationDistance").and_then(|x| x.as_f64()).unwrap_or(f64::INFINITY) as f32;
                let color = v.get("attenuationColor").and_then(|x| x.as_array()).map_or([1.0; 3], |a| {
                    std::array::from_fn(|i| a.get(i).and_then(|x| x.as_f64()).unwrap_or(1.0) as f32)
                });
                let thickness = v.get("thicknessFactor").and_then(|x| x.as_f64()).unwrap_or(0.0);
                if thickness > 0.0 && distance.is_finite() && color.iter().any(|&c| c < 1.0) {
                    if distance <= 0.0 || color.iter().any(|&c| !(c > 0.0 && c <= 1.0)) {
                        return Err(self
                            .src
                            .err(&vpath, "need attenuationDistance > 0 and attenuationColor in (0, 1]"));
                    }
                    let sigma = Rgb::from(color.map(|c| -c.ln() / distance));
                    let mut o = self.obj("medium", "homogeneous", &vpath);
                    self.set(&mut o, "sigma_t", Value::Rgb(sigma), &vpath);
                    self.set(&mut o, "albedo", Value::Float(0.0), &vpath);
                    self.has_media = true;
                    Some(Rc::new(o))
                } else {
                    None
                }
            }
            _ => None,
        };
        Ok(Built { bsdf: Rc::new(bsdf), emitter, interior })
    }

    /// A warning about the value at `path`.
    fn warn(&mut self, path: &str, message: &str) {
        let (line, col) = self.src.loc(path).line_col();
        self.warnings.push(format!("warning: {}:{line}:{col}: {message}", self.src.file.path.display()));
    }
}
