//! Mitsuba 3's ellipsoid primitives — the point clouds of anisotropic ellipsoids that 3D
//! Gaussian splatting and volumetric-primitive methods produce: the analytic `ellipsoids`
//! (shells seen from outside only: a ray that starts inside an ellipsoid, or whose nearer
//! crossing lies behind its origin, passes through it) and `ellipsoidsmesh` (each ellipsoid's
//! shell a triangle mesh, a template scaled to enclose the unit sphere, hit from both sides).
//!
//! An ellipsoid is a centre `c`, a rotation `R` (from a unit quaternion) and semi-axes `s`
//! (world units, the file's scales times the shape's `extent`): the points `c + R (s ⊙ u)` for
//! unit vectors `u`. Its outward normal at the local point `l = Rᵀ (p − c)` is `R (l / s²)`,
//! normalized. There is no parameterization (uv = 0, no ∂p/∂u) and no area to sample, as in
//! Mitsuba.

use super::sphere::SurfacePoint;
use super::TriangleMesh;
use crate::math::float::gamma;
use crate::math::{Bounds3, Mat3, Ray, Transform, Vec3};
use glam::{DMat3, DVec3};

/// The first element of a point file (PLY) as a table: one row per item, one column per
/// property, single precision.
#[derive(Clone, Debug, Default)]
pub struct PointTable {
    /// Column names, in the file's order.
    pub names: Vec<String>,
    /// Values, row after row (`names.len()` per row).
    pub values: Vec<f32>,
}

/// One ellipsoid, world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    /// Centre.
    pub center: Vec3,
    /// Rotation: its columns are the world directions of the ellipsoid's local axes.
    pub rotation: Mat3,
    /// Semi-axes along the local axes (world units).
    pub scale: Vec3,
}

impl Ellipsoid {
    /// `R diag(s)`: its semi-axes as world vectors (the columns).
    #[inline]
    pub fn axes(&self) -> Mat3 {
        Mat3::from_cols(
            self.rotation.x_axis * self.scale.x,
            self.rotation.y_axis * self.scale.y,
            self.rotation.z_axis * self.scale.z,
        )
    }
}

/// Ellipsoids as a file describes them (before the shape's `extent`), with the per-ellipsoid
/// opacity a 3D-Gaussian file carries (used by `extent_adaptive_clamping`).
#[derive(Clone, Debug, Default)]
pub struct EllipsoidSet {
    /// The ellipsoids, scales as read (after activation, `scale_factor` and `to_world`).
    pub ellipsoids: Vec<Ellipsoid>,
    /// Per-ellipsoid opacity in (0, 1), if the file has one: a 3D-Gaussian file's `opacity`
    /// column after the sigmoid, clipped to [10⁻⁸, 1 − 10⁻⁸], or a one-column `opacities_*`
    /// group of another file (Mitsuba's attribute `opacities`).
    pub opacities: Option<Vec<f32>>,
}

