//! Stanford PLY meshes (ASCII and binary) from arbitrary bytes, and the same bytes read as a
//! point table and built into Mitsuba's ellipsoids (analytic shells, traced; mesh shells).
#![no_main]
use libfuzzer_sys::fuzz_target;
use neumann::geometry::ellipsoids::{shell_mesh, EllipsoidSet, Shell};
use neumann::geometry::Ellipsoids;
use neumann::math::{Ray, Transform, Vec3};

fuzz_target!(|data: &[u8]| {
    let _ = neumann::load::ply::parse_ply(data);
    let Ok(table) = neumann::load::ply::parse_ply_table(data) else { return };
    let Ok(set) = EllipsoidSet::from_table(&table, 1.0, &Transform::IDENTITY) else { return };
    let extents = set.extents(3.0, set.opacities.is_some()).expect("opacities present when asked");
    let shells = Ellipsoids::new(&set, &extents);
    let ray = Ray::new(Vec3::new(0.1, 0.2, 10.0), Vec3::new(0.0, 0.0, -1.0));
    for i in 0..shells.len().min(64) {
        let _ = shells.bounds(i);
        if let Some(t) = shells.intersect(i, &ray, f32::INFINITY) {
            let sp = shells.surface(i, &ray, t);
            assert!(sp.p.is_finite() && sp.n.is_finite(), "hit point or normal not finite");
        }
    }
    let _ = shell_mesh(&set, &extents, &Shell::IcoSphere);
});
