//! Triangle meshes, and the built-in rectangle and cube of Mitsuba 3.

use super::sphere::SurfacePoint;
use crate::math::{DirectionCone, Transform, Vec2, Vec3};
use crate::sampling::{sample_uniform_triangle, AliasTable};

/// An indexed triangle mesh in world space. Triangles are counter-clockwise seen from their
/// front side: the geometric normal is `(p1 - p0) × (p2 - p0)`.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex unit normals (empty: flat shading).
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates (empty: barycentric defaults).
    pub uvs: Vec<Vec2>,
    /// Vertex indices of each triangle.
    pub indices: Vec<[u32; 3]>,
    /// Reverse the orientation of every normal (Mitsuba's `flip_normals`).
    pub flip_normals: bool,
    /// Triangle-by-area distribution, built by [`TriangleMesh::prepare_sampling`].
    area_distribution: Option<AliasTable>,
    total_area: f32,
    /// Unit geometric normal of every triangle, cached by [`TriangleMesh::prepare_normals`]
    /// (the scene builder calls it for every mesh): the same values as
    /// [`TriangleMesh::normal_of`], without a cross product and square root per hit or sample.
    face_normals: Vec<Vec3>,
    /// Set by [`TriangleMesh::prepare_sampling`] when the mesh is a flat parallelogram of two
    /// triangles (Mitsuba's `rectangle`, most quad lights): then sampled directly.
    parallelogram: Option<Parallelogram>,
    /// Named per-vertex or per-triangle values (Mitsuba's mesh attributes, e.g. `vertex_color`).
    pub attributes: Vec<MeshAttribute>,
    /// Consecutive triangles per primitive, as the `prim_index` AOV counts them: 1, or the
    /// faces of one shell of an `ellipsoidsmesh` (whose primitive is the ellipsoid, as Mitsuba's).
    pub faces_per_primitive: u32,
}

/// A named value per vertex (interpolated across triangles) or per triangle (Mitsuba's
/// `vertex_*` and `face_*` mesh attributes); one to three channels, kept as RGB (a single
/// channel in all three).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    /// The name (`vertex_color`, `face_color`, …).
    pub name: String,
    /// One value per triangle (else one per vertex).
    pub per_face: bool,
    /// The values.
    pub values: Vec<Vec3>,
}

/// A point on a mesh triangle where textures may look up mesh attributes.
#[derive(Clone, Copy, Debug)]
pub struct MeshPoint<'a> {
    /// The mesh.
    pub mesh: &'a TriangleMesh,
    /// The triangle.
    pub tri: u32,
    /// Barycentric coordinates (b1, b2) of the point (b0 = 1 − b1 − b2).
    pub bary: Vec2,
}

impl MeshPoint<'_> {
    /// The value of attribute `name` here (interpolated per-vertex values, or the triangle's),
    /// if the mesh has it.
    pub fn attribute(&self, name: &str) -> Option<Vec3> {
        let a = self.mesh.attributes.iter().find(|a| a.name == name)?;
        if a.per_face {
            return a.values.get(self.tri as usize).copied();
        }
        let [i0, i1, i2] = self.mesh.indices.get(self.tri as usize)?.map(|v| v as usize);
        let (b1, b2) = (self.bary.x, self.bary.y);
        let v = |i: usize| a.values.get(i).copied();
        Some(v(i0)? * (1.0 - b1 - b2) + v(i1)? * b1 + v(i2)? * b2)
    }
}

/// A parallelogram `o + s e1 + t e2`, `(s, t) ∈ [0, 1]²`, with unit normal `n` (that of the
/// mesh's first triangle) and `mismatch`, the largest coordinate distance between the mesh's
/// fourth corner and `o + e1 + e2` (round-off of transformed corners), which sampled points'
/// error bounds include so that they stay bounds on the distance to the mesh's triangles.
#[derive(Clone, Copy, Debug)]
struct Parallelogram {
    o: Vec3,
    e1: Vec3,
    e2: Vec3,
    n: Vec3,
    mismatch: f32,
}

