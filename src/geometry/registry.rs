//! Shape plugins by name: the registry the scene loaders look shapes up in. A shape plugin builds
//! the geometry in world space from its parameters, the shape's `to_world` (already composed
//! with any instance transform) and `flip_normals`; mesh files come from the loader
//! ([`MeshSource`]). What a shape is made of (BSDF, emitter, media) and instancing are the
//! loader's business.

use super::sphere::{Orientation, SphereClip};
use super::{Cylinder, Disk, Geometry, SdfGrid, Sphere, TriangleMesh};
use crate::image::VolumeSource;
use crate::math::{Transform, Vec3};
use crate::props::{Obj, Result};

/// A mesh read from a file, and whether the file asks for flat shading (Mitsuba's serialized
/// format has a flag for it).
#[derive(Clone, Debug)]
pub struct MeshFile {
    /// The mesh, in its own coordinates.
    pub mesh: TriangleMesh,
    /// The file asks for face normals.
    pub face_normals: bool,
}

/// Where shape plugins get their files: the loader resolves the file that the string parameter
/// `name` of `o` names and reads it: a mesh in the format of `o`'s plugin (`obj`, `ply`, or
/// `serialized` with its `shape_index`), or a grid volume (`.vol`, [`VolumeSource`]).
pub trait MeshSource: VolumeSource {
    /// The mesh named by parameter `name` of `o`; errors are located at the parameter.
    fn mesh(&mut self, o: &Obj, name: &str) -> Result<MeshFile>;

    /// The curves a scene format decoded, named by parameter `name` of `o`.
    fn curves(&mut self, o: &Obj, name: &str) -> Result<super::CurveSet>;

    /// The control points of a Mitsuba curve file named by parameter `name` of `o`: curves,
    /// each a list of points with radii (file coordinates).
    fn curve_file(&mut self, o: &Obj, name: &str) -> Result<Vec<Vec<super::roundcurve::ControlPoint>>>;

    /// The first element of the PLY file named by parameter `name` of `o`, as a table.
    fn point_table(&mut self, o: &Obj, name: &str) -> Result<super::ellipsoids::PointTable>;
}

/// A shape plugin's constructor: `(object, to_world, flip_normals, mesh files)`.
pub type ShapePlugin = fn(&Obj, &Transform, bool, &mut dyn MeshSource) -> Result<Geometry>;

/// Every geometric shape plugin by its (Mitsuba) name.
pub const SHAPE_PLUGINS: &[(&str, ShapePlugin)] = &[
    ("obj", mesh_file),
    ("ply", mesh_file),
    ("serialized", mesh_file),
    ("mesh", decoded_mesh),
    ("rectangle", rectangle),
    ("cube", cube),
    ("disk", disk),
    ("sphere", sphere),
    ("cylinder", cylinder),
    ("sdfgrid", sdfgrid),
    ("curve", curve),
    ("linearcurve", round_curve),
    ("bsplinecurve", round_curve),
    ("ellipsoids", ellipsoids),
    ("ellipsoidsmesh", ellipsoids),
];

/// The constructor of the shape plugin `name`.
pub fn shape_plugin(name: &str) -> Option<ShapePlugin> {
    SHAPE_PLUGINS.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}

/// Mitsuba's `obj`, `ply` and `serialized`: `filename`, `face_normals` (false: the file's
/// vertex normals are kept, and a file without them gets smooth angle-weighted ones, as Mitsuba
/// computes; true, or a serialized file's face-normal flag: flat shading); `obj` also
/// `flip_tex_coords` (true: v becomes 1 − v, as Mitsuba's OBJ loader does); `serialized` also
/// `shape_index` (0; read by the loader).
fn mesh_file(o: &Obj, to_world: &Transform, flip: bool, meshes: &mut dyn MeshSource) -> Result<Geometry> {
    let MeshFile { mut mesh, face_normals: flat_file } = meshes.mesh(o, "filename")?;
    let face_normals = o.bool("face_normals", false)? || flat_file;
    if face_normals {
        mesh.normals.clear();
    }
    if o.ty == "obj" && o.bool("flip_tex_coords", true)? {
        for uv in &mut mesh.uvs {
            uv.y = 1.0 - uv.y;
        }
    }
    mesh.transform(to_world);
    if !face_normals {
        mesh.compute_vertex_normals();
    }
    mesh.flip_normals ^= flip;
    Ok(Geometry::Mesh(mesh))
}

