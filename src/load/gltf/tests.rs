//! glTF loader tests: files written here (JSON with embedded or external buffers, and GLB),
//! compared with the same scene in Mitsuba XML; the defaults, the extensions and the errors.

use super::*;
use crate::geometry::Geometry;
use crate::light::Light;
use crate::load::overrides::{Override, Target};
use crate::load::test_support::{assert_renders_like, mean, render};
use crate::material::Bsdf;
use crate::math::Vec2;
use crate::math::{Rgb, Vec3};
use crate::texture::{TexPoint, Texture};
use serde_json::{json, Value as J};
use std::path::PathBuf;

/// Standard base64 (with padding).
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for i in 0..4 {
            if i <= c.len() {
                s.push(A[(n >> (18 - 6 * i)) as usize & 63] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// Writes glTF documents: binary data into one buffer, accessors over it.
#[derive(Default)]
pub struct Writer {
    bin: Vec<u8>,
    views: Vec<J>,
    accessors: Vec<J>,
}

impl Writer {
    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// An accessor of floats of glTF type `ty` (`SCALAR`, `VEC2`, `VEC3`, `VEC4`, `MAT4`).
    pub fn floats(&mut self, data: &[f32], ty: &str) -> usize {
        let n = match ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 16,
        };
        let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let mut a = json!({"bufferView": view, "componentType": 5126, "count": data.len() / n, "type": ty});
        if ty == "VEC3" {
            let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
            for c in data.chunks(3) {
                for k in 0..3 {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k]);
                }
            }
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// An accessor of unsigned 16-bit integers (`SCALAR` indices or `VEC4` joints).
    pub fn u16s(&mut self, data: &[u16], ty: &str) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let n = if ty == "VEC4" { 4 } else { 1 };
        self.accessors.push(json!({"bufferView": view, "componentType": 5123, "count": data.len() / n, "type": ty}));
        self.accessors.len() - 1
    }

    /// A buffer view holding `bytes` (an image).
    pub fn bytes(&mut self, bytes: &[u8]) -> usize {
        self.view(bytes)
    }

    /// The document `doc` with the buffer, views and accessors, the buffer as a data: URI.
    pub fn gltf(&self, mut doc: J) -> String {
        doc["asset"] = json!({"version": "2.0"});
        doc["buffers"] = json!([{"byteLength": self.bin.len(), "uri": format!("data:application/octet-stream;base64,{}", base64(&self.bin))}]);
        doc["bufferViews"] = J::Array(self.views.clone());
        doc["accessors"] = J::Array(self.accessors.clone());
        serde_json::to_string_pretty(&doc).unwrap()
    }

    /// The document as binary glTF (the buffer in the BIN chunk).
    pub fn glb(&self, mut doc: J) -> Vec<u8> {
        doc["asset"] = json!({"version": "2.0"});
        doc["buffers"] = json!([{"byteLength": self.bin.len()}]);
        doc["bufferViews"] = J::Array(self.views.clone());
        doc["accessors"] = J::Array(self.accessors.clone());
        let mut text = serde_json::to_string(&doc).unwrap().into_bytes();
        while !text.len().is_multiple_of(4) {
            text.push(b' ');
        }
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + text.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(text.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&text);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("neumann-gltf-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn load_text(dir: &Path, text: &str) -> Result<SceneFile> {
    let path = dir.join("scene.gltf");
    std::fs::write(&path, text).unwrap();
    load_gltf_file(&path, &Overrides::default(), None)
}

fn err_text(dir: &Path, text: &str) -> String {
    match load_text(dir, text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// A floor (y = 0, 4 × 4) and a 0.6-cube standing on it, as positions and triangle indices.
fn floor_and_cube() -> (Vec<f32>, Vec<u16>, Vec<f32>, Vec<u16>) {
    let floor = vec![-2.0, 0.0, 2.0, 2.0, 0.0, 2.0, 2.0, 0.0, -2.0, -2.0, 0.0, -2.0];
    let floor_idx = vec![0, 1, 2, 0, 2, 3];
    let (s, h) = (0.3f32, 0.6f32);
    let mut cube = Vec::new();
    for &(x, y, z) in
        &[(-s, 0.0, s), (s, 0.0, s), (s, h, s), (-s, h, s), (-s, 0.0, -s), (s, 0.0, -s), (s, h, -s), (-s, h, -s)]
    {
        cube.extend([x, y, z]);
    }
    // Outward, counter-clockwise seen from outside.
    let cube_idx = vec![
        0, 1, 2, 0, 2, 3, // +z
        5, 4, 7, 5, 7, 6, // -z
        1, 5, 6, 1, 6, 2, // +x
        4, 0, 3, 4, 3, 7, // -x
        3, 2, 6, 3, 6, 7, // +y
        4, 5, 1, 4, 1, 0, // -y
    ];
    (floor, floor_idx, cube, cube_idx)
}

fn obj_text(p: &[f32], idx: &[u16]) -> String {
    let mut s = String::new();
    for c in p.chunks(3) {
        s += &format!("v {} {} {}\n", c[0], c[1], c[2]);
    }
    for t in idx.chunks(3) {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

/// The comparison scene as glTF: two principled materials, a point light of 3 W/sr (2049 cd), a
/// camera at (0, 0.8, 3) looking down −z.
fn comparison_gltf() -> (Writer, J) {
    let (floor, floor_idx, cube, cube_idx) = floor_and_cube();
    let mut w = Writer::default();
    let fp = w.floats(&floor, "VEC3");
    let fi = w.u16s(&floor_idx, "SCALAR");
    let cp = w.floats(&cube, "VEC3");
    let ci = w.u16s(&cube_idx, "SCALAR");
    let doc = json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"mesh": 0},
            {"mesh": 1, "translation": [0.2, 0.0, 0.0]},
            {"camera": 0, "translation": [0.0, 0.8, 3.0]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.5, 2.0, 1.0]}
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": fp}, "indices": fi, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": cp}, "indices": ci, "material": 1}]}
        ],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
            {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.5, 0.3, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.4}}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.3333334, "znear": 0.01}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 2049.0}]}}
    });
    (w, doc)
}