impl EllipsoidSet {
    /// Mitsuba's reading of an ellipsoid point file: the columns must begin with `x y z nx ny
    /// nz` and end with `scale_0 scale_1 scale_2 rot_0 rot_1 rot_2 rot_3`; whatever lies
    /// between are attributes (a 3D-Gaussian file — `f_dc_0` first, `opacity` last among them —
    /// carries spherical-harmonic colours and an opacity; other files groups of columns named
    /// `NAME_k`). The centre is placed by `to_world`; the scale is `exp` of the file's (at least
    /// 10⁻⁶), times `scale_factor` and the mean of the diagonal of `to_world`'s stretch (its
    /// polar decomposition `M = Q S`); the quaternion `(rot_0, rot_1, rot_2, rot_3)` = (w, x, y,
    /// z), normalized, is turned by `Q`. Non-finite values and zero quaternions are refused.
    pub fn from_table(table: &PointTable, scale_factor: f32, to_world: &Transform) -> Result<EllipsoidSet, String> {
        let names = &table.names;
        let n = names.len();
        const HEAD: [&str; 6] = ["x", "y", "z", "nx", "ny", "nz"];
        const TAIL: [&str; 7] = ["scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"];
        let ok = n >= 13
            && names[..6].iter().zip(HEAD).all(|(a, b)| a == b)
            && names[n - 7..].iter().zip(TAIL).all(|(a, b)| a == b);
        if !ok {
            return Err(format!(
                "the columns must begin with 'x y z nx ny nz' and end with 'scale_0 scale_1 scale_2 rot_0 rot_1 rot_2 \
                 rot_3' (as Mitsuba's ellipsoids read them), found '{}'",
                names.join(" ")
            ));
        }
        let (stretch, q) = polar_decomposition(to_world);
        let to_world_scale = (stretch.x_axis.x + stretch.y_axis.y + stretch.z_axis.z) / 3.0;
        let gaussians = names[6] == "f_dc_0" && names[n - 8] == "opacity";
        // The opacity column: a 3D-Gaussian file's, or a lone `opacities_*` column group.
        let opacity_column = if gaussians {
            Some(n - 8)
        } else {
            let group = |k: usize| names[k].rsplit_once('_').map_or(names[k].as_str(), |(p, _)| p);
            let mut start = 6;
            let mut found = None;
            while start < n - 7 {
                let mut end = start + 1;
                while end < n - 7 && group(end) == group(start) {
                    end += 1;
                }
                if group(start) == "opacities" && end - start == 1 {
                    found = Some(start);
                }
                start = end;
            }
            found
        };
        let rows = table.values.chunks_exact(n.max(1));
        let mut ellipsoids = Vec::with_capacity(rows.len());
        let mut opacities = opacity_column.map(|_| Vec::with_capacity(rows.len()));
        for (i, row) in rows.enumerate() {
            if let Some(k) = row.iter().position(|v| !v.is_finite()) {
                return Err(format!("ellipsoid {i}: '{}' is not finite ({})", names[k], row[k]));
            }
            let center = to_world.apply_point(Vec3::new(row[0], row[1], row[2]));
            let scale = (Vec3::new(row[n - 7], row[n - 6], row[n - 5]).exp().max(Vec3::splat(1e-6)) * scale_factor)
                .as_dvec3()
                * to_world_scale.abs();
            let quat =
                glam::DQuat::from_xyzw(row[n - 3] as f64, row[n - 2] as f64, row[n - 1] as f64, row[n - 4] as f64);
            if quat.length_squared() == 0.0 {
                return Err(format!("ellipsoid {i}: the quaternion (rot_0 … rot_3) is zero"));
            }
            let rotation = q * DMat3::from_quat(quat.normalize());
            let (scale, rotation) = (scale.as_vec3(), rotation.as_mat3());
            if !(scale.is_finite() && center.is_finite()) {
                return Err(format!("ellipsoid {i}: its scale or centre overflows"));
            }
            ellipsoids.push(Ellipsoid { center, rotation, scale });
            if let (Some(o), Some(k)) = (opacities.as_mut(), opacity_column) {
                let v = row[k];
                // A 3D-Gaussian file stores the logit: the sigmoid activation, clipped.
                o.push(if gaussians { (1.0 / (1.0 + (-v).exp())).clamp(1e-8, 1.0 - 1e-8) } else { v });
            }
        }
        Ok(EllipsoidSet { ellipsoids, opacities })
    }

    /// Each ellipsoid's extent (the factor its scale is multiplied by): `extent`, or with
    /// `adaptive` (Mitsuba's `extent_adaptive_clamping`) `extent · √(2 ln(opacity / 0.01)) / 3`,
    /// the radius where the Gaussian falls to 0.01 — not positive (no shell) for an opacity at or
    /// below 0.01. `None` if `adaptive` is asked of a set without opacities.
    pub fn extents(&self, extent: f32, adaptive: bool) -> Option<Vec<f32>> {
        if !adaptive {
            return Some(vec![extent; self.ellipsoids.len()]);
        }
        let opacities = self.opacities.as_ref()?;
        Some(opacities.iter().map(|&o| (2.0 * (o / 0.01).ln()).sqrt() * extent / 3.0).collect())
    }
}

/// The polar decomposition `M = Q S` of `t`'s linear part (`Q` orthogonal, `S` symmetric), by
/// Newton's iteration `Q ← (Q + Q⁻ᵀ) / 2` (at most 25 steps, as Mitsuba's `transform_decompose`),
/// with `Q` and `S` negated when `Q` is a reflection, so that `Q` is a rotation. Returns `(S, Q)`.
fn polar_decomposition(t: &Transform) -> (DMat3, DMat3) {
    let m = DMat3::from_mat4(t.matrix().as_dmat4());
    let mut q = m;
    for _ in 0..25 {
        let next = (q + q.inverse().transpose()) * 0.5;
        let done = (next - q).to_cols_array().iter().all(|d| d.abs() < 1e-15);
        q = next;
        if done {
            break;
        }
    }
    if !q.is_finite() {
        return (DMat3::IDENTITY, DMat3::IDENTITY);
    }
    if q.determinant() < 0.0 {
        q = -q;
    }
    (q.transpose() * m, q)
}