/// Why arrays do not make a triangle mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// Normals given, but not one per vertex.
    #[error("{normals} normals for {vertices} vertices")]
    NormalCount {
        /// Normals given.
        normals: usize,
        /// Vertices.
        vertices: usize,
    },
    /// Texture coordinates given, but not one pair per vertex.
    #[error("{uvs} texture coordinates for {vertices} vertices")]
    UvCount {
        /// Texture coordinates given.
        uvs: usize,
        /// Vertices.
        vertices: usize,
    },
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {indices:?} but there are only {vertices} vertices")]
    IndexOutOfRange {
        /// The triangle.
        triangle: usize,
        /// Its vertex indices.
        indices: [u32; 3],
        /// Vertices.
        vertices: usize,
    },
    /// A vertex position is NaN or infinite.
    #[error("vertex {0} has a non-finite position")]
    NonFinite(usize),
}

/// A triangle mesh's surface at a hit ([`TriangleMesh::surface_at`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshSurface {
    /// Shading normal (unit, world space).
    pub ns: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// `∂p/∂u` (world space).
    pub dpdu: Vec3,
    /// `∂p/∂v` (world space; zero when not asked for).
    pub dpdv: Vec3,
}

impl TriangleMesh {
    /// A mesh from its arrays. `normals` and `uvs` are either empty or one per vertex; the
    /// first problem found is the error.
    pub fn new(
        positions: Vec<Vec3>,
        normals: Vec<Vec3>,
        uvs: Vec<Vec2>,
        indices: Vec<[u32; 3]>,
    ) -> Result<Self, MeshError> {
        let n = positions.len();
        if !normals.is_empty() && normals.len() != n {
            return Err(MeshError::NormalCount { normals: normals.len(), vertices: n });
        }
        if !uvs.is_empty() && uvs.len() != n {
            return Err(MeshError::UvCount { uvs: uvs.len(), vertices: n });
        }
        if let Some((i, t)) = indices.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= n)) {
            return Err(MeshError::IndexOutOfRange { triangle: i, indices: *t, vertices: n });
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshError::NonFinite(i));
        }
        let normals = normals.into_iter().map(|v| v.normalize_or(Vec3::Z)).collect();
        Ok(TriangleMesh {
            positions,
            normals,
            uvs,
            indices,
            flip_normals: false,
            area_distribution: None,
            total_area: 0.0,
            face_normals: Vec::new(),
            attributes: Vec::new(),
            parallelogram: None,
            faces_per_primitive: 1,
        })
    }

    /// Mitsuba's `rectangle`: `[-1, 1]²` in the xy plane, normal +z, uv from (0,0) at (-1,-1)
    /// to (1,1) at (1,1).
    pub fn rectangle() -> TriangleMesh {
        let positions = vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        let uvs = vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
        TriangleMesh::new(positions, vec![], uvs, vec![[0, 1, 2], [2, 3, 0]]).expect("valid rectangle")
    }

    /// Mitsuba's `cube`: `[-1, 1]³` with outward faces, 4 vertices per face (flat shading), with
    /// Mitsuba's vertex order and texture coordinates (so textures land on the faces as in
    /// Mitsuba): per face the corners carry uv (0,1), (1,1), (1,0), (0,0), triangles (0,1,2) and
    /// (3,0,2).
    pub fn cube() -> TriangleMesh {
        // Faces in Mitsuba's order: -y, +y, +x, +z, -x, -z; corners as sign triples.
        const FACES: [[[f32; 3]; 4]; 6] = [
            [[1., -1., -1.], [1., -1., 1.], [-1., -1., 1.], [-1., -1., -1.]],
            [[1., 1., -1.], [-1., 1., -1.], [-1., 1., 1.], [1., 1., 1.]],
            [[1., -1., -1.], [1., 1., -1.], [1., 1., 1.], [1., -1., 1.]],
            [[1., -1., 1.], [1., 1., 1.], [-1., 1., 1.], [-1., -1., 1.]],
            [[-1., -1., 1.], [-1., 1., 1.], [-1., 1., -1.], [-1., -1., -1.]],
            [[1., 1., -1.], [1., -1., -1.], [-1., -1., -1.], [-1., 1., -1.]],
        ];
        let corner_uv = [Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)];
        let mut positions = Vec::with_capacity(24);
        let mut uvs = Vec::with_capacity(24);
        let mut indices = Vec::with_capacity(12);
        for face in FACES {
            let base = positions.len() as u32;
            positions.extend(face.map(Vec3::from_array));
            uvs.extend(corner_uv);
            indices.extend([[base, base + 1, base + 2], [base + 3, base, base + 2]]);
        }
        TriangleMesh::new(positions, vec![], uvs, indices).expect("valid cube")
    }

    /// Applies `t` to positions and normals. A transform that swaps handedness reverses the
    /// winding too, so the geometric normal keeps pointing to the same side as the (correctly
    /// transformed) vertex normals.
    pub fn transform(&mut self, t: &Transform) {
        for p in &mut self.positions {
            *p = t.apply_point(*p);
        }
        for n in &mut self.normals {
            *n = t.apply_normal(*n).normalize_or(Vec3::Z);
        }
        if t.swaps_handedness() {
            for tri in &mut self.indices {
                tri.swap(1, 2);
            }
        }
        self.area_distribution = None;
        self.face_normals.clear();
        self.parallelogram = None;
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Vertices of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Sum of the triangle areas.
    pub fn area(&self) -> f32 {
        if self.area_distribution.is_some() {
            return self.total_area;
        }
        (0..self.len()).map(|i| crate::sampling::triangle_area(self.triangle(i)) as f64).sum::<f64>() as f32
    }

    /// Builds the triangle-by-area distribution used by [`TriangleMesh::sample_area`].
    /// Returns `false` if the mesh has no area.
    pub fn prepare_sampling(&mut self) -> bool {
        let areas: Vec<f32> = (0..self.len()).map(|i| crate::sampling::triangle_area(self.triangle(i))).collect();
        self.total_area = areas.iter().map(|&a| a as f64).sum::<f64>() as f32;
        self.area_distribution = AliasTable::new(&areas);
        self.prepare_normals();
        self.parallelogram = if self.area_distribution.is_some() { self.find_parallelogram() } else { None };
        self.area_distribution.is_some()
    }

    /// The parallelogram this mesh is, if it is two triangles with the same orientation
    /// spanning a flat parallelogram, without vertex normals. Corners are matched by position,
    /// so welded and unwelded quads both qualify. Sampling it as `o + s e1 + t e2` gives the
    /// same uniform density as picking a triangle by area and warping, with fewer operations
    /// and random-number transforms.
    fn find_parallelogram(&self) -> Option<Parallelogram> {
        if self.len() != 2 || !self.normals.is_empty() {
            return None;
        }
        let (t0, t1) = (self.triangle(0), self.triangle(1));
        let mut shared = t0.iter().filter(|p| t1.contains(p));
        let (s1, s2) = (*shared.next()?, *shared.next()?);
        let o = *t0.iter().find(|p| !t1.contains(p))?;
        let q = *t1.iter().find(|p| !t0.contains(p))?;
        let (e1, e2) = (s1 - o, s2 - o);
        // The diagonals of a parallelogram bisect each other: q = s1 + s2 - o.
        let mismatch = (q - (s1 + e2)).abs().max_element();
        let scale = o.abs().max(s1.abs()).max(s2.abs()).max_element();
        let n = self.face_normal(0);
        let flat = n.dot(self.face_normal(1)) > 1.0 - 1e-5;
        (mismatch <= 1e-5 * scale && flat && e1.cross(e2) != Vec3::ZERO).then_some(Parallelogram {
            o,
            e1,
            e2,
            n,
            mismatch,
        })
    }

    /// Gives a mesh without vertex normals smooth ones, as Mitsuba 3 does for OBJ and PLY files
    /// unless `face_normals` is set: each vertex gets the unit sum of the unit normals of the
    /// triangles around it, each weighted by the triangle's angle at the vertex (Thürmer and
    /// Wüthrich, "Computing Vertex Normals from Polygonal Facets", 1998); degenerate triangles
    /// add nothing and a vertex with no valid triangle gets (1, 0, 0), as in Mitsuba. Computed
    /// from the current (world-space) positions and winding, so apply transforms first. A mesh
    /// whose every vertex normal equals the normals of its triangles (a planar or unwelded,
    /// faceted mesh) keeps flat shading, which is the same image.
    pub fn compute_vertex_normals(&mut self) {
        if !self.normals.is_empty() {
            return;
        }
        let mut sums = vec![Vec3::ZERO; self.positions.len()];
        let mut face = Vec::with_capacity(self.len());
        for (i, tri) in self.indices.iter().enumerate() {
            let p = self.triangle(i);
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            let len2 = n.length_squared();
            if len2 <= 0.0 || !len2.is_finite() {
                face.push(Vec3::ZERO);
                continue;
            }
            let n = n / len2.sqrt();
            face.push(n);
            for k in 0..3 {
                let (d0, d1) = ((p[(k + 1) % 3] - p[k]).normalize_or_zero(), (p[(k + 2) % 3] - p[k]).normalize_or_zero());
                let angle = d0.dot(d1).clamp(-1.0, 1.0).acos();
                sums[tri[k] as usize] += n * angle;
            }
        }
        let normals: Vec<Vec3> =
            sums.into_iter().map(|n| if n.length() > 0.0 { n.normalize() } else { Vec3::X }).collect();
        let faceted = self.indices.iter().zip(&face).all(|(tri, &n)| {
            n == Vec3::ZERO || tri.iter().all(|&v| normals[v as usize].dot(n) >= 1.0 - 1e-6)
        });
        if !faceted {
            self.normals = normals;
        }
    }

    /// Caches every triangle's unit geometric normal for [`TriangleMesh::face_normal`]. Call it
    /// after the last change of positions, indices or `flip_normals` (a transform clears it).
    pub fn prepare_normals(&mut self) {
        self.face_normals = (0..self.len()).map(|i| self.normal_of(&self.triangle(i))).collect();
    }

    /// A cone holding every front-side geometric normal and (if the mesh has them) every
    /// front-side vertex normal. Unions of single directions, each widened by a round-off margin.
    pub fn normal_cone(&self) -> DirectionCone {
        let sign = if self.flip_normals { -1.0 } else { 1.0 };
        let mut cone = DirectionCone::EMPTY;
        let faces = (0..self.len()).map(|i| self.face_normal(i));
        let vertices = self.normals.iter().map(|n| sign * n.normalize_or_zero()).filter(|n| *n != Vec3::ZERO);
        for n in faces.chain(vertices) {
            if !cone.contains(n) {
                cone = DirectionCone::union(&cone, &DirectionCone::from_direction(n));
                if cone.cos_theta <= -1.0 {
                    break;
                }
            }
        }
        cone
    }

    /// Geometric normal of triangle `i` (unit, front side): cached after
    /// [`TriangleMesh::prepare_normals`], computed otherwise.
    #[inline(always)]
    pub fn face_normal(&self, i: usize) -> Vec3 {
        match self.face_normals.get(i) {
            Some(&n) => n,
            None => self.normal_of(&self.triangle(i)),
        }
    }

    /// Geometric normal (unit, front side) of this mesh's triangle with vertices `p`.
    #[inline]
    pub fn normal_of(&self, p: &[Vec3; 3]) -> Vec3 {
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or(Vec3::Z);
        if self.flip_normals {
            -n
        } else {
            n
        }
    }

    /// The surface of triangle `i` (world vertices `p`, unit face normal `ng`) at barycentrics
    /// `b = (b0, b1, b2)`: shading normal, uv, and `∂p/∂u` (and `∂p/∂v` when `with_v`, else
    /// zero), as Mitsuba 3.9 computes them. The partial derivatives come from the vertices'
    /// texture coordinates where they span the triangle (else the tangents of Duff et al.'s
    /// basis around `ng`, Mitsuba's `coordinate_system`); without texture coordinates the
    /// barycentric parameterization uv = (b1, b2) gives `p1 − p0` and `p2 − p0` (measured against
    /// Mitsuba: anisotropic BSDFs on such meshes change frame from triangle to triangle there,
    /// and so they do here). Reads the triangle's indices once for all of it.
    #[inline(always)]
    pub fn surface_at(&self, i: usize, p: &[Vec3; 3], b: [f32; 3], ng: Vec3, with_v: bool) -> MeshSurface {
        let (dp0, dp1) = (p[1] - p[0], p[2] - p[0]);
        let barycentric_dpdv = if with_v { dp1 } else { Vec3::ZERO };
        if self.normals.is_empty() && self.uvs.is_empty() {
            // No vertex data to interpolate: no need to fetch the indices.
            return MeshSurface { ns: ng, uv: Vec2::new(b[1], b[2]), dpdu: dp0, dpdv: barycentric_dpdv };
        }
        let [a, bb, c] = self.indices[i].map(|v| v as usize);
        let ns = self.interpolated_normal([a, bb, c], b, ng);
        if self.uvs.is_empty() {
            return MeshSurface { ns, uv: Vec2::new(b[1], b[2]), dpdu: dp0, dpdv: barycentric_dpdv };
        }
        let (uv0, uv1, uv2) = (self.uvs[a], self.uvs[bb], self.uvs[c]);
        let uv = uv0 * b[0] + uv1 * b[1] + uv2 * b[2];
        let (duv0, duv1) = (uv1 - uv0, uv2 - uv0);
        let det = duv0.x * duv1.y - duv0.y * duv1.x;
        if det != 0.0 {
            let dpdu = (dp0 * duv1.y - dp1 * duv0.y) / det;
            let dpdv = if with_v { (dp1 * duv0.x - dp0 * duv1.x) / det } else { Vec3::ZERO };
            if dpdu.is_finite() && dpdv.is_finite() {
                return MeshSurface { ns, uv, dpdu, dpdv };
            }
        }
        let f = crate::math::Frame::from_z(ng);
        MeshSurface { ns, uv, dpdu: f.s, dpdv: if with_v { f.t } else { Vec3::ZERO } }
    }

    /// The shading normal at barycentrics `b` of the triangle with vertex indices `v`: the
    /// vertex normals interpolated and normalized (front side), or the face normal `ng` where
    /// the mesh has none (or they cancel).
    #[inline(always)]
    fn interpolated_normal(&self, v: [usize; 3], b: [f32; 3], ng: Vec3) -> Vec3 {
        if self.normals.is_empty() {
            return ng;
        }
        let n = (self.normals[v[0]] * b[0] + self.normals[v[1]] * b[1] + self.normals[v[2]] * b[2]).normalize_or(ng);
        if self.flip_normals {
            -n
        } else {
            n
        }
    }

    /// Shading normal and uv at barycentrics `(b0, b1, b2)` of triangle `i`, given its face
    /// normal `ng`. Without texture coordinates uv is `(b1, b2)`, as in Mitsuba.
    #[inline]
    pub fn shading(&self, i: usize, b: [f32; 3], ng: Vec3) -> (Vec3, Vec2) {
        if self.normals.is_empty() && self.uvs.is_empty() {
            // No vertex data to interpolate: no need to fetch the indices.
            return (ng, Vec2::new(b[1], b[2]));
        }
        let [a, bb, c] = self.indices[i].map(|v| v as usize);
        let ns = self.interpolated_normal([a, bb, c], b, ng);
        let uv = if self.uvs.is_empty() {
            Vec2::new(b[1], b[2])
        } else {
            self.uvs[a] * b[0] + self.uvs[bb] * b[1] + self.uvs[c] * b[2]
        };
        (ns, uv)
    }

    /// Uniform point on the mesh (triangle by area with the alias table, then the triangle
    /// warp; a parallelogram mesh directly as `o + u.x e1 + u.y e2`); pdf `1 / area` per unit
    /// area. Returns the point (with its geometric normal), the
    /// shading normal there, and the pdf. `None` before [`TriangleMesh::prepare_sampling`].
    #[inline]
    pub fn sample_area(&self, u: Vec2) -> Option<(SurfacePoint, Vec3, f32)> {
        if let Some(q) = &self.parallelogram {
            self.area_distribution.as_ref()?;
            let (a, b) = (q.e1 * u.x, q.e2 * u.y);
            let err = crate::math::float::gamma(6) * (q.o.abs() + a.abs() + b.abs()) + q.mismatch;
            return Some((SurfacePoint { p: q.o + a + b, n: q.n, p_error: err }, q.n, 1.0 / self.total_area));
        }
        self.sample_area_uv(u).map(|(sp, ns, pdf, _)| (sp, ns, pdf))
    }

    /// What [`TriangleMesh::sample_area`]'s parallelogram shortcut computes with, for samplers
    /// that do its arithmetic themselves (the path tracer's lanes): the corner, the two edges
    /// and the unit normal, the corner mismatch added to error bounds, and the density `1 /
    /// area`. `None` where the mesh is not sampled as a parallelogram.
    pub(crate) fn parallelogram_sampling(&self) -> Option<([Vec3; 4], f32, f32)> {
        let q = self.parallelogram.as_ref()?;
        self.area_distribution.as_ref()?;
        Some(([q.o, q.e1, q.e2, q.n], q.mismatch, 1.0 / self.total_area))
    }

    /// [`TriangleMesh::sample_area`] that also gives the point's texture coordinates (a
    /// triangle by area, then a uniform point in it; the same density, without the
    /// parallelogram shortcut): for emitters whose radiance is a texture.
    pub fn sample_area_uv(&self, u: Vec2) -> Option<(SurfacePoint, Vec3, f32, Vec2)> {
        let dist = self.area_distribution.as_ref()?;
        let (tri, u_rest) = dist.sample(u.x);
        let i = tri.value;
        let b = sample_uniform_triangle(Vec2::new(u_rest, u.y)).value;
        let p = self.triangle(i);
        let x = p[0] * b.x + p[1] * b.y + p[2] * b.z;
        let err = crate::math::float::gamma(6) * ((b.x * p[0]).abs() + (b.y * p[1]).abs() + (b.z * p[2]).abs());
        let ng = self.face_normal(i);
        let (ns, uv) = self.shading(i, [b.x, b.y, b.z], ng);
        Some((SurfacePoint { p: x, n: ng, p_error: err }, ns, 1.0 / self.total_area, uv))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_shapes_have_expected_area_and_orientation() {
        let r = TriangleMesh::rectangle();
        assert!((r.area() - 4.0).abs() < 1e-6);
        assert!((r.face_normal(0) - Vec3::Z).length() < 1e-6 && (r.face_normal(1) - Vec3::Z).length() < 1e-6);
        let c = TriangleMesh::cube();
        assert!((c.area() - 24.0).abs() < 1e-5);
        for i in 0..c.len() {
            let p = c.triangle(i);
            let centroid = (p[0] + p[1] + p[2]) / 3.0;
            assert!(c.face_normal(i).dot(centroid) > 0.0, "cube face {i} not outward");
        }
    }

    #[test]
    fn cached_face_normals_match_and_a_transform_drops_them() {
        let mut c = TriangleMesh::cube();
        c.prepare_normals();
        for i in 0..c.len() {
            assert_eq!(c.face_normal(i), c.normal_of(&c.triangle(i)));
        }
        c.transform(&Transform::rotate(Vec3::Y, 30.0).unwrap());
        for i in 0..c.len() {
            assert_eq!(c.face_normal(i), c.normal_of(&c.triangle(i)), "stale normal of face {i}");
        }
    }

    /// Mitsuba's vertex normals of a mesh without any: on a welded octahedron each vertex has
    /// four faces meeting at equal angles, so its normal points along the vertex; a square pyramid
    /// with a non-uniform base shows the angle weighting (not area, not plain average); a
    /// planar mesh stays flat (no normals).
    #[test]
    fn smooth_vertex_normals_are_angle_weighted() {
        let p = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let idx = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        let mut octa = TriangleMesh::new(p.clone(), Vec::new(), Vec::new(), idx).unwrap();
        octa.compute_vertex_normals();
        for (n, v) in octa.normals.iter().zip(&p) {
            assert!((*n - *v).length() < 1e-6, "{n} at {v}");
        }
        // Apex (0, 0, 1) over the base corners (±1, 0, 0), (0, ±1, 0), (2, 0, 0)-stretched on +x:
        // the faces meet the corner (2, 0, 0) at different angles.
        let p = vec![Vec3::new(2.0, 0.0, 0.0), Vec3::Y, -Vec3::X, -Vec3::Y, Vec3::Z];
        let idx = vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        let mut pyramid = TriangleMesh::new(p.clone(), Vec::new(), Vec::new(), idx.clone()).unwrap();
        pyramid.compute_vertex_normals();
        let apex = pyramid.normals[4];
        let mut want = Vec3::ZERO;
        for t in &idx {
            let q = [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]];
            let n = (q[1] - q[0]).cross(q[2] - q[0]).normalize();
            want += n * (q[0] - q[2]).normalize().dot((q[1] - q[2]).normalize()).acos();
        }
        assert!((apex - want.normalize()).length() < 1e-5, "{apex} vs {}", want.normalize());
        assert!(apex.x < 0.0, "the wide faces on +x meet the apex at small angles: {apex}");
        let mut quad = TriangleMesh::rectangle();
        quad.normals.clear();
        quad.compute_vertex_normals();
        assert!(quad.normals.is_empty(), "a planar mesh stays flat");
    }

    #[test]
    fn mirror_transform_keeps_orientation_consistent() {
        let mut c = TriangleMesh::cube();
        c.transform(&Transform::scale(Vec3::new(-1.0, 2.0, 1.0)).unwrap());
        for i in 0..c.len() {
            let p = c.triangle(i);
            let centroid = (p[0] + p[1] + p[2]) / 3.0;
            assert!(c.face_normal(i).dot(centroid) > 0.0, "face {i} turned inward");
        }
        assert!((c.area() - (2.0 * (4.0 * 2.0 + 4.0 * 2.0 + 4.0))).abs() < 1e-4);
    }

    #[test]
    fn area_sampling_is_uniform_over_triangles() {
        let mut c = TriangleMesh::cube();
        c.transform(&Transform::scale(Vec3::new(3.0, 1.0, 0.5)).unwrap());
        assert!(c.prepare_sampling());
        let total = c.area();
        let counts = {
            let mut k = vec![0.0; 6];
            let mut rng = crate::sampling::Pcg32::new(2, 2);
            for _ in 0..300_000 {
                let (sp, _, pdf) = c.sample_area(crate::testkit::u2(&mut rng)).unwrap();
                assert!((pdf - 1.0 / total).abs() < 1e-6);
                let a = sp.n.abs();
                let face = if a.x > 0.5 {
                    0
                } else if a.y > 0.5 {
                    2
                } else {
                    4
                } + usize::from(sp.n.max_element() < 0.5);
                k[face] += 1.0;
            }
            k
        };
        let face_area = [2.0, 2.0, 6.0, 6.0, 12.0, 12.0];
        let expected: Vec<f64> = face_area.iter().map(|a| a / total as f64 * 300_000.0).collect();
        let out = crate::testkit::pearson(&counts, &expected, &crate::testkit::Chi2Config::default());
        assert!(out.passed(), "{out}");
        assert!(TriangleMesh::new(vec![Vec3::ZERO], vec![], vec![], vec![[0, 1, 2]]).is_err());
    }

    /// A placed rectangle (rotated like the Cornell box light, so its corners carry round-off)
    /// is sampled as a parallelogram: pdf 1/area, every point on the rectangle within its error
    /// bound, and uniform (χ² over a 6×6 grid of the rectangle's own coordinates).
    #[test]
    fn rectangles_are_sampled_uniformly_as_parallelograms() {
        let t = Transform::translate(Vec3::new(0.2, 0.99, 0.01))
            * Transform::rotate(Vec3::new(1.0, 0.3, 0.0), 90.0).unwrap()
            * Transform::scale(Vec3::new(0.23, 0.6, 1.0)).unwrap();
        let mut r = TriangleMesh::rectangle();
        r.transform(&t);
        assert!(r.prepare_sampling());
        assert!(r.parallelogram.is_some(), "a placed rectangle must be found to be a parallelogram");
        let (n_bins, n) = (6usize, 360_000usize);
        let mut counts = vec![0.0; n_bins * n_bins];
        let mut rng = crate::sampling::Pcg32::new(5, 1);
        let to_local = t.inverse();
        for _ in 0..n {
            let (sp, ns, pdf) = r.sample_area(crate::testkit::u2(&mut rng)).unwrap();
            assert_eq!(pdf, 1.0 / r.area());
            assert_eq!(sp.n, r.face_normal(0));
            assert_eq!(ns, sp.n);
            // Distance to the plane of the triangles within the error bound.
            let off_plane = (sp.p - r.positions[0]).dot(sp.n).abs();
            assert!(off_plane <= sp.p_error.length() + 1e-7, "{off_plane} vs {:?}", sp.p_error);
            let l = to_local.apply_point(sp.p);
            assert!(l.x.abs() <= 1.0 + 1e-5 && l.y.abs() <= 1.0 + 1e-5, "{l} outside the rectangle");
            let bin = |c: f32| (((c + 1.0) / 2.0 * n_bins as f32) as usize).min(n_bins - 1);
            counts[bin(l.y) * n_bins + bin(l.x)] += 1.0;
        }
        let expected = vec![n as f64 / (n_bins * n_bins) as f64; n_bins * n_bins];
        let out = crate::testkit::pearson(&counts, &expected, &crate::testkit::Chi2Config::default());
        assert!(out.passed(), "{out}");
    }

    /// Two-triangle meshes that are not flat parallelograms (a kite, a folded quad, opposite
    /// windings) or have vertex normals keep the triangle-by-area sampling.
    #[test]
    fn other_two_triangle_meshes_are_not_parallelograms() {
        let quad = |d: Vec3, normals: bool, indices: Vec<[u32; 3]>| {
            let p = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0) + d, Vec3::Y];
            let nv = if normals { vec![Vec3::Z; 4] } else { vec![] };
            let mut m = TriangleMesh::new(p, nv, vec![], indices).unwrap();
            assert!(m.prepare_sampling());
            m.parallelogram.is_some()
        };
        let ccw = vec![[0, 1, 2], [0, 2, 3]];
        assert!(quad(Vec3::ZERO, false, ccw.clone()), "the unit square is one");
        assert!(quad(Vec3::ZERO, false, vec![[1, 2, 3], [3, 0, 1]]), "either diagonal");
        assert!(!quad(Vec3::new(0.5, 0.5, 0.0), false, ccw.clone()), "kite");
        assert!(!quad(Vec3::new(0.0, 0.0, 0.5), false, ccw.clone()), "folded");
        assert!(!quad(Vec3::ZERO, false, vec![[0, 1, 2], [0, 3, 2]]), "opposite windings");
        assert!(!quad(Vec3::ZERO, true, ccw), "vertex normals");
        // Unwelded: six vertices, corners matched by position.
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let mut m = TriangleMesh::new(p.to_vec(), vec![], vec![], vec![[0, 1, 2], [3, 4, 5]]).unwrap();
        assert!(m.prepare_sampling() && m.parallelogram.is_some());
    }
}