const COMPARISON_XML: &str = r#"<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="45.836624"/>
        <string name="fov_axis" value="y"/>
        <float name="near_clip" value="0.01"/>
        <transform name="to_world"><lookat origin="0, 0.8, 3" target="0, 0.8, 2" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="48"/><integer name="height" value="36"/></film>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
    </sensor>
    <emitter type="point"><point name="position" x="0.5" y="2" z="1"/><rgb name="intensity" value="3"/></emitter>
    <shape type="obj">
        <string name="filename" value="floor.obj"/><boolean name="face_normals" value="true"/>
        <bsdf type="principled"><rgb name="base_color" value="0.7"/><float name="roughness" value="1"/></bsdf>
    </shape>
    <shape type="obj">
        <string name="filename" value="cube.obj"/><boolean name="face_normals" value="true"/>
        <transform name="to_world"><translate x="0.2"/></transform>
        <bsdf type="principled"><rgb name="base_color" value="0.8, 0.5, 0.3"/><float name="roughness" value="0.4"/></bsdf>
    </shape>
</scene>"#;

fn res(w: i64, h: i64) -> Overrides {
    Overrides {
        integrator: None,
        settings: vec![
            Override::new(Target::Film, "width", crate::props::Value::Integer(w), format!("--res {w}x{h}")),
            Override::new(Target::Film, "height", crate::props::Value::Integer(h), format!("--res {w}x{h}")),
        ],
    }
}

#[test]
fn the_same_scene_in_gltf_and_mitsuba_xml_renders_the_same() {
    let dir = tmp("compare");
    let (floor, floor_idx, cube, cube_idx) = floor_and_cube();
    std::fs::write(dir.join("floor.obj"), obj_text(&floor, &floor_idx)).unwrap();
    std::fs::write(dir.join("cube.obj"), obj_text(&cube, &cube_idx)).unwrap();
    std::fs::write(dir.join("scene.xml"), COMPARISON_XML).unwrap();
    let xml = crate::load::mitsuba::load_scene_file(&dir.join("scene.xml"), &[]).unwrap();
    let (w, doc) = comparison_gltf();
    std::fs::write(dir.join("scene.gltf"), w.gltf(doc.clone())).unwrap();
    let gltf = load_gltf_file(&dir.join("scene.gltf"), &res(48, 36), None).unwrap();
    assert_eq!((gltf.scene.camera().width(), gltf.scene.camera().height(), gltf.spp), (48, 36, 64));
    assert!(gltf.warnings.is_empty(), "{:?}", gltf.warnings);
    assert_renders_like(&gltf, &xml);
    // The same document as .glb, and with the buffer in an external file, loads the same scene.
    std::fs::write(dir.join("scene.glb"), w.glb(doc.clone())).unwrap();
    let glb = load_gltf_file(&dir.join("scene.glb"), &res(48, 36), None).unwrap();
    assert!(render(&glb, 4, 1) == render(&gltf, 4, 1));
    let mut external = serde_json::from_str::<J>(&w.gltf(doc)).unwrap();
    std::fs::write(dir.join("my data.bin"), base64_decode_for_test(&external["buffers"][0]["uri"])).unwrap();
    external["buffers"][0]["uri"] = json!("my%20data.bin");
    std::fs::write(dir.join("external.gltf"), external.to_string()).unwrap();
    let ext = load_gltf_file(&dir.join("external.gltf"), &res(48, 36), None).unwrap();
    assert!(render(&ext, 4, 1) == render(&gltf, 4, 1));
}

fn base64_decode_for_test(uri: &J) -> Vec<u8> {
    let s = uri.as_str().unwrap();
    json::base64_decode(s.split_once(";base64,").unwrap().1).unwrap()
}

/// One triangle facing +z with material 0 (and whatever `doc` adds).
fn triangle_doc(w: &mut Writer, extra: J) -> J {
    let p = w.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    let mut doc = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": p}}]}]
    });
    if let J::Object(m) = extra {
        for (k, v) in m {
            doc[k] = v;
        }
    }
    doc
}