/// neumann's `mesh`: a mesh that a scene format decoded itself (glTF's primitives), named by
/// `filename`, with its own normals (none: flat shading, as glTF asks), placed by `to_world`.
fn decoded_mesh(o: &Obj, to_world: &Transform, flip: bool, meshes: &mut dyn MeshSource) -> Result<Geometry> {
    let MeshFile { mut mesh, .. } = meshes.mesh(o, "filename")?;
    mesh.transform(to_world);
    mesh.flip_normals ^= flip;
    Ok(Geometry::Mesh(mesh))
}

/// Mitsuba's `rectangle`: [-1, 1]² in the z = 0 plane, facing +z. It takes Mitsuba's
/// `face_normals`, which changes nothing on a flat shape.
fn rectangle(o: &Obj, to_world: &Transform, flip: bool, _: &mut dyn MeshSource) -> Result<Geometry> {
    o.bool("face_normals", false)?;
    let mut mesh = TriangleMesh::rectangle();
    mesh.transform(to_world);
    mesh.flip_normals ^= flip;
    Ok(Geometry::Mesh(mesh))
}

/// Mitsuba's `cube`: [-1, 1]³, facing out, each face flat. It takes Mitsuba's mesh parameter
/// `face_normals` (the Blender exporter writes it), which changes nothing on flat faces.
fn cube(o: &Obj, to_world: &Transform, flip: bool, _: &mut dyn MeshSource) -> Result<Geometry> {
    o.bool("face_normals", false)?;
    let mut mesh = TriangleMesh::cube();
    mesh.transform(to_world);
    mesh.flip_normals ^= flip;
    Ok(Geometry::Mesh(mesh))
}

/// Whether the analytic shape `o` asks for pbrt-v4's (u, v) (neumann's `parameterization`:
/// `mitsuba`, the default, or `pbrt`).
fn pbrt_uv(o: &Obj) -> Result<bool> {
    Ok(o.choice("parameterization", &["mitsuba", "pbrt"])? == "pbrt")
}

/// `phimax` (degrees in (0, 360], default 360) of a partial analytic shape (pbrt-v4's), in
/// radians.
fn phi_max(o: &Obj) -> Result<f32> {
    Ok(o.float_checked("phimax", 360.0, |p| p > 0.0 && p <= 360.0, "in (0, 360] degrees")?.to_radians())
}

/// Mitsuba's `disk`: the unit disk in the z = 0 plane, facing +z; (u, v) = (r, φ/2π), or
/// pbrt-v4's (φ/2π, 1 − r) with `parameterization` `pbrt`. neumann's `innerradius` (a hole of
/// that radius, the disk's being 1) and `phimax` (degrees) make pbrt-v4's partial disk.
fn disk(o: &Obj, to_world: &Transform, flip: bool, _: &mut dyn MeshSource) -> Result<Geometry> {
    let d = Disk::new(*to_world, flip).ok_or_else(|| o.error_at("to_world", "the transform flattens the disk"))?;
    let inner =
        o.float_checked("innerradius", 0.0, |r| (0.0..1.0).contains(&r), "in [0, 1) (the disk's radius is 1)")?;
    let d = d.partial(inner, phi_max(o)?).expect("checked above");
    Ok(Geometry::Disk(if pbrt_uv(o)? { d.with_pbrt_uv() } else { d }))
}

