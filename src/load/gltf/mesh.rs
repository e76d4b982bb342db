//! glTF mesh primitives as triangle meshes: every triangle mode (lists, strips, fans), vertex
//! normals (none: flat shading), one texture-coordinate set, `COLOR_0` (the `vertex_color`
//! attribute), morph targets at the node's (or mesh's) weights, and skins posed by their joints'
//! current transforms.

use super::data::{read_integers, read_vectors};
use super::{Result, Translator};
use crate::geometry::mesh::MeshAttribute;
use crate::geometry::TriangleMesh;
use crate::math::{Mat3, Mat4, Transform, Vec2, Vec3};
use crate::props::Value;
use gltf::mesh::{Mode, Semantic};
use std::rc::Rc;

impl Translator<'_> {
    /// The shapes of `mesh`, placed by `node`.
    pub(super) fn mesh(&mut self, node: &gltf::Node, mesh: &gltf::Mesh, world: &[Mat4]) -> Result<()> {
        let skin = node.skin();
        let node_path = format!("nodes[{}]", node.index());
        let m = world[node.index()];
        if skin.is_none() && m.determinant().abs() < 1e-30 {
            // A zero scale hides a node (a common idiom); it has no area to render.
            return Ok(());
        }
        let weights: Vec<f32> = node.weights().or(mesh.weights()).map(<[f32]>::to_vec).unwrap_or_default();
        let joints = match &skin {
            Some(s) => Some(self.joint_matrices(s, world)?),
            None => None,
        };
        let posed = joints.is_some() || weights.iter().any(|&w| w != 0.0);
        for p in mesh.primitives() {
            let path = format!("meshes[{}].primitives[{}]", mesh.index(), p.index());
            if !matches!(p.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                self.warnings.push(format!(
                    "warning: {}: {path}: {:?} primitives have no area and are not rendered",
                    self.src.file.path.display(),
                    p.mode()
                ));
                continue;
            }
            let material = p.material();
            let (uv_set, other_sets) = self.uv_sets(&material);
            let name = if posed { format!("{path}@{node_path}") } else { path.clone() };
            if !self.memory.meshes.contains_key(&name) {
                let Some(mut tri) = self.primitive(&p, &path, (uv_set, &other_sets), &weights)? else { continue };
                if let Some(j) = &joints {
                    self.skin_mesh(&p, &path, &mut tri, j)?;
                }
                self.memory.meshes.insert(name.clone(), tri);
            }
            let tri = &self.memory.meshes[&name];
            let to_world = if joints.is_some() { Mat4::IDENTITY } else { m };
            for q in &tri.positions {
                self.bounds = self.bounds.union_point(to_world.transform_point3(*q));
            }
            let mut shape = self.obj("shape", "mesh", &path);
            self.set(&mut shape, "filename", Value::String(name), &path);
            if to_world != Mat4::IDENTITY {
                let t =
                    Transform::from_matrix(to_world).ok_or_else(|| self.src.err(&node_path, "singular transform"))?;
                self.set(&mut shape, "to_world", Value::Transform(t), &node_path);
            }
            let built = self.material(&material, uv_set, p.get(&Semantic::Colors(0)).is_some())?;
            shape.children.push(built.bsdf.clone());
            if let Some(e) = &built.emitter {
                shape.children.push(e.clone());
            }
            if let Some(m) = &built.interior {
                self.set(&mut shape, "interior", Value::Object(m.clone()), &path);
            }
            self.shapes.push(Rc::new(shape));
        }
        Ok(())
    }

    /// The triangles of one primitive in the mesh's own space, morphed by `weights`; `None` (and
    /// a warning) for a primitive without positions, which glTF says not to render.
    fn primitive(
        &mut self,
        p: &gltf::Primitive,
        path: &str,
        (uv_set, other_sets): (u32, &[u32]),
        weights: &[f32],
    ) -> Result<Option<TriangleMesh>> {
        let (src, buffers) = (self.src, self.buffers);
        let Some(pos) = p.get(&Semantic::Positions) else {
            self.warnings
                .push(format!("warning: {}: {path} has no POSITION and is not rendered", src.file.path.display()));
            return Ok(None);
        };
        let mut positions: Vec<Vec3> =
            read_vectors::<3>(src, buffers, &pos, "POSITION")?.into_iter().map(Vec3::from).collect();
        let n = positions.len();
        let same_count = |a: &gltf::Accessor, what: &str| -> Result<()> {
            if a.count() != n {
                return Err(src.err(
                    &format!("accessors[{}].count", a.index()),
                    format!("{what} has {} elements but POSITION has {n} (one per vertex is needed)", a.count()),
                ));
            }
            Ok(())
        };
        let mut normals: Vec<Vec3> = match p.get(&Semantic::Normals) {
            Some(a) => {
                same_count(&a, "NORMAL")?;
                read_vectors::<3>(src, buffers, &a, "NORMAL")?.into_iter().map(Vec3::from).collect()
            }
            None => Vec::new(),
        };
        for (t, target) in p.morph_targets().enumerate() {
            let w = weights.get(t).copied().unwrap_or(0.0);
            if w == 0.0 {
                continue;
            }
            if let Some(a) = target.positions() {
                same_count(&a, "a morph target's POSITION")?;
                for (q, d) in
                    positions.iter_mut().zip(read_vectors::<3>(src, buffers, &a, "a morph target's POSITION")?)
                {
                    *q += w * Vec3::from(d);
                }
            }
            if let (Some(a), false) = (target.normals(), normals.is_empty()) {
                same_count(&a, "a morph target's NORMAL")?;
                for (q, d) in normals.iter_mut().zip(read_vectors::<3>(src, buffers, &a, "a morph target's NORMAL")?) {
                    *q += w * Vec3::from(d);
                }
            }
        }
        // A normal that cannot be normalized makes the whole primitive flat-shaded.
        if normals.iter().any(|v| v.length_squared() <= 1e-20 || !v.is_finite()) {
            normals.clear();
        }
        let uvs: Vec<Vec2> = match p.get(&Semantic::TexCoords(uv_set)) {
            Some(a) => {
                same_count(&a, "TEXCOORD")?;
                read_vectors::<2>(src, buffers, &a, "TEXCOORD")?.into_iter().map(Vec2::from).collect()
            }
            None => Vec::new(),
        };
        let mut extra_uvs = Vec::new();
        for &set in other_sets {
            let a = p.get(&Semantic::TexCoords(set)).ok_or_else(|| {
                src.err(
                    &format!("{path}.attributes"),
                    format!("the material's textures read TEXCOORD_{set}, which the primitive lacks"),
                )
            })?;
            same_count(&a, "TEXCOORD")?;
            let values = read_vectors::<2>(src, buffers, &a, "TEXCOORD")?
                .into_iter()
                .map(|[u, v]| Vec3::new(u, v, 0.0))
                .collect();
            extra_uvs.push(MeshAttribute { name: format!("vertex_texcoord{set}"), per_face: false, values });
        }
        let colors = match p.get(&Semantic::Colors(0)) {
            Some(a) => {
                same_count(&a, "COLOR_0")?;
                let rgb: Vec<Vec3> = if a.dimensions().multiplicity() == 4 {
                    read_vectors::<4>(src, buffers, &a, "COLOR_0")?
                        .into_iter()
                        .map(|c| Vec3::new(c[0], c[1], c[2]))
                        .collect()
                } else {
                    read_vectors::<3>(src, buffers, &a, "COLOR_0")?.into_iter().map(Vec3::from).collect()
                };
                Some(rgb)
            }
            None => None,
        };
        let order: Vec<u32> = match p.indices() {
            Some(a) => {
                let idx = read_integers(src, buffers, &a, "indices")?;
                if let Some(bad) = idx.iter().find(|&&i| i as usize >= n) {
                    return Err(src.err(
                        &format!("{path}.indices"),
                        format!("index {bad} is out of range: the primitive has {n} vertices"),
                    ));
                }
                idx
            }
            None => (0..n as u32).collect(),
        };
        let indices: Vec<[u32; 3]> = match p.mode() {
            Mode::Triangles => order.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
            Mode::TriangleStrip => (0..order.len().saturating_sub(2))
                .map(|i| {
                    if i % 2 == 0 {
                        [order[i], order[i + 1], order[i + 2]]
                    } else {
                        [order[i], order[i + 2], order[i + 1]]
                    }
                })
                .collect(),
            _ => (0..order.len().saturating_sub(2)).map(|i| [order[i + 1], order[i + 2], order[0]]).collect(),
        };
        let mut mesh = TriangleMesh::new(positions, normals, uvs, indices).map_err(|e| src.err(path, e.to_string()))?;
        if let Some(values) = colors {
            mesh.attributes.push(MeshAttribute { name: "vertex_color".into(), per_face: false, values });
        }
        mesh.attributes.extend(extra_uvs);
        Ok(Some(mesh))
    }

    /// Each joint's skinning matrix: its world transform times its inverse bind matrix.
    fn joint_matrices(&self, skin: &gltf::Skin, world: &[Mat4]) -> Result<Vec<Mat4>> {
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let inverse_bind = match skin.inverse_bind_matrices() {
            Some(a) => {
                let m = read_vectors::<16>(self.src, self.buffers, &a, "inverseBindMatrices")?;
                if m.len() < joints.len() {
                    return Err(self.src.err(
                        &format!("skins[{}].inverseBindMatrices", skin.index()),
                        format!("{} matrices for {} joints", m.len(), joints.len()),
                    ));
                }
                m.into_iter().map(|c| Mat4::from_cols_array(&c)).collect()
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        Ok(joints.iter().zip(inverse_bind).map(|(&j, ibm)| world[j] * ibm).collect())
    }

    /// Poses a skinned primitive: each vertex by its joints' matrices, blended by its weights
    /// (every `JOINTS_n` / `WEIGHTS_n` set), normals by the blend's inverse transpose.
    fn skin_mesh(&self, p: &gltf::Primitive, path: &str, mesh: &mut TriangleMesh, joints: &[Mat4]) -> Result<()> {
        let (src, buffers) = (self.src, self.buffers);
        let n = mesh.positions.len();
        let mut blend = vec![Mat4::ZERO; n];
        let mut set = 0;
        while let (Some(ja), Some(wa)) = (p.get(&Semantic::Joints(set)), p.get(&Semantic::Weights(set))) {
            if ja.count() != n || wa.count() != n {
                return Err(src.err(path, format!("JOINTS_{set} and WEIGHTS_{set} need one element per vertex ({n})")));
            }
            let js = read_integers(src, buffers, &ja, "JOINTS")?;
            let ws = read_vectors::<4>(src, buffers, &wa, "WEIGHTS")?;
            if js.len() != 4 * n {
                return Err(src.err(&format!("accessors[{}].type", ja.index()), "JOINTS must be VEC4"));
            }
            for (v, w) in ws.iter().enumerate() {
                for k in 0..4 {
                    if w[k] == 0.0 {
                        continue;
                    }
                    let j = js[4 * v + k] as usize;
                    let m = joints.get(j).ok_or_else(|| {
                        src.err(path, format!("vertex {v} names joint {j}, but the skin has {} joints", joints.len()))
                    })?;
                    blend[v] += *m * w[k];
                }
            }
            set += 1;
        }
        if set == 0 {
            return Err(src.err(path, "the node has a skin but the primitive has no JOINTS_0 and WEIGHTS_0"));
        }
        for (v, m) in blend.iter().enumerate() {
            mesh.positions[v] = m.transform_point3(mesh.positions[v]);
            if let Some(nrm) = mesh.normals.get_mut(v) {
                let inv_t = Mat3::from_mat4(*m).inverse().transpose();
                *nrm = (inv_t * *nrm).normalize_or(*nrm);
            }
        }
        if let Some(i) = mesh.positions.iter().position(|q| !q.is_finite()) {
            return Err(src.err(path, format!("skinning moved vertex {i} to a non-finite position")));
        }
        *mesh = TriangleMesh::new(
            std::mem::take(&mut mesh.positions),
            std::mem::take(&mut mesh.normals),
            std::mem::take(&mut mesh.uvs),
            std::mem::take(&mut mesh.indices),
        )
        .map(|mut m| {
            m.attributes = std::mem::take(&mut mesh.attributes);
            m
        })
        .map_err(|e| src.err(path, e.to_string()))?;
        Ok(())
    }
}