#[test]
fn without_camera_and_lights_the_scene_is_framed_and_lit() {
    let dir = tmp("defaults");
    let mut w = Writer::default();
    let doc = triangle_doc(&mut w, json!({}));
    let f = load_text(&dir, &w.gltf(doc)).unwrap();
    assert!(f.warnings.iter().any(|w| w.contains("no lights")), "{:?}", f.warnings);
    assert_eq!(f.scene.infinite_lights().len(), 1);
    // The camera looks at the centre of the bounds from +z.
    let cam = f.scene.camera();
    let ray = cam.generate_ray(
        crate::math::Vec2::new(cam.width() as f32 / 2.0, cam.height() as f32 / 2.0),
        crate::math::Vec2::splat(0.5),
    );
    assert!(ray.o.z > 1.0 && ray.d.z < -0.5, "{ray:?}");
    let hit = f.scene.intersect(&ray).expect("the centre ray hits the triangle");
    assert!((hit.p - Vec3::new(0.5, 0.5, 0.0)).length() < 0.1, "{}", hit.p);
    // The default material: white, metallic 1, roughness 1, one-sided.
    assert!(matches!(f.scene.bsdfs()[0], Bsdf::Principled(_)));
    assert!(mean(&render(&f, 4, 0)) > 0.05);
}

#[test]
fn cameras_by_index_and_name_and_their_projections() {
    let dir = tmp("cameras");
    let mut w = Writer::default();
    let doc = triangle_doc(
        &mut w,
        json!({
            "scenes": [{"nodes": [0, 1, 2]}],
            "nodes": [
                {"mesh": 0},
                {"camera": 0, "name": "front", "translation": [0.3, 0.3, 4.0]},
                {"camera": 1, "translation": [0.3, 0.3, 2.0], "rotation": [0.0, 0.0, 0.0, 1.0]}
            ],
            "cameras": [
                {"name": "wide", "type": "perspective", "perspective": {"yfov": 1.0, "aspectRatio": 2.0, "znear": 0.1, "zfar": 100.0}},
                {"name": "plan", "type": "orthographic", "orthographic": {"xmag": 2.0, "ymag": 1.0, "znear": 0.01, "zfar": 50.0}}
            ]
        }),
    );
    let path = dir.join("scene.gltf");
    std::fs::write(&path, w.gltf(doc)).unwrap();
    let first = load_gltf_file(&path, &Overrides::default(), None).unwrap();
    assert_eq!((first.scene.camera().width(), first.scene.camera().height()), (960, 480));
    for choice in ["1", "plan"] {
        let f = load_gltf_file(&path, &Overrides::default(), Some(choice)).unwrap();
        let cam = f.scene.camera();
        assert_eq!((cam.width(), cam.height()), (960, 480));
        assert_eq!(cam.projection(), crate::camera::Projection::Orthographic);
        // xmag 2: the film's left edge is 2 left of the axis.
        let r = cam.generate_ray(crate::math::Vec2::new(0.0, 240.0), crate::math::Vec2::ZERO);
        assert!((r.o.x - (0.3 - 2.0)).abs() < 1e-3 && r.d.z < -0.99, "{r:?}");
    }
    let by_node = load_gltf_file(&path, &Overrides::default(), Some("front")).unwrap();
    assert_eq!(by_node.scene.camera().projection(), crate::camera::Projection::Perspective);
    let e = load_gltf_file(&path, &Overrides::default(), Some("top")).unwrap_err().to_string();
    assert!(e.contains("--camera top") && e.contains("0 ('wide', node 1)") && e.contains("1 ('plan', node 2)"), "{e}");
}

#[test]
fn punctual_lights_in_photometric_units() {
    let dir = tmp("lights");
    let mut w = Writer::default();
    let doc = triangle_doc(
        &mut w,
        json!({
            "scenes": [{"nodes": [0, 1, 2, 3]}],
            "nodes": [
                {"mesh": 0},
                {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.0, 0.0, 1.0]},
                {"extensions": {"KHR_lights_punctual": {"light": 1}}, "rotation": [-0.70710677, 0.0, 0.0, 0.70710677]},
                {"extensions": {"KHR_lights_punctual": {"light": 2}}, "translation": [0.0, 2.0, 0.0]}
            ],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 683.0},
                {"type": "directional", "intensity": 1366.0},
                {"type": "spot", "intensity": 68.3, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}
            ]}}
        }),
    );
    let f = load_text(&dir, &w.gltf(doc)).unwrap();
    let lights = f.scene.lights();
    assert_eq!(lights.len(), 3, "no default environment when the file has lights");
    let mut seen = 0;
    for l in lights {
        match l {
            Light::Point { position, intensity, .. } => {
                assert!((*position - Vec3::Z).length() < 1e-6);
                assert!((*intensity - Rgb::new(1.0, 0.5, 0.25)).abs().max_element() < 1e-5, "{intensity}");
                seen |= 1;
            }
            Light::Directional { direction, irradiance, .. } => {
                // Rotated −90° about x: −z turns to −y.
                assert!((*direction - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-5, "{direction}");
                assert!((*irradiance - Rgb::splat(2.0)).abs().max_element() < 1e-5);
                seen |= 2;
            }
            Light::Spot { cutoff, beam, frame, .. } => {
                assert!((cutoff - 0.5).abs() < 1e-5 && (beam - 0.2).abs() < 1e-5);
                assert!((frame.n - -Vec3::Z).length() < 1e-5, "{}", frame.n);
                seen |= 4;
            }
            other => panic!("unexpected light {other:?}"),
        }
    }
    assert_eq!(seen, 7);
}