/// Mitsuba's `sphere`: `center` (origin), `radius` (1) and `to_world`; (u, v) = (φ/2π, θ/π),
/// or pbrt-v4's (φ/2π, 1 − θ/π) with `parameterization` `pbrt` (θ from the object's −z instead
/// of +z). neumann's `zmin`, `zmax` (object units, along the object's z from the centre) and
/// `phimax` (degrees) make pbrt-v4's partial sphere, with pbrt's (u, v) stretched over what is
/// left. A `to_world` that mirrors turns the normals inward, as Mitsuba's. One that scales
/// unevenly or shears is taken as Mitsuba 3.9 takes it, with its warning: the sphere of centre
/// `to_world(0)` and radius `|to_world · x̂|`, the whole map kept for (u, v) (see
/// [`super::sphere::Orientation`]); pbrt-v4 would make an ellipsoid of it, which the pbrt
/// loader and partial spheres refuse.
fn sphere(o: &Obj, to_world: &Transform, flip: bool, files: &mut dyn MeshSource) -> Result<Geometry> {
    // pbrt's v runs from the −z pole: the object's z axis reversed (a reflection the sphere's
    // surface and normals do not see).
    let pbrt = pbrt_uv(o)?;
    let center = o.point_opt("center")?.unwrap_or(Vec3::ZERO);
    let radius = o.float_checked("radius", 1.0, |r| r > 0.0 && r.is_finite(), "positive")?;
    let t = *to_world * Transform::translate(center) * Transform::scale(Vec3::splat(radius)).expect("r > 0");
    let mirrors = t.swaps_handedness();
    let t = if pbrt { t * Transform::scale(Vec3::new(1.0, 1.0, -1.0)).expect("non-zero") } else { t };
    let (zmin, zmax) = (o.float("zmin", -radius)?, o.float("zmax", radius)?);
    let clip = SphereClip::from_pbrt(radius, zmin, zmax, phi_max(o)?.to_degrees())
        .ok_or_else(|| o.error_at("zmin", "zmin and zmax leave nothing of the sphere"))?;
    // In the reflected frame of pbrt's (u, v), z is the object's −z.
    let clip = if pbrt { SphereClip { z_min: -clip.z_max, z_max: -clip.z_min, ..clip } } else { clip };
    let axes = [t.apply_vector(Vec3::X), t.apply_vector(Vec3::Y), t.apply_vector(Vec3::Z)];
    let (c, r) = (t.apply_point(Vec3::ZERO), axes[0].length());
    let linear = crate::math::Mat3::from_cols(axes[0] / r, axes[1] / r, axes[2] / r);
    let orientation = if is_similarity(&axes) {
        Orientation::rotation(linear)
    } else if pbrt || clip.is_partial() {
        return Err(o.error_at(
            "to_world",
            "this sphere's to_world scales unevenly or shears: an ellipsoid, which a pbrt-v4 or partial sphere cannot be",
        ));
    } else {
        let stretched = (r > 0.0 && r.is_finite()).then(|| Orientation::stretched(linear)).flatten();
        let orientation = stretched.ok_or_else(|| o.error_at("to_world", "the transform flattens the sphere"))?;
        let at = o.get("to_world").map_or_else(|| o.loc.position(), |p| p.loc.position());
        files.warn(format!(
            "warning: {at}: {} 'sphere': to_world scales unevenly or shears; as Mitsuba does, the sphere keeps the centre \
             to_world(0) and the radius |to_world · (1, 0, 0)| = {r}",
            o.tag
        ));
        orientation
    };
    // Mitsuba flips a mirrored sphere's normals (its decomposed scale is negative); the pbrt
    // loader gives pbrt-v4's flip (of every quadric) as `flip_normals`.
    Ok(Geometry::Sphere(Sphere { orientation, clip, ..Sphere::new(c, r, flip ^ (mirrors && !pbrt)) }))
}

/// Mitsuba's `cylinder`: from `p0` (origin) to `p1` (+z), `radius` (1), open. neumann's
/// `phimax` (degrees) makes pbrt-v4's partial cylinder. A `to_world` that scales unevenly
/// across the axis or shears makes an elliptic cylinder, as Mitsuba 3.9 renders it (with its
/// warning) and pbrt-v4 too; it cannot emit (see [`Cylinder`]).
fn cylinder(o: &Obj, to_world: &Transform, flip: bool, files: &mut dyn MeshSource) -> Result<Geometry> {
    let p0 = o.point_opt("p0")?.unwrap_or(Vec3::ZERO);
    let p1 = o.point_opt("p1")?.unwrap_or(Vec3::Z);
    let radius = o.float_checked("radius", 1.0, |r| r > 0.0 && r.is_finite(), "positive")?;
    let c = Cylinder::new(p0, p1, radius, *to_world, flip)
        .ok_or_else(|| o.error_at("p1", "degenerate cylinder (p0 = p1, or a transform that flattens it)"))?;
    if c.is_elliptic() {
        let at = o.get("to_world").map_or_else(|| o.loc.position(), |p| p.loc.position());
        files.warn(format!(
            "warning: {at}: {} 'cylinder': to_world scales unevenly across the axis or shears: an elliptic cylinder, as \
             Mitsuba and pbrt-v4 render it",
            o.tag
        ));
    }
    Ok(Geometry::Cylinder(c.partial(phi_max(o)?).expect("phimax checked positive")))
}