/// An ellipsoid prepared for ray tests (double precision, as Mitsuba's scalar variants test).
#[derive(Clone, Copy, Debug)]
struct Prepared {
    center: DVec3,
    /// Rows of `diag(1/s) Rᵀ`: world offsets to the local unit-sphere frame.
    to_unit: [DVec3; 3],
    /// `R diag(s)`: the unit-sphere frame to world offsets.
    from_unit: DMat3,
}

/// Mitsuba's analytic `ellipsoids`: one primitive per ellipsoid, hit from outside only.
#[derive(Clone, Debug)]
pub struct Ellipsoids {
    ellipsoids: Vec<Ellipsoid>,
    prepared: Vec<Prepared>,
}

impl Ellipsoids {
    /// The shells of `set`, each scale multiplied by its extent. An ellipsoid whose extent is
    /// not positive has no shell (Mitsuba's test fails on it too): it is never hit.
    pub fn new(set: &EllipsoidSet, extents: &[f32]) -> Ellipsoids {
        let mut ellipsoids = Vec::with_capacity(set.ellipsoids.len());
        let mut prepared = Vec::with_capacity(set.ellipsoids.len());
        for (e, &k) in set.ellipsoids.iter().zip(extents) {
            let scale = if k > 0.0 { e.scale * k } else { Vec3::ZERO };
            let e = Ellipsoid { scale, ..*e };
            let r = e.rotation.as_dmat3();
            let s = scale.as_dvec3();
            let inv = DVec3::ONE / s;
            prepared.push(Prepared {
                center: e.center.as_dvec3(),
                to_unit: [r.x_axis * inv.x, r.y_axis * inv.y, r.z_axis * inv.z],
                from_unit: DMat3::from_cols(r.x_axis * s.x, r.y_axis * s.y, r.z_axis * s.z),
            });
            ellipsoids.push(e);
        }
        Ellipsoids { ellipsoids, prepared }
    }

    /// Number of ellipsoids.
    pub fn len(&self) -> usize {
        self.ellipsoids.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.ellipsoids.is_empty()
    }

    /// Ellipsoid `i` (its scale including the extent).
    pub fn ellipsoid(&self, i: usize) -> &Ellipsoid {
        &self.ellipsoids[i]
    }

    /// The bounds of ellipsoid `i`: along world axis k its half-width is the length of row k of
    /// `R diag(s)`, padded by a few units of rounding.
    pub fn bounds(&self, i: usize) -> Bounds3 {
        let e = &self.ellipsoids[i];
        let m = e.axes();
        let half = Vec3::new(m.row(0).length(), m.row(1).length(), m.row(2).length());
        let half = half + gamma(4) * (half + e.center.abs());
        Bounds3::new(e.center - half, e.center + half)
    }

    /// The distance to ellipsoid `i` along `ray` within `(0, t_max)`: the nearer crossing of its
    /// shell, if that lies ahead — a ray starting inside, or whose nearer crossing is behind
    /// it, misses (Mitsuba's backface culling).
    #[inline]
    pub fn intersect(&self, i: usize, ray: &Ray, t_max: f32) -> Option<f32> {
        let e = &self.prepared[i];
        let oc = ray.o.as_dvec3() - e.center;
        let d = ray.d.as_dvec3();
        let o = DVec3::new(e.to_unit[0].dot(oc), e.to_unit[1].dot(oc), e.to_unit[2].dot(oc));
        let d = DVec3::new(e.to_unit[0].dot(d), e.to_unit[1].dot(d), e.to_unit[2].dot(d));
        // |o + t d|² = 1: a t² − 2 b t + c = 0 with b = −o·d; the discriminant a (1 − |f|²), f the
        // offset of the closest approach to the centre (Ray Tracing Gems II, as Mitsuba).
        let a = d.length_squared();
        let b = -o.dot(d);
        let c = o.length_squared() - 1.0;
        let f = o + (b / a) * d;
        let disc = a * (1.0 - f.length_squared());
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let q = b + disc.sqrt().copysign(b);
        let (t0, t1) = (c / q, q / a);
        let near = t0.min(t1);
        // Not NaN (a zero-scale ellipsoid, a zero `q`), ahead of the origin and before t_max.
        (near > 0.0 && near < t_max as f64).then_some(near as f32)
    }