/// A PNG of `w × h` RGBA pixels.
fn png_rgba(w: u32, h: u32, pixels: &[[u8; 4]]) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().unwrap();
        writer.write_image_data(&pixels.concat()).unwrap();
    }
    out
}

/// A unit quad in z = 0 facing +z with uvs (u right, v down the image) and `material`.
fn quad_doc(w: &mut Writer, materials: J, extra: J) -> J {
    let p = w.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    let uv = w.floats(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0], "VEC2");
    let i = w.u16s(&[0, 1, 2, 0, 2, 3], "SCALAR");
    let mut doc = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": p, "TEXCOORD_0": uv}, "indices": i, "material": 0}]}],
        "materials": materials
    });
    if let J::Object(m) = extra {
        for (k, v) in m {
            doc[k] = v;
        }
    }
    doc
}

/// The BSDF of the first shape, with its wrappers peeled off in order (their names).
fn layers(f: &SceneFile) -> (Vec<&'static str>, &Bsdf) {
    let mut b = &f.scene.bsdfs()[f.scene.shapes()[0].bsdf as usize];
    let mut names = Vec::new();
    loop {
        names.push(b.plugin_name());
        b = match b {
            Bsdf::TwoSided(pair) => &pair[0],
            Bsdf::Mask { bsdf, .. } => bsdf,
            Bsdf::Perturbed(p) => &p.bsdf,
            _ => return (names, b),
        };
    }
}

#[test]
fn metallic_roughness_materials_and_their_textures() {
    let dir = tmp("materials");
    let mut w = Writer::default();
    // 2 × 1 texture: left texel red, opaque; right texel blue, alpha 0.2 (sRGB-encoded 188 → 0.5).
    let png = png_rgba(2, 1, &[[188, 0, 0, 255], [0, 0, 188, 51]]);
    let img = w.bytes(&png);
    let mr = png_rgba(1, 1, &[[0, 128, 255, 255]]);
    let mr_img = w.bytes(&mr);
    let doc = quad_doc(
        &mut w,
        json!([{
            "pbrMetallicRoughness": {
                "baseColorFactor": [1.0, 0.5, 1.0, 1.0],
                "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0.0], "scale": [0.5, 1.0]}}},
                "metallicFactor": 0.5, "roughnessFactor": 0.8,
                "metallicRoughnessTexture": {"index": 1}
            },
            "normalTexture": {"index": 1, "scale": 0.5},
            "emissiveFactor": [1.0, 0.5, 0.25],
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
            "alphaMode": "MASK", "alphaCutoff": 0.5,
            "doubleSided": true
        }]),
        json!({
            "extensionsUsed": ["KHR_texture_transform", "KHR_materials_emissive_strength"],
            "textures": [{"source": 0, "sampler": 0}, {"source": 1}],
            "samplers": [{"magFilter": 9728, "wrapS": 33071, "wrapT": 33648}],
            "images": [{"bufferView": img, "mimeType": "image/png"}, {"bufferView": mr_img, "mimeType": "image/png"}]
        }),
    );
    let f = load_text(&dir, &w.gltf(doc)).unwrap();
    let (names, inner) = layers(&f);
    assert_eq!(names, ["mask", "twosided", "normalmap", "principled"]);
    let Bsdf::Principled(p) = inner else { unreachable!() };
    // uv' = (0.5 + 0.5 u, v): u = 0.2 lands on the right texel (blue, scaled by the factor).
    let c = p.base_color.eval(Vec2::new(0.2, 0.5));
    assert!((c - Rgb::new(0.0, 0.0, 0.5)).abs().max_element() < 0.01, "{c}");
    // Metallic from blue (1.0 × 0.5), roughness from green (128/255 × 0.8), raw.
    let metallic = p.metallic.as_ref().unwrap().eval_scalar(&TexPoint::at_uv(Vec2::splat(0.5)));
    let roughness = p.roughness.eval_scalar(&TexPoint::at_uv(Vec2::splat(0.5)));
    assert!((metallic - 0.5).abs() < 1e-3 && (roughness - 0.8 * 128.0 / 255.0).abs() < 1e-3, "{metallic} {roughness}");
    // The mask: alpha 1 on the left texel, 0.2 < 0.5 on the right (through the transform).
    let Bsdf::Mask { opacity, .. } = &f.scene.bsdfs()[f.scene.shapes()[0].bsdf as usize] else { unreachable!() };
    assert_eq!(opacity.eval_scalar(&TexPoint::at_uv(Vec2::new(0.2, 0.5))), 0.0);
    let Texture::Threshold { texture, .. } = opacity else { panic!("{opacity:?}") };
    assert!(matches!(**texture, Texture::Bitmap { .. } | Texture::Scale(_)));
    // Emission: factor × strength on the front.
    let emitters: Vec<_> = f.scene.lights().iter().filter(|l| matches!(l, Light::Area { .. })).collect();
    assert_eq!(emitters.len(), 1);
    assert!(f.scene.infinite_lights().is_empty(), "an emissive material is a light");
}