/// Mitsuba's `sdfgrid`: `filename` (a one-channel `.vol` grid volume over the unit cube of
/// object space, required: Mitsuba's XML cannot give the `grid` tensor), `normals` (`smooth`,
/// the default, or `analytic`), `to_world` (any affine map; Mitsuba warns on rotations, which
/// its bounding boxes mishandle, while these are exact). No `flip_normals`, as in Mitsuba.
fn sdfgrid(o: &Obj, to_world: &Transform, flip: bool, files: &mut dyn MeshSource) -> Result<Geometry> {
    if flip {
        return Err(o.error_at("flip_normals", "an sdfgrid has no flip_normals (as in Mitsuba): negate the samples"));
    }
    let smooth = o.choice("normals", &["smooth", "analytic"])? == "smooth";
    let grid = files.grid_volume(o, "filename")?;
    let sdf = SdfGrid::new(&grid, *to_world, smooth).map_err(|e| o.error_at("filename", e.to_string()))?;
    Ok(Geometry::SdfGrid(Box::new(sdf)))
}

/// Whether a linear map's columns `cols` are orthogonal and of one positive length (a
/// similarity: uniform scale, rotation, possibly a reflection), to a relative 10⁻⁴.
pub fn is_similarity(cols: &[Vec3; 3]) -> bool {
    let r = cols[0].length();
    let uniform = cols.iter().all(|c| (c.length() - r).abs() <= 1e-4 * r);
    let orthogonal = (cols[0].dot(cols[1])).abs() <= 1e-4 * r * r
        && (cols[0].dot(cols[2])).abs() <= 1e-4 * r * r
        && (cols[1].dot(cols[2])).abs() <= 1e-4 * r * r;
    uniform && orthogonal && r > 0.0
}

/// neumann's `curve`: pbrt-v4's curves as a scene format decoded them (`filename` names them
/// among the decoded files), placed by `to_world` (`flip_normals` turns their normals over).
fn curve(o: &Obj, to_world: &Transform, flip: bool, meshes: &mut dyn MeshSource) -> Result<Geometry> {
    let set = meshes.curves(o, "filename")?;
    Ok(Geometry::Curves(Box::new(super::Curves::new(&set, to_world, flip))))
}

/// Mitsuba's `linearcurve` and `bsplinecurve`: round tubes from the curve file `filename`
/// (`load::curve_file`), along its polylines or along the uniform cubic B-splines of its
/// points (at least four per curve), the points placed by `to_world` and the radii kept (as in
/// Mitsuba). No `flip_normals` (Mitsuba's curves have none: a tube is seen from outside only).
fn round_curve(o: &Obj, to_world: &Transform, flip: bool, files: &mut dyn MeshSource) -> Result<Geometry> {
    if flip {
        let message = format!("a {} has no flip_normals (as in Mitsuba): its tubes are seen from outside only", o.ty);
        return Err(o.error_at("flip_normals", message));
    }
    let curves = files.curve_file(o, "filename")?;
    let located = |e: String| o.error_at("filename", e);
    Ok(if o.ty == "bsplinecurve" {
        Geometry::BSplineCurves(Box::new(super::BSplineCurves::new(&curves, to_world).map_err(located)?))
    } else {
        Geometry::LinearCurves(Box::new(super::LinearCurves::new(&curves, to_world).map_err(located)?))
    })
}