    /// The point at distance `t` along `ray` on ellipsoid `i`, reprojected onto its shell, with
    /// its error bound and outward unit normal.
    #[inline]
    pub fn surface(&self, i: usize, ray: &Ray, t: f32) -> SurfacePoint {
        let e = &self.prepared[i];
        let oc = ray.o.as_dvec3() + ray.d.as_dvec3() * t as f64 - e.center;
        let u = DVec3::new(e.to_unit[0].dot(oc), e.to_unit[1].dot(oc), e.to_unit[2].dot(oc)).normalize_or_zero();
        let offset = e.from_unit * u;
        let p = e.center + offset;
        // ∇ of |Rᵀ(p − c) / s|² ∝ R (u / s): the transposed rows of the world-to-unit map times u.
        let n = (e.to_unit[0] * u.x + e.to_unit[1] * u.y + e.to_unit[2] * u.z).normalize_or_zero();
        // Computed in double precision: the error is the final rounding, bounded generously.
        let p_error = gamma(3) * (e.center.abs() + offset.abs()).as_vec3();
        SurfacePoint { p: p.as_vec3(), n: n.as_vec3(), p_error }
    }
}

/// The template shell of an `ellipsoidsmesh`: Mitsuba's three, or a mesh's triangles.
#[derive(Clone, Debug)]
pub enum Shell {
    /// A cube (12 triangles).
    Box,
    /// An icosahedron (20 triangles), a vertex on each pole of local y: Mitsuba's default.
    IcoSphere,
    /// A UV sphere of 9 segments and 5 bands about local y (72 triangles).
    UvSphere,
    /// A mesh's vertices and triangles, as placed by its own `to_world`.
    Mesh(Vec<Vec3>, Vec<[u32; 3]>),
}

impl Shell {
    /// The template's vertices and outward-wound triangles, scaled (as Mitsuba scales them) so
    /// that every vertex and every triangle's centroid lie at least at distance 1 from the
    /// origin: the shell encloses the unit sphere. `None` if a vertex or centroid is at the
    /// origin.
    pub fn template(&self) -> Option<(Vec<Vec3>, Vec<[u32; 3]>)> {
        let (vertices, faces) = match self {
            Shell::Box => {
                let mesh = TriangleMesh::cube();
                (mesh.positions.clone(), mesh.indices.clone())
            }
            Shell::IcoSphere => icosahedron(),
            Shell::UvSphere => uv_sphere(9, 5),
            Shell::Mesh(v, f) => (v.clone(), f.clone()),
        };
        let nearest = faces
            .iter()
            .flat_map(|f| {
                let [a, b, c] = f.map(|k| vertices[k as usize]);
                [a.length(), b.length(), c.length(), ((a + b + c) / 3.0).length()]
            })
            .fold(f32::INFINITY, f32::min);
        (nearest > 0.0 && nearest.is_finite()).then(|| (vertices.iter().map(|v| *v / nearest).collect(), faces))
    }
}

/// The icosahedron with a vertex on each pole of y (−y first), its rings at y = ∓1/√5 turned by
/// 36° from each other, outward triangles; unit circumradius.
fn icosahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (y, r) = (1.0 / 5f32.sqrt(), 2.0 / 5f32.sqrt());
    let ring = |y: f32, start_deg: f32| {
        (0..5).map(move |k| {
            let a = (start_deg + 72.0 * k as f32).to_radians();
            Vec3::new(r * a.cos(), y, r * a.sin())
        })
    };
    let mut v = vec![Vec3::new(0.0, -1.0, 0.0)];
    v.extend(ring(-y, 36.0));
    // The upper ring starts at 72° (then 144°, 216°, 288°, 0°).
    v.extend(ring(y, 72.0));
    v.push(Vec3::Y);
    let faces = vec![
        [0, 1, 2],
        [1, 0, 5],
        [0, 2, 3],
        [0, 3, 4],
        [0, 4, 5],
        [1, 5, 10],
        [2, 1, 6],
        [3, 2, 7],
        [4, 3, 8],
        [5, 4, 9],
        [1, 10, 6],
        [2, 6, 7],
        [3, 7, 8],
        [4, 8, 9],
        [5, 9, 10],
        [6, 10, 11],
        [7, 6, 11],
        [8, 7, 11],
        [9, 8, 11],
        [10, 9, 11],
    ];
    (v, faces)
}