#[test]
fn transmission_volume_and_the_other_lobes() {
    let dir = tmp("lobes");
    let mut w = Writer::default();
    let doc = quad_doc(
        &mut w,
        json!([{
            "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.1},
            "doubleSided": true,
            "extensions": {
                "KHR_materials_transmission": {"transmissionFactor": 0.9},
                "KHR_materials_ior": {"ior": 1.33},
                "KHR_materials_volume": {"thicknessFactor": 1.0, "attenuationDistance": 2.0, "attenuationColor": [0.5, 1.0, 0.25]},
                "KHR_materials_clearcoat": {"clearcoatFactor": 0.7, "clearcoatRoughnessFactor": 0.1},
                "KHR_materials_sheen": {"sheenColorFactor": [0.3, 0.6, 0.2]}
            }
        }]),
        json!({}),
    );
    let f = load_text(&dir, &w.gltf(doc)).unwrap();
    let (names, inner) = layers(&f);
    assert_eq!(names, ["principled"], "a transmissive material is not wrapped in twosided");
    let Bsdf::Principled(p) = inner else { unreachable!() };
    assert!((p.eta - 1.33).abs() < 1e-6);
    let at = |t: &Option<Texture>| t.as_ref().map(|t| t.eval_scalar(&TexPoint::at_uv(Vec2::ZERO)));
    let near = |v: Option<f32>, x: f32| v.is_some_and(|v| (v - x).abs() < 1e-5);
    assert!(near(at(&p.spec_trans), 0.9) && near(at(&p.clearcoat), 0.7) && near(at(&p.sheen), 0.6));
    assert!(p.metallic.is_none());
    let gloss = p.clearcoat_gloss.eval_scalar(&TexPoint::at_uv(Vec2::ZERO));
    assert!((0.1 + (0.001 - 0.1) * gloss - 0.01).abs() < 1e-4, "coat α = 0.1²: gloss {gloss}");
    // The volume: σ = −ln(colour) / distance, rendered by the volumetric path tracer.
    assert_eq!(f.integrator.kind(), crate::integrator::IntegratorKind::Volpath);
    assert_eq!(f.scene.media().len(), 1);
    // Transmission without a volume is thin-walled: principledthin.
    let mut w = Writer::default();
    let doc = quad_doc(
        &mut w,
        json!([{"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}]),
        json!({}),
    );
    let f = load_text(&dir, &w.gltf(doc)).unwrap();
    let (names, _) = layers(&f);
    assert_eq!(names, ["principledthin"]);
    assert!(
        f.warnings.iter().any(|w| w.contains("no metallic lobe")),
        "glTF's default metallic is 1: {:?}",
        f.warnings
    );
    // KHR_materials_specular: F0 = 0.04 × 0.5 → specular 0.25 (η 1.5 without an ior).
    let mut w = Writer::default();
    let doc = quad_doc(&mut w, json!([{"extensions": {"KHR_materials_specular": {"specularFactor": 0.5}}}]), json!({}));
    let f = load_text(&dir, &w.gltf(doc)).unwrap();
    let (_, inner) = layers(&f);
    let Bsdf::Principled(p) = inner else { unreachable!() };
    let f0 = ((p.eta - 1.0) / (p.eta + 1.0)).powi(2);
    assert!((f0 - 0.02).abs() < 1e-4, "F0 {f0}");
}

#[test]
fn vertex_colours_modes_hierarchy_morphs_and_skins() {
    let dir = tmp("meshes");
    let mut w = Writer::default();
    let p = w.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    let colors = w.floats(&[1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0], "VEC4");
    let list = w.u16s(&[0, 1, 2, 0, 2, 3], "SCALAR");
    let strip = w.u16s(&[1, 2, 0, 3], "SCALAR");
    let fan = w.u16s(&[0, 1, 2, 3], "SCALAR");
    let offsets = w.floats(&[0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 0.0, 0.0, 2.0], "VEC3");
    let joints = w.u16s(&[0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0], "VEC4");
    let weights = w.floats(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], "VEC4");
    let doc = json!({
        "scenes": [{"nodes": [0, 3, 4, 5, 6, 7]}],
        "nodes": [
            {"translation": [10.0, 0.0, 0.0], "children": [1]},
            {"scale": [2.0, 2.0, 2.0], "children": [2]},
            {"mesh": 0, "translation": [0.0, 0.0, 1.0]},
            {"mesh": 1, "translation": [20.0, 0.0, 0.0]},
            {"mesh": 2, "translation": [30.0, 0.0, 0.0], "weights": [0.5]},
            {"mesh": 3, "skin": 0, "translation": [100.0, 0.0, 0.0]},
            {"translation": [40.0, 0.0, 0.0]},
            {"translation": [40.0, 5.0, 0.0]}
        ],
        "skins": [{"joints": [6, 7]}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": p, "COLOR_0": colors}, "indices": list}]},
            {"primitives": [{"attributes": {"POSITION": p}, "indices": strip, "mode": 5},
                            {"attributes": {"POSITION": p}, "indices": fan, "mode": 6},
                            {"attributes": {"POSITION": p}, "mode": 0}]},
            {"primitives": [{"attributes": {"POSITION": p}, "indices": list, "targets": [{"POSITION": offsets}]}]},
            {"primitives": [{"attributes": {"POSITION": p, "JOINTS_0": joints, "WEIGHTS_0": weights}, "indices": list}]}
        ]
    });
    let f = load_text(&dir, &w.gltf(doc)).unwrap();
    assert!(f.warnings.iter().any(|w| w.contains("Points primitives have no area")), "{:?}", f.warnings);
    let meshes: Vec<&crate::geometry::TriangleMesh> = f
        .scene
        .geometries()
        .iter()
        .map(|g| match g {
            Geometry::Mesh(m) => m,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(meshes.len(), 5);
    // Parent translation, then scale, then the child's translation: (10, 0, 2) + 2 p.
    assert!((meshes[0].positions[2] - Vec3::new(12.0, 2.0, 2.0)).length() < 1e-5, "{}", meshes[0].positions[2]);
    assert_eq!(meshes[0].attributes[0].name, "vertex_color");
    assert_eq!(meshes[0].attributes[0].values[1], Vec3::new(0.0, 1.0, 0.0));
    // Strips and fans give the list's two triangles, counter-clockwise (normal +z).
    for m in &meshes[1..3] {
        assert_eq!(m.indices.len(), 2);
        for t in 0..2 {
            let [a, b, c] = m.triangle(t);
            assert!((b - a).cross(c - a).z > 0.0, "{:?}", m.indices);
        }
    }
    // The morph target at weight 0.5 moves the quad by z = 1.
    assert!((meshes[3].positions[0] - Vec3::new(30.0, 0.0, 1.0)).length() < 1e-5, "{}", meshes[3].positions[0]);
    // Skinned: the node's transform is ignored; the top vertices follow joint 1 (40, 5, 0).
    assert!((meshes[4].positions[0] - Vec3::new(40.0, 0.0, 0.0)).length() < 1e-5, "{}", meshes[4].positions[0]);
    assert!((meshes[4].positions[2] - Vec3::new(41.0, 6.0, 0.0)).length() < 1e-5, "{}", meshes[4].positions[2]);
}

#[test]
fn errors_are_located_and_never_panic() {
    let dir = tmp("errors");
    let mut w = Writer::default();
    let doc = triangle_doc(&mut w, json!({}));
    let good = w.gltf(doc);
    // Malformed JSON: the line and column of the problem.
    let bad = good.replacen("\"nodes\": [", "\"nodes\": [,", 1);
    let e = err_text(&dir, &bad);
    assert!(e.contains("scene.gltf:") && e.contains("malformed JSON"), "{e}");
    let line = bad.lines().position(|l| l.contains("\"nodes\": [,")).unwrap() + 1;
    assert!(e.contains(&format!("scene.gltf:{line}:")), "line {line}: {e}");
    // A required extension neumann lacks.
    let mut doc: J = serde_json::from_str(&good).unwrap();
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    let e = err_text(&dir, &serde_json::to_string_pretty(&doc).unwrap());
    assert!(e.contains("requires the extension KHR_draco_mesh_compression"), "{e}");
    // An index out of range, located at the reference.
    let mut doc: J = serde_json::from_str(&good).unwrap();
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(7);
    let text = serde_json::to_string_pretty(&doc).unwrap();
    let e = err_text(&dir, &text);
    let line = text.lines().position(|l| l.contains("\"POSITION\": 7")).unwrap() + 1;
    assert!(e.contains("index out of range") && e.contains(&format!("scene.gltf:{line}:")), "{e}");
    // An accessor reading past its buffer view.
    let mut doc: J = serde_json::from_str(&good).unwrap();
    doc["accessors"][0]["count"] = json!(1000);
    let e = err_text(&dir, &serde_json::to_string_pretty(&doc).unwrap());
    assert!(e.contains("out of range") && e.contains("accessor"), "{e}");
    // A vertex index past the vertices.
    let mut w2 = Writer::default();
    let p = w2.floats(&[0.0; 9], "VEC3");
    let i = w2.u16s(&[0, 1, 5], "SCALAR");
    let doc = json!({"scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": p}, "indices": i}]}]});
    let e = err_text(&dir, &w2.gltf(doc));
    assert!(e.contains("index 5 is out of range"), "{e}");
    // glTF 1.0, a node cycle, a truncated GLB, a missing buffer file.
    let e = err_text(&dir, r#"{"asset": {"version": "1.0"}}"#);
    assert!(e.contains("glTF 1.0 is not supported"), "{e}");
    let e = err_text(
        &dir,
        r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"children": [1]}, {"children": [0]}]}"#,
    );
    assert!(e.contains("ancestor") || e.contains("child of"), "{e}");
    let glb = w.glb(serde_json::from_str(&good).unwrap());
    let e = load_gltf_bytes(&dir.join("s.glb"), &glb[..glb.len() / 2], &Overrides::default(), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("s.glb") && e.contains("binary glTF"), "{e}");
    let e = err_text(&dir, r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 4, "uri": "missing.bin"}]}"#);
    assert!(e.contains("missing.bin"), "{e}");
    // Every prefix of a valid file and of a GLB: an error or a scene, never a panic.
    for n in (0..good.len()).step_by(37) {
        let _ = load_gltf_bytes(&dir.join("p.gltf"), &good.as_bytes()[..n], &Overrides::default(), None);
    }
    for n in (0..glb.len()).step_by(13) {
        let _ = load_gltf_bytes(&dir.join("p.glb"), &glb[..n], &Overrides::default(), None);
    }
}