/// Mitsuba's `ellipsoids` and `ellipsoidsmesh`: `filename` (a PLY point file; see
/// [`EllipsoidSet::from_table`]), `scale_factor` (1), `extent` (3: the shells' size in units of
/// the file's scales), `extent_adaptive_clamping` (false; true scales each extent by
/// `√(2 ln(opacity / 0.01)) / 3`, and without opacities in the file is ignored with a warning,
/// as in Mitsuba), `to_world` (centres moved by it, scales by its mean stretch, orientations
/// turned by its rotation); `ellipsoidsmesh` also `shell` (`ico_sphere`, the default, `box`,
/// `uv_sphere`, or a nested mesh shape), `flip_normals` and `face_normals` (a mesh's; the shells
/// have face normals only). Mitsuba's tensor parameters (`data`, `centers`, `scales`,
/// `quaternions`, attribute tensors) come from Python only.
fn ellipsoids(o: &Obj, to_world: &Transform, flip: bool, files: &mut dyn MeshSource) -> Result<Geometry> {
    use super::ellipsoids::{shell_mesh, EllipsoidSet};
    if flip && o.ty == "ellipsoids" {
        return Err(o.error_at("flip_normals", "analytic ellipsoids have no flip_normals (as in Mitsuba)"));
    }
    if o.ty == "ellipsoidsmesh" {
        // A mesh's parameter; the shells have face normals only, as Mitsuba's.
        o.bool("face_normals", false)?;
    }
    let scale_factor = o.float_checked("scale_factor", 1.0, |s| s > 0.0 && s.is_finite(), "positive")?;
    let extent = o.float_checked("extent", 3.0, |s| s > 0.0 && s.is_finite(), "positive")?;
    let adaptive = o.bool("extent_adaptive_clamping", false)?;
    let shell = if o.ty == "ellipsoidsmesh" { Some(shell_template(o, files)?) } else { None };
    let table = files.point_table(o, "filename")?;
    let set = EllipsoidSet::from_table(&table, scale_factor, to_world).map_err(|e| o.error_at("filename", e))?;
    let extents = match set.extents(extent, adaptive) {
        Some(e) => e,
        None => {
            let at = o.get("extent_adaptive_clamping").map_or_else(|| o.loc.position(), |p| p.loc.position());
            files.warn(format!(
                "warning: {at}: {} '{}': the file has no opacities: extent_adaptive_clamping is ignored (as Mitsuba ignores it)",
                o.tag, o.ty
            ));
            set.extents(extent, false).expect("a fixed extent needs no opacities")
        }
    };
    Ok(match shell {
        None => Geometry::Ellipsoids(Box::new(super::Ellipsoids::new(&set, &extents))),
        Some(shell) => {
            let mut mesh = shell_mesh(&set, &extents, &shell).map_err(|e| o.error_at("shell", e))?;
            mesh.flip_normals ^= flip;
            Geometry::Mesh(mesh)
        }
    })
}

/// An `ellipsoidsmesh`'s `shell`: one of Mitsuba's templates by name, or a nested mesh shape
/// (its triangles as its own `to_world` places them).
fn shell_template(o: &Obj, files: &mut dyn MeshSource) -> Result<super::ellipsoids::Shell> {
    use super::ellipsoids::Shell;
    use crate::props::Value;
    let value = o.get("shell").map(|p| p.value.clone());
    Ok(match value {
        None => Shell::IcoSphere,
        Some(Value::String(s)) => match s.as_str() {
            "default" | "ico_sphere" => Shell::IcoSphere,
            "box" => Shell::Box,
            "uv_sphere" => Shell::UvSphere,
            _ => {
                let message = format!("unknown shell '{s}' (expected default, ico_sphere, box or uv_sphere, or a mesh shape)");
                return Err(o.error_at("shell", message));
            }
        },
        Some(Value::Object(mesh)) if mesh.tag == "shape" => {
            mesh.built.set(true);
            mesh.check_children(&["bsdf"])?;
            let plugin = shape_plugin(&mesh.ty).ok_or_else(|| {
                mesh.unknown_plugin(&SHAPE_PLUGINS.iter().map(|p| p.0).collect::<Vec<_>>())
            })?;
            let to_world = mesh.transform("to_world")?;
            let flip = mesh.bool("flip_normals", false)?;
            match plugin(&mesh, &to_world, flip, files)? {
                Geometry::Mesh(m) => Shell::Mesh(m.positions, m.indices),
                _ => return Err(mesh.error("an ellipsoidsmesh's shell must be a triangle mesh")),
            }
        }
        Some(_) => return Err(o.error_at("shell", "the shell must be a <string> or a nested mesh <shape>")),
    })
}