/// A UV sphere about y: `segments` meridians from −z towards +x, `bands` bands of equal polar
/// angle (`bands − 1` rings and two poles), outward triangles; unit radius.
fn uv_sphere(segments: u32, bands: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for ring in 1..bands {
        let (sin_t, cos_t) = (std::f32::consts::PI * ring as f32 / bands as f32).sin_cos();
        for k in 0..segments {
            let (sin_p, cos_p) = (std::f32::consts::TAU * k as f32 / segments as f32).sin_cos();
            v.push(Vec3::new(sin_t * sin_p, cos_t, -sin_t * cos_p));
        }
    }
    let (top, bottom) = (v.len() as u32, v.len() as u32 + 1);
    v.push(Vec3::Y);
    v.push(-Vec3::Y);
    let at = |ring: u32, k: u32| ring * segments + k % segments;
    let mut faces = Vec::new();
    for k in 0..segments {
        faces.push([top, at(0, k + 1), at(0, k)]);
        for ring in 0..bands - 2 {
            let (a, b, c, d) = (at(ring, k), at(ring, k + 1), at(ring + 1, k + 1), at(ring + 1, k));
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
        faces.push([bottom, at(bands - 2, k), at(bands - 2, k + 1)]);
    }
    (v, faces)
}

/// Mitsuba's `ellipsoidsmesh`: every ellipsoid's copy of the template shell (see
/// [`Shell::template`]), placed by `c + R (s · extent ⊙ v)`, one mesh with face normals;
/// triangle `k` belongs to ellipsoid `k / (the template's triangles)`. An ellipsoid whose extent
/// is not positive gets its shell collapsed onto its centre (never hit). An error if the template
/// is degenerate, or the shells would hold more than [`MAX_SHELL_VERTICES`] vertices.
pub fn shell_mesh(set: &EllipsoidSet, extents: &[f32], shell: &Shell) -> Result<TriangleMesh, String> {
    let (template, faces) = shell
        .template()
        .ok_or("the shell has a vertex or a face centred at its origin (it cannot enclose the sphere)")?;
    let total = set.ellipsoids.len().saturating_mul(template.len());
    if total > MAX_SHELL_VERTICES {
        return Err(format!(
            "{} ellipsoids × {} shell vertices is more than {MAX_SHELL_VERTICES} vertices",
            set.ellipsoids.len(),
            template.len()
        ));
    }
    let mut positions = Vec::with_capacity(set.ellipsoids.len() * template.len());
    let mut indices = Vec::with_capacity(set.ellipsoids.len() * faces.len());
    for (e, &k) in set.ellipsoids.iter().zip(extents) {
        let base = positions.len() as u32;
        // No shell: collapsed onto the centre (never hit), keeping the triangles' numbering.
        let k = if k > 0.0 { k } else { 0.0 };
        let m = e.axes();
        positions.extend(template.iter().map(|v| e.center + m * (*v * k)));
        indices.extend(faces.iter().map(|f| f.map(|i| i + base)));
    }
    let mut mesh = TriangleMesh::new(positions, Vec::new(), Vec::new(), indices).map_err(|e| e.to_string())?;
    // The AOV `prim_index` counts ellipsoids, as Mitsuba's does.
    mesh.faces_per_primitive = faces.len() as u32;
    Ok(mesh)
}

/// The most vertices an `ellipsoidsmesh` may have (3 GiB of positions; a 3D-Gaussian capture of
/// millions of Gaussians with 38-vertex `uv_sphere` shells stays well below).
pub const MAX_SHELL_VERTICES: usize = 1 << 28;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat4;
    use crate::sampling::Pcg32;

    fn table(names: &[&str], rows: &[&[f32]]) -> PointTable {
        PointTable { names: names.iter().map(|s| s.to_string()).collect(), values: rows.concat() }
    }

    const PLAIN: [&str; 13] =
        ["x", "y", "z", "nx", "ny", "nz", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"];

    /// Random ellipsoids: centres in [-2, 2]³, semi-axes 0.05–1, random orientations.
    fn random_set(rng: &mut Pcg32, n: usize) -> EllipsoidSet {
        let mut rows = Vec::new();
        for _ in 0..n {
            let mut row = vec![0.0; 13];
            for v in &mut row[..3] {
                *v = 4.0 * rng.next_f32() - 2.0;
            }
            for v in &mut row[6..9] {
                *v = (0.05 + 0.95 * rng.next_f32()).ln();
            }
            for v in &mut row[9..] {
                *v = 2.0 * rng.next_f32() - 1.0;
            }
            rows.push(row);
        }
        let rows: Vec<&[f32]> = rows.iter().map(|r| r.as_slice()).collect();
        EllipsoidSet::from_table(&table(&PLAIN, &rows), 1.0, &Transform::IDENTITY).unwrap()
    }

    /// A uniformly distributed unit vector.
    fn unit(rng: &mut Pcg32) -> Vec3 {
        crate::sampling::sample_uniform_sphere(crate::math::Vec2::new(rng.next_f32(), rng.next_f32())).value
    }

    /// `|Rᵀ (p − c) / s|`: 1 on the shell.
    fn unit_radius(e: &Ellipsoid, p: Vec3) -> f32 {
        (e.rotation.transpose() * (p - e.center) / e.scale).length()
    }

    /// Hits lie on the shell, with the normalized gradient as normal; a ray starting inside
    /// misses, as does one whose nearer crossing lies behind it or beyond `t_max`.
    #[test]
    fn hits_lie_on_the_shell_and_back_faces_are_culled() {
        let mut rng = Pcg32::new(5, 1);
        let set = random_set(&mut rng, 64);
        let shells = Ellipsoids::new(&set, &[1.5; 64]);
        let mut hits = 0;
        for i in 0..shells.len() {
            let e = *shells.ellipsoid(i);
            for _ in 0..50 {
                let dir = unit(&mut rng);
                let target = e.center + e.rotation * (e.scale * 0.9 * dir);
                let origin = target + 5.0 * unit(&mut rng);
                let ray = Ray::new(origin, (target - origin).normalize());
                let t = shells.intersect(i, &ray, f32::INFINITY).expect("aimed inside the ellipsoid from outside");
                let sp = shells.surface(i, &ray, t);
                assert!((unit_radius(&e, sp.p) - 1.0).abs() < 1e-5, "{}", unit_radius(&e, sp.p));
                assert!((sp.p - ray.at(t)).length() < 1e-4 * (1.0 + t));
                let grad =
                    (e.rotation * ((e.rotation.transpose() * (sp.p - e.center)) / (e.scale * e.scale))).normalize();
                assert!((sp.n - grad).length() < 1e-4, "{} {grad}", sp.n);
                assert!(sp.n.dot(ray.d) < 0.0, "the nearer crossing faces the ray");
                assert!((sp.p - ray.at(t)).abs().cmple(sp.p_error + 1e-4 * (1.0 + t)).all());
                // The hit is within the ellipsoid's bounds.
                let b = shells.bounds(i);
                assert!(Bounds3::new(b.min - Vec3::splat(1e-5), b.max + Vec3::splat(1e-5)).contains(sp.p));
                // From the target (inside) nothing of this ellipsoid is hit.
                assert_eq!(shells.intersect(i, &Ray::new(target, ray.d), f32::INFINITY), None);
                // Beyond the shell, looking back along the ray: the nearer crossing is behind.
                let beyond = origin + ray.d * (t + 4.0 * e.scale.max_element());
                assert_eq!(shells.intersect(i, &Ray::new(beyond, ray.d), f32::INFINITY), None);
                assert_eq!(shells.intersect(i, &ray, t * 0.999), None);
                hits += 1;
            }
        }
        assert_eq!(hits, 64 * 50);
    }

    /// The bounds are the tightest box: each face touches the shell at its support point.
    #[test]
    fn bounds_are_tight() {
        let mut rng = Pcg32::new(9, 3);
        let set = random_set(&mut rng, 32);
        let shells = Ellipsoids::new(&set, &[1.0; 32]);
        for i in 0..shells.len() {
            let e = shells.ellipsoid(i);
            let b = shells.bounds(i);
            let m = e.axes();
            for k in 0..3 {
                // The support point along +e_k: c + M Mᵀ e_k / |Mᵀ e_k|.
                let row = m.row(k);
                let p = e.center + m * (row / row.length());
                assert!((unit_radius(e, p) - 1.0).abs() < 1e-5);
                assert!((b.max[k] - p[k]).abs() < 1e-5 * (1.0 + p[k].abs()), "axis {k}: {} vs {}", b.max[k], p[k]);
                assert!(b.max[k] >= p[k]);
            }
        }
    }

    /// Mitsuba's reading of the file: exp of the scales (at least 10⁻⁶), the quaternion
    /// normalized with its real part first, `scale_factor`, and `to_world` moving the centres,
    /// stretching by its mean scale and turning by its rotation — a mirroring one as its
    /// rotation part (an ellipsoid is symmetric about its centre: the same shell).
    #[test]
    fn reads_files_as_mitsuba() {
        let row: &[f32] = &[1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 0.5f32.ln(), -30.0, 0.0, 2.0, 0.0, 0.0, 2.0];
        let set = EllipsoidSet::from_table(&table(&PLAIN, &[row]), 2.0, &Transform::IDENTITY).unwrap();
        let e = set.ellipsoids[0];
        assert_eq!(e.center, Vec3::new(1.0, 2.0, 3.0));
        assert!((e.scale - Vec3::new(1.0, 2e-6, 2.0)).abs().max_element() < 1e-6, "{}", e.scale);
        // (w, x, y, z) = (1, 0, 0, 1)/√2: 90° about z.
        assert!((e.rotation * Vec3::X - Vec3::Y).length() < 1e-6);
        assert!(set.opacities.is_none());

        let t = Transform::translate(Vec3::new(0.5, 0.0, -1.0))
            * Transform::rotate(Vec3::new(1.0, 2.0, 3.0), 40.0).unwrap()
            * Transform::scale(Vec3::splat(3.0)).unwrap();
        let placed = EllipsoidSet::from_table(&table(&PLAIN, &[row]), 2.0, &t).unwrap().ellipsoids[0];
        assert!((placed.center - t.apply_point(e.center)).length() < 1e-5);
        assert!((placed.scale - 3.0 * e.scale).abs().max_element() < 1e-5);
        // Points on the shell map to points on the placed shell.
        let mirror = Transform::scale(Vec3::new(-1.0, 1.0, 1.0)).unwrap() * t;
        let mirrored = EllipsoidSet::from_table(&table(&PLAIN, &[row]), 2.0, &mirror).unwrap().ellipsoids[0];
        let wide = Ellipsoid { scale: Vec3::new(1.0, 0.3, 2.0), ..e };
        let mut rng = Pcg32::new(1, 1);
        for _ in 0..20 {
            let u = unit(&mut rng);
            let p = wide.center + wide.rotation * (wide.scale * u);
            for (x, placed) in [(t, placed), (mirror, mirrored)] {
                let placed = Ellipsoid { scale: placed.scale / e.scale * wide.scale, ..placed };
                assert!((unit_radius(&placed, x.apply_point(p)) - 1.0).abs() < 1e-5);
            }
        }
    }

    /// Polar decomposition of a sheared map: Q orthonormal with det +1, S symmetric, Q S = M.
    #[test]
    fn polar_decomposition_of_a_shear() {
        let mut m = Mat4::IDENTITY;
        m.y_axis.x = 0.7;
        m.z_axis.y = -0.4;
        m.x_axis.x = 2.0;
        let (s, q) = polar_decomposition(&Transform::from_matrix(m).unwrap());
        assert!((q.transpose() * q - DMat3::IDENTITY).to_cols_array().iter().all(|d| d.abs() < 1e-12));
        assert!((q.determinant() - 1.0).abs() < 1e-12);
        assert!((s - s.transpose()).to_cols_array().iter().all(|d| d.abs() < 1e-12));
        assert!((q * s - DMat3::from_mat4(m.as_dmat4())).to_cols_array().iter().all(|d| d.abs() < 1e-6));
    }

    /// A 3D-Gaussian file's opacities (sigmoid of the logit) and adaptive extents; another file's
    /// `opacities_0` column as it is; errors name the ellipsoid and the column.
    #[test]
    fn opacities_extents_and_errors() {
        let names = [
            "x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
            "rot_0", "rot_1", "rot_2", "rot_3",
        ];
        let row = |logit: f32| -> Vec<f32> {
            vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.2, 0.3, logit, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
        };
        let (a, b) = (row(0.0), row(-6.0));
        let set = EllipsoidSet::from_table(&table(&names, &[&a, &b]), 1.0, &Transform::IDENTITY).unwrap();
        let o = set.opacities.clone().unwrap();
        assert!((o[0] - 0.5).abs() < 1e-7 && (o[1] - 1.0 / (1.0 + 6f32.exp())).abs() < 1e-7);
        let extents = set.extents(3.0, true).unwrap();
        assert!((extents[0] - (2.0 * 50f32.ln()).sqrt()).abs() < 1e-6);
        assert!(extents[1].is_nan() || extents[1] <= 0.0, "opacity 0.0025: no shell");
        let shells = Ellipsoids::new(&set, &extents);
        let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
        assert!(shells.intersect(0, &ray, f32::INFINITY).is_some());
        assert_eq!(shells.intersect(1, &ray, f32::INFINITY), None);
        let mesh = shell_mesh(&set, &extents, &Shell::IcoSphere).unwrap();
        // 4000 ellipsoids of a 70 000-vertex shell: refused before anything is allocated.
        let many = EllipsoidSet { ellipsoids: vec![set.ellipsoids[0]; 4000], opacities: None };
        let huge = Shell::Mesh(vec![Vec3::ONE; 70_000], vec![[0, 1, 2]]);
        let e = shell_mesh(&many, &[1.0; 4000], &huge).unwrap_err();
        assert!(e.contains("more than 268435456 vertices"), "{e}");
        assert_eq!(mesh.len(), 40, "two shells, the second collapsed");
        assert!(mesh.positions[12..].iter().all(|p| *p == set.ellipsoids[1].center));
        assert_eq!(set.extents(2.0, false).unwrap(), vec![2.0, 2.0]);

        let mut names2 = PLAIN.to_vec();
        names2.splice(6..6, ["opacities_0", "color_0", "color_1"]);
        let r: Vec<f32> = vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.25, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
        let set = EllipsoidSet::from_table(&table(&names2, &[&r]), 1.0, &Transform::IDENTITY).unwrap();
        assert_eq!(set.opacities, Some(vec![0.25]));
        assert!(EllipsoidSet::from_table(&table(&PLAIN, &[&r[3..]]), 1.0, &Transform::IDENTITY)
            .unwrap()
            .extents(1.0, true)
            .is_none());

        let e = EllipsoidSet::from_table(&table(&names[..12], &[&a[..12]]), 1.0, &Transform::IDENTITY).unwrap_err();
        assert!(e.contains("must begin with 'x y z nx ny nz' and end with 'scale_0"), "{e}");
        let mut nan = a.clone();
        nan[11] = f32::NAN;
        let e = EllipsoidSet::from_table(&table(&names, &[&a, &nan]), 1.0, &Transform::IDENTITY).unwrap_err();
        assert!(e.contains("ellipsoid 1: 'scale_1' is not finite"), "{e}");
        let mut zero = a.clone();
        zero[13] = 0.0;
        let e = EllipsoidSet::from_table(&table(&names, &[&zero]), 1.0, &Transform::IDENTITY).unwrap_err();
        assert!(e.contains("ellipsoid 0: the quaternion"), "{e}");
    }

    /// The templates: Mitsuba's vertices (printed by Mitsuba 3.9.1 for a unit ellipsoid), outward
    /// triangles, every vertex and centroid at least at distance 1 with one at exactly 1.
    #[test]
    fn shell_templates_enclose_the_unit_sphere_as_mitsuba_s() {
        let mitsuba: [(Shell, usize, &[[f32; 3]]); 3] = [
            (Shell::Box, 12, &[[0.90453404, -0.90453404, -0.90453404], [-0.90453404, 0.90453404, 0.90453404]]),
            (
                Shell::IcoSphere,
                20,
                &[
                    [0.0, -1.2584256, 0.0],
                    [0.9105967, -0.5627868, 0.6615795],
                    [-0.34780997, -0.5627868, 1.0704671],
                    [0.34780997, 0.5627868, 1.0704671],
                    [1.1255673, 0.5627868, 0.0],
                    [0.0, 1.2584256, 0.0],
                ],
            ),
            (
                Shell::UvSphere,
                72,
                &[[0.41696241, 0.89282936, -0.49691695], [1.0336385, -0.34103048, -0.18225807], [0.0, -1.1035978, 0.0]],
            ),
        ];
        for (shell, faces, points) in mitsuba {
            let (v, f) = shell.template().unwrap();
            assert_eq!(f.len(), faces, "{shell:?}");
            for p in points {
                let nearest = v.iter().map(|q| (*q - Vec3::from(*p)).length()).fold(f32::INFINITY, f32::min);
                assert!(nearest < 3e-5, "{shell:?}: {p:?} is {nearest} from the nearest vertex");
            }
            let mut least = f32::INFINITY;
            for t in &f {
                let [a, b, c] = t.map(|k| v[k as usize]);
                let centroid = (a + b + c) / 3.0;
                assert!((b - a).cross(c - a).dot(centroid) > 0.0, "{shell:?}: {t:?} faces inward");
                least = least.min(a.length()).min(b.length()).min(c.length()).min(centroid.length());
            }
            assert!((least - 1.0).abs() < 1e-6, "{shell:?}: {least}");
        }
        assert!(Shell::Mesh(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]).template().is_none());
    }
}