#[test]
fn sparse_accessors_and_quantized_attributes() {
    let dir = tmp("sparse");
    let mut w = Writer::default();
    // POSITION: a sparse accessor without a buffer view (zeros) with two substituted elements.
    let sparse_idx = w.bytes(&[1u16, 2].iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>());
    let sparse_val =
        w.bytes(&[1.0f32, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>());
    // TEXCOORD_0: normalized unsigned bytes (KHR_mesh_quantization), with a byte stride of 4.
    let uv = w.bytes(&[0, 0, 9, 9, 255, 0, 9, 9, 0, 255, 9, 9]);
    let doc = json!({
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}]}],
        "extra_views": [{"buffer": 0, "byteOffset": 0, "byteLength": 12, "byteStride": 4}],
        "accessors_override": [
            {"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0],
             "sparse": {"count": 2, "indices": {"bufferView": sparse_idx, "componentType": 5123},
                        "values": {"bufferView": sparse_val}}},
            {"bufferView": "UV", "componentType": 5121, "normalized": true, "count": 3, "type": "VEC2"}
        ]
    });
    let mut doc: J = serde_json::from_str(&w.gltf(doc)).unwrap();
    let views = doc["bufferViews"].as_array_mut().unwrap();
    views[uv]["byteStride"] = json!(4);
    let mut accessors = doc["accessors_override"].take();
    accessors[1]["bufferView"] = json!(uv);
    doc["accessors"] = accessors;
    doc.as_object_mut().unwrap().remove("accessors_override");
    doc.as_object_mut().unwrap().remove("extra_views");
    let f = load_text(&dir, &serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    let Geometry::Mesh(m) = &f.scene.geometries()[0] else { panic!() };
    assert_eq!(m.positions, [Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(m.uvs, [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)]);
    // A sparse index past the accessor's elements is located.
    let mut bad = doc.clone();
    bad["accessors"][0]["count"] = json!(2);
    let e = err_text(&dir, &serde_json::to_string_pretty(&bad).unwrap());
    assert!(e.contains("sparse index 2 is out of range"), "{e}");
}

/// Documents the `gltf` crate's validation lets through but its accessors would panic on.
#[test]
fn inconsistent_documents_are_errors() {
    let dir = tmp("inconsistent");
    let base = r#""asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}]"#;
    for (doc, needle) in [
        (r#""nodes": [{"camera": 0}], "cameras": [{"type": "perspective"}]"#, "cameras[0]"),
        (r#""nodes": [{"camera": 0}], "cameras": [{"type": "orthographic"}]"#, "cameras[0]"),
        (r#""nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}}]"#, "light"),
        (
            r#""nodes": [{"extensions": {"KHR_lights_punctual": {"light": 3}}}], "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point"}]}}"#,
            "light",
        ),
        (
            r#""nodes": [{"extensions": {"KHR_lights_punctual": {"light": 0}}}], "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot"}]}}"#,
            "spot",
        ),
    ] {
        let text = format!("{{{base}, {doc}}}");
        let e = err_text(&dir, &text);
        assert!(e.contains(needle), "{doc}: {e}");
    }
}

#[test]
fn textures_on_a_second_texture_coordinate_set() {
    let dir = tmp("uv1");
    let mut w = Writer::default();
    // 2 × 1: left texel black, right texel white (sRGB 255 → 1).
    let png = png_rgba(2, 1, &[[0, 0, 0, 255], [255, 255, 255, 255]]);
    let img = w.bytes(&png);
    let p = w.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    let uv0 = w.floats(&[0.1, 0.5, 0.1, 0.5, 0.1, 0.5], "VEC2");
    let uv1 = w.floats(&[0.9, 0.5, 0.9, 0.5, 0.9, 0.5], "VEC2");
    let doc = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": p, "TEXCOORD_0": uv0, "TEXCOORD_1": uv1}, "material": 0}]}],
        "materials": [{
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
            "emissiveFactor": [1.0, 1.0, 1.0],
            "emissiveTexture": {"index": 0, "texCoord": 1}
        }],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728}],
        "images": [{"bufferView": img, "mimeType": "image/png"}]
    });
    let f = load_text(&dir, &w.gltf(doc)).unwrap();
    let Geometry::Mesh(m) = &f.scene.geometries()[0] else { panic!() };
    // The emissive texture's set is the mesh's uv (emitters read no attributes); TEXCOORD_0
    // becomes an attribute.
    assert_eq!(m.uvs[0], Vec2::new(0.9, 0.5));
    assert_eq!(m.attributes[0].name, "vertex_texcoord0");
    let point = crate::geometry::mesh::MeshPoint { mesh: m, tri: 0, bary: Vec2::splat(0.3) };
    let Light::Area { radiance, .. } = &f.scene.lights()[0] else { panic!() };
    // The emission reads TEXCOORD_1 (white), the base colour TEXCOORD_0 (black).
    assert_eq!(radiance.eval(m.uvs[0]), Rgb::ONE);
    let (_, inner) = layers(&f);
    let Bsdf::Principled(pr) = inner else { unreachable!() };
    assert_eq!(pr.base_color.eval_at(&TexPoint { mesh: Some(&point), ..TexPoint::at_uv(m.uvs[0]) }), Rgb::ZERO);
}

/// A textured floor (nearest-filtered checker, repeated 3 × by KHR_texture_transform), a
/// double-sided emissive panel and a spot light, in glTF and in Mitsuba XML.
#[test]
fn a_textured_scene_in_gltf_and_mitsuba_xml_renders_the_same() {
    let dir = tmp("compare-textured");
    let checker: Vec<[u8; 4]> =
        (0..16).map(|i| if (i % 4 < 2) ^ (i / 4 < 2) { [200, 180, 40, 255] } else { [30, 60, 160, 255] }).collect();
    let png = png_rgba(4, 4, &checker);
    std::fs::write(dir.join("checker.png"), &png).unwrap();
    let floor = [-2.0f32, 0.0, 2.0, 2.0, 0.0, 2.0, 2.0, 0.0, -2.0, -2.0, 0.0, -2.0];
    let uvs = [0.0f32, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0];
    let mut obj = String::new();
    for c in floor.chunks(3) {
        obj += &format!("v {} {} {}\n", c[0], c[1], c[2]);
    }
    // OBJ's v points up: Mitsuba's loader flips it back to glTF's.
    for c in uvs.chunks(2) {
        obj += &format!("vt {} {}\n", c[0], 1.0 - c[1]);
    }
    obj += "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
    std::fs::write(dir.join("floor.obj"), obj).unwrap();
    let panel = [-0.3f32, 1.5, 0.3, 0.3, 1.5, 0.3, 0.3, 1.5, -0.3, -0.3, 1.5, -0.3];
    let mut pobj = String::new();
    for c in panel.chunks(3) {
        pobj += &format!("v {} {} {}\n", c[0], c[1], c[2]);
    }
    // Facing down (−y): clockwise seen from above.
    pobj += "f 1 3 2\nf 1 4 3\n";
    std::fs::write(dir.join("panel.obj"), pobj).unwrap();
    let xml = r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="45.836624"/><string name="fov_axis" value="y"/><float name="near_clip" value="0.01"/>
        <transform name="to_world"><lookat origin="0, 1.2, 3" target="0, 1.2, 2" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="30"/></film>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
    </sensor>
    <emitter type="spot">
        <transform name="to_world"><lookat origin="1, 2, 1" target="0, 0, 0" up="0, 1, 0"/></transform>
        <rgb name="intensity" value="2"/><float name="cutoff_angle" value="34.377468"/><float name="beam_width" value="11.459156"/>
    </emitter>
    <shape type="obj">
        <string name="filename" value="floor.obj"/><boolean name="face_normals" value="true"/>
        <bsdf type="principled">
            <texture type="bitmap" name="base_color">
                <string name="filename" value="checker.png"/><string name="filter_type" value="nearest"/>
                <transform name="to_uv"><scale x="3" y="3"/></transform>
            </texture>
            <float name="roughness" value="0.5"/>
        </bsdf>
    </shape>
    <shape type="obj">
        <string name="filename" value="panel.obj"/><boolean name="face_normals" value="true"/>
        <emitter type="area"><rgb name="radiance" value="3, 2.5, 2"/></emitter>
        <bsdf type="twosided"><bsdf type="principled"><rgb name="base_color" value="0"/><float name="roughness" value="1"/></bsdf></bsdf>
    </shape>
</scene>"#;
    std::fs::write(dir.join("scene.xml"), xml).unwrap();
    let xml = crate::load::mitsuba::load_scene_file(&dir.join("scene.xml"), &[]).unwrap();
    let mut w = Writer::default();
    let fp = w.floats(&floor, "VEC3");
    let fuv = w.floats(&uvs, "VEC2");
    let fi = w.u16s(&[0, 1, 2, 0, 2, 3], "SCALAR");
    let pp = w.floats(&panel, "VEC3");
    let pi = w.u16s(&[0, 2, 1, 0, 3, 2], "SCALAR");
    let img = w.bytes(&png);
    // The spot's node: −z toward the origin from (1, 2, 1), +y up (its roll does not matter).
    let look = Transform::look_at(Vec3::new(1.0, 2.0, 1.0), Vec3::new(2.0, 4.0, 2.0), Vec3::Y).unwrap();
    let m = look.matrix().to_cols_array();
    let doc = json!({
        "extensionsUsed": ["KHR_lights_punctual", "KHR_texture_transform"],
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"mesh": 0},
            {"mesh": 1},
            {"camera": 0, "translation": [0.0, 1.2, 3.0]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "matrix": m}
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": fp, "TEXCOORD_0": fuv}, "indices": fi, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": pp}, "indices": pi, "material": 1}]}
        ],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"scale": [3.0, 3.0]}}},
                                      "metallicFactor": 0.0, "roughnessFactor": 0.5}},
            {"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0}, "doubleSided": true,
             "emissiveFactor": [1.0, 0.8333333, 0.6666667], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 3.0}}}
        ],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728}],
        "images": [{"bufferView": img, "mimeType": "image/png"}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.3333334, "znear": 0.01}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "intensity": 1366.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}}]}}
    });
    std::fs::write(dir.join("scene.gltf"), w.gltf(doc)).unwrap();
    let gltf = load_gltf_file(&dir.join("scene.gltf"), &res(40, 30), None).unwrap();
    assert_renders_like(&gltf, &xml);
}
