//! Loader tests: the shared scenes, every construct of the format, and the errors users meet.

use super::*;
use crate::film::filter::Filter;
use crate::geometry::Geometry;
use crate::light::Light;
use crate::material::Bsdf;
use crate::math::{Ray, Rgb, Vec3};
use crate::sampling::sampler::SamplerKind;
use std::path::PathBuf;

fn shared(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

fn load(text: &str) -> Result<SceneFile, SceneError> {
    load_scene_text(Path::new("test.xml"), text, &[])
}

/// A minimal scene around `body` (camera at z = 5 looking at the origin).
fn scene(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/></film>
    </sensor>
{body}
</scene>"#
    )
}

fn err(text: &str) -> String {
    match load(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn shared_cornell_box_matches_the_builtin() {
    let file = load_scene_file(&shared("cbox.xml"), &[]).expect("cbox.xml loads");
    assert!(file.warnings.is_empty(), "{:?}", file.warnings);
    assert_eq!((file.scene.camera().width(), file.scene.camera().height()), (256, 256));
    assert_eq!(file.spp, 64);
    assert!(matches!(file.integrator, crate::integrator::AnyIntegrator::Path(p) if p.settings.max_depth == 65));
    assert!(file.filter.is_pixel_box());
    let builtin = crate::scene::cornell::cornell_box(256, 256).unwrap();
    assert_eq!(file.scene.primitive_count(), builtin.primitive_count());
    assert_eq!(file.scene.lights().len(), builtin.lights().len());
    // Same camera rays and same first hits over a grid of pixels.
    for (x, y) in [(10.5, 10.5), (128.0, 128.0), (200.3, 40.7), (60.0, 230.0), (250.0, 250.0)] {
        let film = crate::math::Vec2::new(x, y);
        let u = crate::math::Vec2::splat(0.5);
        let (a, b) = (file.scene.camera().generate_ray(film, u), builtin.camera().generate_ray(film, u));
        assert!((a.o - b.o).length() < 1e-6 && (a.d - b.d).length() < 1e-6);
        let (ha, hb) = (file.scene.intersect(&a).unwrap(), builtin.intersect(&b).unwrap());
        assert!((ha.p - hb.p).length() < 1e-5, "{} vs {}", ha.p, hb.p);
    }
    // -D overrides.
    let small =
        load_scene_file(&shared("cbox.xml"), &[("res".into(), "24".into()), ("spp".into(), "4".into())]).unwrap();
    assert_eq!((small.scene.camera().width(), small.spp), (24, 4));
    // The same picture, bit for bit, from the file and from the built-in scene.
    let settings = crate::render::RenderSettings { spp: 4, seed: 9, ..Default::default() };
    let never = std::sync::atomic::AtomicBool::new(false);
    let from_file = crate::render::render_integrator(&small.scene, &small.integrator, &settings, &never).unwrap();
    let builtin_small = crate::scene::cornell::cornell_box(24, 24).unwrap();
    let integrator = crate::integrator::PathIntegrator::with_max_depth(65);
    let from_builtin = crate::render::render(&builtin_small, &integrator, &settings, &never).unwrap();
    assert!(from_file.film.image() == from_builtin.film.image(), "cbox.xml and the built-in box differ");
}

/// Mitsuba's `merge` (nested shapes merged into one mesh per BSDF, to save memory) renders
/// the same image as its shapes listed one by one, emitters and different BSDFs included; it
/// takes shapes only.
#[test]
fn merge_renders_as_its_shapes() {
    let red = r#"<bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>"#;
    let shapes = r#"<shape type="rectangle"><ref id="red"/><transform name="to_world"><scale value="3"/><translate z="-1"/></transform></shape>
        <shape type="cube"><ref id="red"/><transform name="to_world"><scale value="0.4"/><rotate y="1" angle="30"/></transform></shape>
        <shape type="sphere"><point name="center" x="1" y="0.5" z="0"/><float name="radius" value="0.3"/><bsdf type="conductor"/></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><translate z="2"/></transform>
            <emitter type="area"><rgb name="radiance" value="8, 8, 8"/></emitter></shape>"#;
    let plain = load(&scene(&format!("{red}{shapes}"))).unwrap();
    let merged = load(&scene(&format!(r#"{red}<shape type="merge">{shapes}</shape>"#))).unwrap();
    assert!(merged.warnings.is_empty(), "{:?}", merged.warnings);
    assert_eq!(merged.scene.shapes().len(), 4);
    assert_eq!(merged.scene.lights().len(), 1);
    let settings = crate::render::RenderSettings { spp: 4, seed: 3, ..Default::default() };
    let never = std::sync::atomic::AtomicBool::new(false);
    let a = crate::render::render_integrator(&plain.scene, &plain.integrator, &settings, &never).unwrap();
    let b = crate::render::render_integrator(&merged.scene, &merged.integrator, &settings, &never).unwrap();
    let mean = a.film.image().iter().map(|c| c.x + c.y + c.z).sum::<f32>() / a.film.image().len() as f32;
    assert!(mean > 0.01, "a dark test image: {mean}");
    assert!(a.film.image() == b.film.image(), "merge changed the image");
    let e = err(&scene(r#"<shape type="merge"><bsdf type="diffuse"/><shape type="sphere"/></shape>"#));
    assert!(e.contains("test.xml:") && e.contains("<bsdf> cannot be nested in shape 'merge'"), "{e}");
    let e = err(&scene(r#"<shape type="mrege"/>"#));
    assert!(e.contains("the nearest is 'merge'"), "{e}");
}

/// A 1 × 1 film's size parameters.
const ONE_PIXEL: &str = r#"<integer name="width" value="1"/><integer name="height" value="1"/>"#;

/// A scene rendered by the path tracer through a sensor of type `ty` (`params` inside it,
/// `spp` samples, a box-filtered film of size parameters `film`) around `body`.
fn meter_scene(ty: &str, params: &str, spp: u32, film: &str, body: &str) -> String {
    format!(
        r#"<scene version="3.0.0"><integrator type="path"/>
        <sensor type="{ty}">{params}
            <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
            <film type="hdrfilm">{film}<rfilter type="box"/></film></sensor>
        {body}</scene>"#
    )
}

/// The one pixel of a meter's render of `f` at its sample count (seed `seed`).
fn measure_pixel(f: &SceneFile, seed: u64) -> Vec3 {
    let settings = crate::render::RenderSettings { spp: f.spp, seed, ..Default::default() };
    let never = std::sync::atomic::AtomicBool::new(false);
    crate::render::render_integrator(&f.scene, &f.integrator, &settings, &never).unwrap().film.image()[0]
}

/// Mitsuba's `radiancemeter`: one ray, from `origin` along `direction` (or `to_world`'s origin
/// along its +z, which wins over them). A diffuse sphere (albedo 0.5) under a constant
/// environment of radiance 1 reflects exactly 0.5 toward the meter (a convex surface sees the
/// whole sky). A film other than 1 × 1, half of `origin`/`direction`, a zero direction and the
/// light tracer are errors.
#[test]
fn radiancemeter_measures_one_ray() {
    use crate::math::Vec2;
    let meter = |params: &str, film: &str| {
        let body = r#"<shape type="sphere"><bsdf type="diffuse"/></shape><emitter type="constant"/>"#;
        meter_scene("radiancemeter", params, 16384, film, body)
    };
    let one = ONE_PIXEL;
    let f =
        load(&meter(r#"<point name="origin" x="0" y="0" z="3"/><vector name="direction" x="0" y="0" z="-2"/>"#, one))
            .unwrap();
    let cam = f.scene.camera();
    for film in [Vec2::new(0.1, 0.9), Vec2::new(0.5, 0.5)] {
        let r = cam.generate_ray(film, Vec2::new(0.3, 0.6));
        assert!((r.o - Vec3::new(0.0, 0.0, 3.0)).length() < 1e-5 && (r.d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        assert_eq!(r.t_max, f32::INFINITY);
    }
    let v = measure_pixel(&f, 1);
    assert!((v - Vec3::splat(0.5)).abs().max_element() < 0.01, "{v}");
    // to_world wins over origin (Mitsuba reads and ignores it then).
    let f = load(&meter(
        r#"<transform name="to_world"><lookat origin="4, 0, 0" target="0, 0, 0"/></transform><point name="origin" x="0" y="0" z="3"/>"#,
        one,
    ))
    .unwrap();
    let r = f.scene.camera().generate_ray(Vec2::splat(0.5), Vec2::ZERO);
    assert!((r.o - Vec3::new(4.0, 0.0, 0.0)).length() < 1e-5 && (r.d - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6);
    assert!(f.scene.camera().with_resolution(4, 4).is_err());
    for (params, film, what) in [
        ("", r#"<integer name="width" value="4"/><integer name="height" value="3"/>"#, "must be 1x1, got 4x3"),
        (r#"<point name="origin" x="0" y="0" z="3"/>"#, one, "both 'origin' and 'direction'"),
        (r#"<point name="origin" x="0" y="0" z="3"/><vector name="direction" x="0" y="0" z="0"/>"#, one, "non-zero"),
        (r#"<float name="fov" value="30"/>"#, one, "fov"),
    ] {
        let e = err(&meter(params, film));
        assert!(e.contains("test.xml:") && e.contains(what), "{params}: {e}");
    }
    let f = load(&meter("", one)).unwrap();
    let light_tracer = crate::integrator::AnyIntegrator::Ptracer(Default::default());
    let settings = crate::render::RenderSettings { spp: 4, ..Default::default() };
    let never = std::sync::atomic::AtomicBool::new(false);
    let e = crate::render::render_integrator(&f.scene, &light_tracer, &settings, &never).err().unwrap();
    assert!(e.to_string().contains("meter one"), "{e}");
}

/// Mitsuba's `irradiancemeter`, nested in the shape it measures: the film holds the irradiance
/// averaged over the surface. Under a unit constant environment an unoccluded plane receives
/// exactly π; flipped (facing away from a light above it) nothing. Under a sphere light
/// (radius 1, radiance 1, centre 3 above the middle of a 3 × 3 square) the mean irradiance is
/// `∫ π R² h / D³ dA / A` = 0.281149 (quadrature); only the point at the centre would read
/// π/9 = 0.349, and uniform instead of cosine directions 0.18. Misplaced meters are errors.
#[test]
fn irradiancemeter_measures_mean_irradiance() {
    let meter = |flip: bool, film: &str, light: &str| {
        format!(
            r#"<scene version="3.0.0"><integrator type="path"/>
            <shape type="rectangle"><transform name="to_world"><scale value="1.5"/></transform>
                <boolean name="flip_normals" value="{flip}"/>
                <sensor type="irradiancemeter">
                    <sampler type="independent"><integer name="sample_count" value="262144"/></sampler>
                    <film type="hdrfilm">{film}<rfilter type="box"/></film></sensor></shape>
            {light}</scene>"#
        )
    };
    let one = ONE_PIXEL;
    let sphere = r#"<shape type="sphere"><point name="center" x="0" y="0" z="3"/><float name="radius" value="1"/>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#;
    let measure = |text: &str, spp: u32| {
        let mut f = load(text).unwrap();
        assert!(f.warnings.is_empty(), "{:?}", f.warnings);
        assert_eq!(f.scene.camera().ray_weight(), std::f32::consts::PI);
        f.spp = spp;
        measure_pixel(&f, 5)
    };
    let sky = measure(&meter(false, one, r#"<emitter type="constant"/>"#), 64);
    assert!((sky - Vec3::splat(std::f32::consts::PI)).abs().max_element() < 1e-4, "{sky}");
    let below = measure(&meter(true, one, sphere), 4096);
    assert_eq!(below, Vec3::ZERO);
    let e = measure(&meter(false, one, sphere), 262_144).x;
    assert!((e - 0.281149).abs() < 0.025 * 0.281149, "{e}");
    for (text, what) in [
        (meter(false, r#"<integer name="width" value="2"/><integer name="height" value="1"/>"#, sphere), "must be 1x1, got 2x1"),
        (scene(r#"<shape type="sphere"><sensor type="perspective"/></shape>"#), "only an irradiancemeter"),
        (
            r#"<scene version="3.0.0"><sensor type="irradiancemeter"><film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film></sensor></scene>"#.to_string(),
            "must be nested in the <shape>",
        ),
        (scene(r#"<shape type="sphere"><sensor type="irradiancemeter"/></shape>"#), "more than one <sensor>"),
    ] {
        let e = err(&text);
        assert!(e.contains(":") && e.contains(what), "{e}");
    }
}

/// Mitsuba's `batch` sensor: its sensors side by side, each on an equal column of the film (its
/// own film replaced); rays as Mitsuba 3.9.1 traces them (`Sensor::sample_ray` at film
/// positions 0.1, 0.3, 0.49, 0.51 and 0.9 of the width). A width that is not a multiple of the
/// sensor count, and a batch of meters, are errors; `--res` keeps the columns.
#[test]
fn batch_sensor_puts_cameras_side_by_side() {
    use crate::math::Vec2;
    let batch = |width: u32, second: &str| {
        format!(
            r#"<scene version="3.0.0"><integrator type="path"/>
            <sensor type="batch">
                <sensor type="perspective"><float name="fov" value="40"/>
                    <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform></sensor>
                {second}
                <film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="4"/></film>
            </sensor><shape type="sphere"/><emitter type="constant"/></scene>"#
        )
    };
    let ortho = r#"<sensor type="orthographic"><transform name="to_world"><lookat origin="5,0,0" target="0,0,0" up="0,1,0"/></transform>
        <film type="hdrfilm"><integer name="width" value="7"/><integer name="height" value="3"/></film></sensor>"#;
    let f = load(&batch(8, ortho)).unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let cam = f.scene.camera();
    assert_eq!((cam.width(), cam.height()), (8, 4));
    let expected = [
        (0.1, [-0.00218382, 0.0, 4.99], [-0.213354, 0.0, -0.976975]),
        (0.3, [0.00072794, 0.0, 4.99], [0.0726019, 0.0, -0.997361]),
        (0.49, [0.00349411, 0.0, 4.99], [0.329855, 0.0, -0.944031]),
        (0.51, [4.99, 0.0, 0.96], [-1.0, 0.0, 0.0]),
        (0.9, [4.99, 0.0, -0.6], [-1.0, 0.0, 0.0]),
    ];
    for (x, o, d) in expected {
        let r = cam.generate_ray(Vec2::new(8.0 * x, 2.0), Vec2::splat(0.5));
        assert!((r.o - Vec3::from(o)).length() < 1e-5, "x = {x}: {}", r.o);
        assert!((r.d - Vec3::from(d)).length() < 1e-5, "x = {x}: {}", r.d);
    }
    // A render fills both columns; --res 16x4 keeps two columns of 8.
    let settings = crate::render::RenderSettings { spp: 4, seed: 1, ..Default::default() };
    let never = std::sync::atomic::AtomicBool::new(false);
    let out = crate::render::render_integrator(&f.scene, &f.integrator, &settings, &never).unwrap();
    assert_eq!(out.film.image().len(), 32);
    let wide = cam.with_resolution(16, 4).unwrap();
    let r = wide.generate_ray(Vec2::new(16.0 * 0.9, 2.0), Vec2::splat(0.5));
    assert!((r.d - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6);
    assert!(cam.with_resolution(9, 4).is_err());
    for (text, what) in [
        (batch(7, ortho), "multiple of the number of nested sensors (2)"),
        (batch(8, r#"<sensor type="radiancemeter"/>"#), "cannot be part of a batch"),
        (batch(8, r#"<sensor type="orthographic"><rfilter type="box"/></sensor>"#), "<rfilter> cannot be nested"),
    ] {
        let e = err(&text);
        assert!(e.contains("test.xml:") && e.contains(what), "{e}");
    }
}

/// Mitsuba's `distant` sensor: parallel rays from outside the scene's bounding sphere (radius
/// √3 · (1 + 10⁻⁴) around a unit sphere) toward its target; the film holds the radiance
/// leaving the scene toward the sensor, averaged over the target. Against a unit sphere that
/// emits 2 (and nothing else): 2/3 · (1 - 2·10⁻⁴) over the bounding sphere's cross-section,
/// exactly 2 through a point on it, 0 through a point beside it, 2 · π/4 over a 2 × 2 square
/// (a target shape, not part of the scene). The ray through a point starts 2R before it, as
/// Mitsuba 3.9.1 traces it.
#[test]
fn distant_sensor_averages_over_its_target() {
    use crate::math::Vec2;
    let distant = |params: &str, film: &str| {
        let body = r#"<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
            <emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>"#;
        meter_scene("distant", params, 65536, film, body)
    };
    let one = ONE_PIXEL;
    let down = r#"<vector name="direction" x="0" y="0" z="-1"/>"#;
    let measure = |params: &str| {
        let f = load(&distant(params, one)).unwrap();
        assert!(f.warnings.is_empty(), "{:?}", f.warnings);
        let v = measure_pixel(&f, 2).x;
        (f, v)
    };
    let (f, v) = measure(&format!(r#"{down}<point name="target" x="0.5" y="0" z="0"/>"#));
    assert_eq!(v, 2.0);
    let r = f.scene.camera().generate_ray(Vec2::splat(0.5), Vec2::new(0.3, 0.6));
    assert!((r.o - Vec3::new(0.5, 0.0, 3.46441)).length() < 1e-4 && r.d == Vec3::new(0.0, 0.0, -1.0), "{}", r.o);
    assert_eq!(measure(&format!(r#"{down}<point name="target" x="2" y="0" z="0"/>"#)).1, 0.0);
    let (f, v) = measure(down);
    assert!((v - 2.0 / 3.0 * (1.0 - 2e-4)).abs() < 0.015, "{v}");
    for u in [Vec2::new(0.3, 0.6), Vec2::new(0.99, 0.01)] {
        let r = f.scene.camera().generate_ray(Vec2::splat(0.5), u);
        assert!((r.o.z - 3f32.sqrt()).abs() < 1e-3 && r.o.truncate().length() <= 3f32.sqrt() * 1.0002, "{}", r.o);
    }
    let square = r#"<shape type="rectangle" name="target"/>"#;
    let (f, v) = measure(&format!("{down}{square}"));
    assert!((v - 2.0 * std::f32::consts::FRAC_PI_4).abs() < 0.013, "{v}");
    assert_eq!(f.scene.shapes().len(), 1, "the target is not part of the scene");
    for (params, film, what) in [
        (down.to_string(), r#"<integer name="width" value="2"/><integer name="height" value="2"/>"#, "must be 1x1"),
        (format!(r#"{down}<transform name="to_world"><rotate x="1" angle="30"/></transform>"#), one, "not both"),
        (r#"<vector name="direction" x="0" y="0" z="0"/>"#.to_string(), one, "non-zero"),
        (format!(r#"{down}<string name="target" value="sphere"/>"#), one, "'target'"),
    ] {
        let e = err(&distant(&params, film));
        assert!(e.contains("test.xml:") && e.contains(what), "{params}: {e}");
    }
}

/// Mitsuba's `volume` texture: a `<volume>` looked up at the surface point's world position,
/// as Mitsuba 3.9.1 evaluates it (a 2 × 1 × 1 grid from 0 to 1 over a box scaled by 2: 0 at
/// x = 0.25 and 0.5 (clamped to the first texel centre), 1 at 1.5 and beyond; 0.5 between the
/// centres); an RGB `constvolume`'s scalar is its channels' mean (0.4 for 0.2, 0.4, 0.6). The
/// nested volume named `volume` is required (as in Mitsuba, a float will not do).
#[test]
fn volume_texture_is_looked_up_by_position() {
    use crate::image::GridVolume;
    use crate::math::Vec2;
    use crate::texture::{TexPoint, Texture};
    let dir = std::env::temp_dir().join(format!("neumann-voltex-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let grid = GridVolume { res: [2, 1, 1], channels: 1, bbox: [[0.0; 3], [1.0; 3]], data: vec![0.0, 1.0] };
    std::fs::write(dir.join("ramp.vol"), crate::load::volume::grid_volume_bytes(&grid)).unwrap();
    let bsdf = |texture: &str| {
        scene(&format!(
            r#"<shape type="sphere"><bsdf type="diffuse"><texture type="volume" name="reflectance">{texture}</texture></bsdf></shape>"#
        ))
    };
    let reflectance = |text: &str| {
        let f = load_scene_text(&dir.join("s.xml"), text, &[]).unwrap();
        assert!(f.warnings.is_empty(), "{:?}", f.warnings);
        match &f.scene.bsdfs()[f.scene.shapes()[0].bsdf as usize] {
            Bsdf::Diffuse(d) => d.reflectance.clone(),
            b => panic!("{b:?}"),
        }
    };
    let ramp = reflectance(&bsdf(
        r#"<volume type="gridvolume" name="volume"><string name="filename" value="ramp.vol"/>
            <transform name="to_world"><scale value="2"/></transform></volume>"#,
    ));
    assert!(matches!(ramp, Texture::Volume(_)) && ramp.uses_position());
    let at = |p: Vec3| TexPoint { uv: Vec2::new(0.9, 0.1), p, n: Vec3::Z, mesh: None, textures: None };
    for (x, want) in [(0.25, 0.0), (0.5, 0.0), (1.0, 0.5), (1.5, 1.0), (3.0, 1.0)] {
        let got = ramp.eval_at(&at(Vec3::new(x, 0.5, 0.5)));
        assert!((got - Vec3::splat(want)).abs().max_element() < 1e-6, "x = {x}: {got}");
    }
    let rgb = reflectance(&bsdf(
        r#"<volume type="constvolume" name="volume"><rgb name="value" value="0.2, 0.4, 0.6"/></volume>"#,
    ));
    assert_eq!(rgb.eval_at(&at(Vec3::splat(5.0))), Vec3::new(0.2, 0.4, 0.6));
    assert!((rgb.eval_scalar(&at(Vec3::splat(5.0))) - 0.4).abs() < 1e-6);
    for (texture, what) in [
        ("", "'volume' (a nested <volume name=\"volume\">) is required"),
        (r#"<float name="volume" value="0.5"/>"#, "'volume' (a nested"),
        (r#"<volume type="constvolume"/>"#, "a <volume> cannot be nested in texture 'volume'"),
    ] {
        let e = match load_scene_text(&dir.join("s.xml"), &bsdf(texture), &[]) {
            Ok(_) => panic!("{texture}: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(what), "{texture}: {e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn shared_scenes_load() {
    let spheres = load_scene_file(&shared("cbox_spheres.xml"), &[]).expect("cbox_spheres.xml loads");
    assert!(spheres.warnings.is_empty(), "{:?}", spheres.warnings);
    let kinds: Vec<&str> = spheres
        .scene
        .bsdfs()
        .iter()
        .map(|b| match b {
            Bsdf::Conductor(_) => "conductor",
            Bsdf::Dielectric(_) => "dielectric",
            Bsdf::Diffuse(_) => "diffuse",
            _ => "other",
        })
        .collect();
    assert!(kinds.contains(&"conductor") && kinds.contains(&"dielectric"), "{kinds:?}");
    let furnace = load_scene_file(&shared("furnace.xml"), &[("albedo".into(), "0.5".into())]).unwrap();
    assert!(matches!(furnace.scene.lights()[0], Light::Constant { radiance, .. } if radiance == Rgb::ONE));
    match &furnace.scene.bsdfs()[0] {
        Bsdf::Diffuse(d) => assert_eq!(d.reflectance.mean(), Rgb::splat(0.5)),
        other => panic!("{other:?}"),
    }
}

#[test]
fn transforms_apply_in_document_order() {
    // scale, then rotate 90° about z, then translate: the sphere's centre (1,0,0) → (2,0,0)
    // → (0,2,0) → (0,2,1).
    let f = load(&scene(
        r#"<shape type="sphere"><point name="center" x="1" y="0" z="0"/><float name="radius" value="0.5"/>
           <transform name="to_world"><scale value="2"/><rotate z="1" angle="90"/><translate value="0 0 1"/></transform>
        </shape>"#,
    ))
    .unwrap();
    match &f.scene.geometries()[0] {
        Geometry::Sphere(s) => {
            assert!((s.center - Vec3::new(0.0, 2.0, 1.0)).length() < 1e-5, "{}", s.center);
            assert!((s.radius - 1.0).abs() < 1e-6);
        }
        g => panic!("{g:?}"),
    }
    // A row-major matrix equals the same translation.
    let m = load(&scene(
        r#"<shape type="sphere"><transform name="to_world">
             <matrix value="1 0 0 3  0 1 0 0  0 0 1 0  0 0 0 1"/></transform></shape>"#,
    ))
    .unwrap();
    match &m.scene.geometries()[0] {
        Geometry::Sphere(s) => assert!((s.center - Vec3::new(3.0, 0.0, 0.0)).length() < 1e-6),
        g => panic!("{g:?}"),
    }
}

/// A sphere's `to_world` that scales unevenly (and shears, rotated before the scale) is taken
/// as Mitsuba 3.9.1 takes it, with a warning: the sphere of centre `to_world(0)` and radius
/// `|to_world · x̂|`, (u, v) and their derivatives from the whole map. The hit, (u, v), ∂p/∂u
/// and ∂p/∂v are Mitsuba's for the same ray (its Python API, `scalar_rgb`). A mirroring
/// `to_world` turns the normals inward, as in Mitsuba; pbrt-v4 (an ellipsoid) refuses it.
#[test]
fn spheres_take_uneven_scales_as_mitsuba_does() {
    let file = load(&scene(
        r#"<shape type="sphere"><transform name="to_world">
             <rotate z="1" angle="30"/><scale x="2" y="0.5" z="1"/><translate x="0.3"/></transform></shape>"#,
    ))
    .unwrap();
    assert_eq!(file.warnings.len(), 1, "{:?}", file.warnings);
    assert!(file.warnings[0].contains("test.xml:7:22") && file.warnings[0].contains("= 1.75"), "{}", file.warnings[0]);
    let Geometry::Sphere(s) = &file.scene.geometries()[0] else { panic!("a sphere") };
    assert!((s.center - Vec3::new(0.3, 0.0, 0.0)).length() < 1e-6 && (s.radius - 1.75).abs() < 1e-6);
    let d = Vec3::new(-0.1, -0.05, -1.0).normalize();
    let si = file.scene.intersect(&Ray::new(Vec3::new(1.0, 0.7, 6.0), d)).expect("hits");
    let close = |a: Vec3, b: [f32; 3], tol: f32| (a - Vec3::from_array(b)).abs().max_element() <= tol;
    assert!(close(si.p, [0.566083, 0.483042, 1.66083], 1e-5), "{}", si.p);
    // The interaction computes (u, v) and their derivatives only for what needs them.
    let uv = s.uv_of_direction((si.p - s.center) / s.radius);
    let (dpdu, dpdv) = s.dpduv(si.p, true);
    assert!((uv - crate::math::Vec2::new(0.144886, 0.400962)).abs().max_element() < 1e-5, "{uv}");
    assert!(close(dpdu, [-12.1402, 0.417963, 0.0], 1e-4), "{dpdu}");
    assert!(close(dpdv, [1.42364, 2.58444, -3.06368], 1e-4), "{dpdv}");
    assert!(si.ng.dot(-d) > 0.0, "outward normal");
    // Mirrored: the normal points inward, as Mitsuba's (flipped twice: outward again).
    for (mirror, flip, inward) in
        [(r#"x="-1""#, "false", true), (r#"y="-1" z="-1""#, "false", false), (r#"z="-1""#, "true", false)]
    {
        let file = load(&scene(&format!(
            r#"<shape type="sphere"><boolean name="flip_normals" value="{flip}"/>
                 <transform name="to_world"><scale {mirror}/></transform></shape>"#
        )))
        .unwrap();
        let si = file.scene.intersect(&Ray::new(Vec3::new(0.3, 0.2, 6.0), -Vec3::Z)).expect("hits");
        assert_eq!(si.ng.z < 0.0, inward, "{mirror} flip {flip}: {}", si.ng);
    }
    // A flattened sphere is an error (the transform's already).
    let flat = r#"<matrix value="0 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1"/>"#;
    let e = err(&scene(&format!(r#"<shape type="sphere"><transform name="to_world">{flat}</transform></shape>"#)));
    assert!(e.contains("test.xml:7:") && e.contains("singular"), "{e}");
}

/// A cylinder's `to_world` that scales unevenly across the axis, or shears, makes an elliptic
/// cylinder, as Mitsuba 3.9.1 renders it (with a warning): the hit, normal and (u, v) are
/// Mitsuba's for the same ray (its Python API, `scalar_rgb`). It cannot emit.
#[test]
fn cylinders_take_uneven_scales_as_mitsuba_does() {
    let d = Vec3::new(0.0, -1.0, 0.05).normalize();
    for (transform, p, n, uv) in [
        (r#"<scale x="1" y="2" z="1"/>"#, [0.1, 0.979796, 0.50101], [0.377964, 0.92582, 0.0], [0.217953, 0.50101]),
        (
            r#"<rotate z="1" angle="30"/><scale x="2" y="0.5" z="1.5"/>"#,
            [0.1, 0.248747, 0.537563],
            [0.025118, 0.999684, 0.0],
            [0.150725, 0.358375],
        ),
    ] {
        let file = load(&scene(&format!(
            r#"<shape type="cylinder"><float name="radius" value="0.5"/><transform name="to_world">{transform}</transform></shape>"#
        )))
        .unwrap();
        assert!(file.warnings.len() == 1 && file.warnings[0].contains("elliptic cylinder"), "{:?}", file.warnings);
        let Geometry::Cylinder(c) = &file.scene.geometries()[0] else { panic!("a cylinder") };
        let (t, local) = c.intersect(&Ray::new(Vec3::new(0.1, 5.0, 0.3), d), f32::INFINITY).expect("hits");
        let (sp, got_uv) = c.surface(local);
        let close = |a: Vec3, b: [f32; 3]| (a - Vec3::from_array(b)).abs().max_element() <= 2e-5;
        assert!(close(sp.p, p) && close(Vec3::new(0.1, 5.0, 0.3) + t * d, p), "{transform}: {}", sp.p);
        assert!(close(sp.n, n), "{transform}: {}", sp.n);
        assert!((got_uv - crate::math::Vec2::from_array(uv)).abs().max_element() < 2e-5, "{transform}: {got_uv}");
    }
    let e = err(&scene(
        r#"<shape type="cylinder"><emitter type="area"/><transform name="to_world"><scale y="2"/></transform></shape>"#,
    ));
    assert!(
        e.contains("test.xml:7:") && e.contains("an elliptic cylinder") && e.contains("cannot be an area emitter"),
        "{e}"
    );
}

#[test]
fn defaults_references_spectra_and_plugins() {
    let text = r#"<scene version="2.1.0">
    <default name="spp" value="7"/>
    <default name="col" value="0.25"/>
    <integrator type="path"><integer name="max_depth" value="3"/><boolean name="hide_emitters" value="true"/></integrator>
    <sensor type="thinlens">
        <float name="fov" value="30"/><string name="fov_axis" value="y"/>
        <float name="aperture_radius" value="0.1"/><float name="focus_distance" value="4"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0"/></transform>
        <sampler type="ldsampler"><integer name="sample_count" value="$spp"/><integer name="seed" value="3"/></sampler>
        <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="30"/>
            <integer name="crop_offset_x" value="5"/><integer name="crop_width" value="10"/>
            <rfilter type="tent"><float name="radius" value="1.5"/></rfilter></film>
    </sensor>
    <texture type="checkerboard" id="checks"><rgb name="color0" value="$col"/></texture>
    <bsdf type="diffuse" id="mat"><ref name="reflectance" id="checks"/></bsdf>
    <bsdf type="roughconductor" id="gold"><string name="material" value="Au"/><string name="distribution" value="ggx"/>
        <float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/></bsdf>
    <shape type="rectangle"><ref id="mat"/></shape>
    <shape type="disk"><ref id="gold"/><emitter type="area"><spectrum name="radiance" value="400:1, 700:1"/></emitter></shape>
    <shape type="cube"><bsdf type="twosided"><bsdf type="plastic"><float name="int_ior" value="1.6"/></bsdf></bsdf></shape>
    <shape type="sphere"><bsdf type="roughdielectric"><string name="int_ior" value="water"/></bsdf></shape>
    <shape type="sphere"><bsdf type="mask"><float name="opacity" value="0.3"/><bsdf type="conductor"/></bsdf></shape>
    <shape type="sphere"><bsdf type="blendbsdf"><float name="weight" value="0.2"/>
        <bsdf type="thindielectric"/><bsdf type="roughplastic"><string name="distribution" value="phong"/></bsdf></bsdf></shape>
    <shape type="shapegroup" id="g"><shape type="sphere"><float name="radius" value="0.1"/></shape></shape>
    <shape type="instance"><ref id="g"/><transform name="to_world"><translate x="2"/></transform></shape>
    <shape type="instance"><ref id="g"/><transform name="to_world"><translate x="-2"/></transform></shape>
    <emitter type="point"><point name="position" x="0" y="3" z="0"/><rgb name="intensity" value="5"/></emitter>
    <emitter type="spot"><transform name="to_world"><lookat origin="0,3,0" target="0,0,0" up="1,0,0"/></transform></emitter>
    <emitter type="directional"><vector name="direction" x="0" y="-1" z="0"/></emitter>
    <emitter type="constant"><spectrum name="radiance" value="0.5"/></emitter>
</scene>"#;
    let f = load(text).unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    assert_eq!((f.spp, f.sampler, f.seed), (7, SamplerKind::Sobol, 3));
    assert_eq!(f.window, Some([5, 0, 10, 30]));
    assert!(matches!(f.filter, Filter::Tent { radius } if radius == 1.5));
    assert!(
        matches!(f.integrator, crate::integrator::AnyIntegrator::Path(p) if p.settings.hide_emitters && p.settings.max_depth == 3)
    );
    // Two instanced spheres at x = ±2.
    let centres: Vec<Vec3> = f
        .scene
        .geometries()
        .iter()
        .filter_map(|g| match g {
            Geometry::Sphere(s) if s.radius < 0.2 => Some(s.center),
            _ => None,
        })
        .collect();
    assert_eq!(centres, vec![Vec3::new(2.0, 0.0, 0.0), Vec3::new(-2.0, 0.0, 0.0)]);
    // The checkerboard reaches the diffuse BSDF with the substituted colour.
    match &f.scene.bsdfs()[f.scene.shapes()[0].bsdf as usize] {
        Bsdf::Diffuse(d) => assert_eq!(d.reflectance.mean(), Rgb::splat(0.5 * (0.25 + 0.2))),
        b => panic!("{b:?}"),
    }
    // The emission spectrum is an illuminant (illuminant E is pinkish in sRGB), the constant
    // environment too, as in Mitsuba.
    let area = f.scene.lights().iter().find_map(|l| match l {
        Light::Area { radiance: crate::texture::Texture::Constant(c), .. } => Some(*c),
        _ => None,
    });
    let area = area.unwrap();
    assert!(area.x > area.y && area.y > area.z, "{area}");
    assert_eq!(f.scene.lights().len(), 5);
    let spot_axis = f.scene.lights().iter().find_map(|l| match l {
        Light::Spot { frame, .. } => Some(frame.to_world(Vec3::Z)),
        _ => None,
    });
    assert!((spot_axis.unwrap() - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-5);
    // The thin-lens camera is in place: the centre ray starts on the lens and aims at the focus.
    let r: Ray = f.scene.camera().generate_ray(crate::math::Vec2::new(20.0, 15.0), crate::math::Vec2::splat(0.5));
    assert!((r.d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5);
}

#[test]
fn includes_resolve_against_the_including_file() {
    let dir = std::env::temp_dir().join(format!("neumann-xml-include-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::write(
        dir.join("parts/materials.xml"),
        r#"<scene version="3.0.0"><bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf></scene>"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("main.xml"),
        scene(r#"<include filename="parts/materials.xml"/><shape type="sphere"><ref id="red"/></shape>"#),
    )
    .unwrap();
    let f = load_scene_file(&dir.join("main.xml"), &[]).unwrap();
    match &f.scene.bsdfs()[0] {
        Bsdf::Diffuse(d) => assert_eq!(d.reflectance.mean(), Rgb::new(0.8, 0.1, 0.1)),
        b => panic!("{b:?}"),
    }
    std::fs::write(dir.join("bad.xml"), scene(r#"<include filename="missing.xml"/>"#)).unwrap();
    let e = load_scene_file(&dir.join("bad.xml"), &[]).unwrap_err().to_string();
    assert!(e.contains("bad.xml:7:") && e.contains("missing.xml"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The Blender exporter's layout (mitsuba-data's StandardShaderBall): every object carries a
/// `name`, those placed directly in the scene too, and a material file is included by a
/// `$`-substituted name. Mitsuba's scene takes its nested objects whatever their names; two of
/// one name are an error (Mitsuba would drop the first without a word).
#[test]
fn named_objects_in_the_scene_as_blender_writes_them() {
    let dir = std::env::temp_dir().join(format!("neumann-xml-named-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("materials")).unwrap();
    std::fs::write(
        dir.join("materials/gold.xml"),
        r#"<scene version="3.0.0"><bsdf type="conductor" id="mat" name="mat"><string name="material" value="Au"/></bsdf></scene>"#,
    )
    .unwrap();
    let main = r#"<scene version="3.0.0">
    <default name="material" value="gold"/>
    <integrator type="path" id="elm__0" name="elm__0"><integer name="max_depth" value="3"/></integrator>
    <sensor type="perspective" id="camera" name="camera">
        <float name="fov" value="40"/>
        <sampler type="independent" name="sampler"><integer name="sample_count" value="7"/></sampler>
        <film type="hdrfilm" name="film"><integer name="width" value="20"/><integer name="height" value="10"/></film>
    </sensor>
    <include filename="materials/$material.xml"/>
    <shape type="rectangle" id="emit-light" name="emit-light">
        <emitter type="area" name="emitter"><rgb name="radiance" value="1"/></emitter>
        <bsdf type="null" name="bsdf"/>
    </shape>
    <shape type="sphere" id="ball" name="ball"><ref id="mat"/></shape>
    <emitter type="constant" id="sky" name="sky"/>
</scene>"#;
    std::fs::write(dir.join("main.xml"), main).unwrap();
    let f = load_scene_file(&dir.join("main.xml"), &[]).unwrap();
    assert_eq!((f.spp, f.scene.camera().width(), f.scene.camera().height()), (7, 20, 10));
    assert_eq!((f.scene.shapes().len(), f.scene.lights().len()), (2, 2));
    assert!(f.scene.bsdfs().iter().any(|b| matches!(b, Bsdf::Conductor(_))), "{:?}", f.scene.bsdfs());
    std::fs::write(dir.join("twice.xml"), main.replace(r#"name="sky""#, r#"name="ball""#)).unwrap();
    let e = load_scene_file(&dir.join("twice.xml"), &[]).unwrap_err().to_string();
    assert!(e.contains("twice.xml:15:") && e.contains("named 'ball'") && e.contains("twice.xml:14:"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Mitsuba's file resolution: `<path>` folders come first, then the main scene's folder; files
/// named inside an included file (nested includes, textures) resolve through that list, not
/// against the included file's own folder; a missing `<path>` folder and a `<path>` outside the
/// scene's root are located errors.
#[test]
fn paths_and_includes_resolve_as_mitsuba() {
    let dir = std::env::temp_dir().join(format!("neumann-xml-path-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::create_dir_all(dir.join("assets")).unwrap();
    crate::film::output::write_image(
        &dir.join("assets/tex.png"),
        1,
        1,
        &[Rgb::new(1.0, 0.0, 0.0)],
        &crate::film::output::ImageInfo::default(),
    )
    .unwrap();
    // parts/a.xml includes parts/b.xml by its path from the scene's folder, and names a texture
    // that only the <path> folder holds.
    std::fs::write(
        dir.join("parts/a.xml"),
        r#"<scene version="3.0.0"><include filename="parts/b.xml"/>
           <bsdf type="diffuse" id="tex"><texture type="bitmap" name="reflectance"><string name="filename" value="tex.png"/></texture></bsdf></scene>"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("parts/b.xml"),
        r#"<scene version="3.0.0"><bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf></scene>"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("main.xml"),
        scene(
            r#"<path value="assets"/><include filename="parts/a.xml"/>
            <shape type="sphere"><ref id="tex"/></shape><shape type="sphere"><ref id="red"/></shape>"#,
        ),
    )
    .unwrap();
    let f = load_scene_file(&dir.join("main.xml"), &[]).unwrap();
    let means: Vec<Rgb> = f
        .scene
        .bsdfs()
        .iter()
        .map(|b| match b {
            Bsdf::Diffuse(d) => d.reflectance.mean(),
            b => panic!("{b:?}"),
        })
        .collect();
    assert_eq!(means.len(), 2);
    assert!(means.iter().any(|m| (*m - Rgb::new(1.0, 0.0, 0.0)).abs().max_element() < 1e-3), "{means:?}");
    assert!(means.contains(&Rgb::new(0.8, 0.1, 0.1)), "{means:?}");
    std::fs::write(dir.join("nofolder.xml"), scene(r#"<path value="nowhere"/>"#)).unwrap();
    let e = load_scene_file(&dir.join("nofolder.xml"), &[]).unwrap_err().to_string();
    assert!(e.contains("nofolder.xml:7:") && e.contains("folder \"nowhere\" not found"), "{e}");
    std::fs::write(dir.join("nested.xml"), scene(r#"<shape type="sphere"><path value="assets"/></shape>"#)).unwrap();
    let e = load_scene_file(&dir.join("nested.xml"), &[]).unwrap_err().to_string();
    assert!(e.contains("must be a child of the <scene>"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// An area emitter declared at the top level with an id lights every shape that references it;
/// without an id it is an error.
#[test]
fn area_emitters_by_reference() {
    let f = load(&scene(
        r#"<emitter type="area" id="lamp"><rgb name="radiance" value="2, 3, 4"/></emitter>
           <shape type="sphere"><ref id="lamp"/></shape>
           <shape type="rectangle"><ref id="lamp"/></shape>
           <shape type="sphere"><point name="center" x="3" y="0" z="0"/></shape>"#,
    ))
    .unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    assert_eq!(f.scene.lights().len(), 2);
    assert!(f
        .scene
        .lights()
        .iter()
        .all(|l| matches!(l, Light::Area { radiance: crate::texture::Texture::Constant(c), .. } if *c == Rgb::new(2.0, 3.0, 4.0))));
    let e = load(&scene(r#"<emitter type="area"><rgb name="radiance" value="1"/></emitter>"#)).unwrap_err();
    assert!(e.to_string().contains("nested in the <shape> that emits, or given an id"), "{e}");
    let e = load(&scene(r#"<emitter type="area" id="lost"><rgb name="radiance" value="1"/></emitter>"#)).unwrap_err();
    assert!(e.to_string().contains("no shape references this area emitter") && e.to_string().contains("lost"), "{e}");
}

/// Mitsuba's `directionalarea`: nested in a shape or referenced by id like an area emitter; the
/// shape's default BSDF is black, as for any emitting shape; its parameter is `radiance`, and
/// what Mitsuba refuses (a `to_world`) is a located error.
#[test]
fn directional_area_emitters() {
    let f = load(&scene(
        r#"<shape type="rectangle"><emitter type="directionalarea"><rgb name="radiance" value="2, 3, 4"/></emitter></shape>
           <emitter type="directionalarea" id="lamp"/>
           <shape type="disk"><ref id="lamp"/></shape>"#,
    ))
    .unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let radiances: Vec<Rgb> = f
        .scene
        .lights()
        .iter()
        .map(|l| match l {
            Light::DirectionalArea { radiance: crate::texture::Texture::Constant(c), .. } => *c,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(radiances, [Rgb::new(2.0, 3.0, 4.0), Rgb::ONE]);
    for shape in f.scene.shapes() {
        assert!(shape.light.is_some(), "the emitting shape knows its light (hide_emitters passes through it)");
        assert!(matches!(&f.scene.bsdfs()[shape.bsdf as usize], Bsdf::Diffuse(d) if matches!(d.reflectance, crate::texture::Texture::Constant(c) if c == Rgb::ZERO)));
    }
    for (body, expectation) in [
        (r#"<emitter type="directionalarea"/>"#, "a directionalarea emitter must be nested in the <shape>"),
        (r#"<emitter type="directionalarea" id="x"/>"#, "no shape references this directionalarea emitter"),
        (
            r#"<shape type="sphere"><emitter type="directionalarea"><transform name="to_world"/></emitter></shape>"#,
            "to_world",
        ),
        (
            r#"<shape type="sphere"><emitter type="directionalarea"><rgb name="radiance" value="1e38"/></emitter><float name="radius" value="1e3"/></shape>"#,
            "overflows",
        ),
        (r#"<shape type="sphere"><emitter type="spot"/></shape>"#, "only an 'area' or 'directionalarea' emitter"),
        (
            r#"<shape type="rectangle"><emitter type="directionalarea"><texture type="mesh_attribute" name="radiance"><string name="name" value="vertex_color"/></texture></emitter></shape>"#,
            "a mesh_attribute texture as an area emitter's radiance is not implemented",
        ),
    ] {
        let e = err(&scene(body));
        assert!(e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
}

/// Mitsuba's `sunsky`: every parameter read (a direction, or a time and place), the sun where
/// the parameters put it, a sun below the horizon a warning, and every refusal a located error.
#[test]
fn sunsky_emitters() {
    let f = load(&scene(
        r#"<emitter type="sunsky"><vector name="sun_direction" x="0.3" y="0.2" z="0.8"/>
             <float name="turbidity" value="5"/><rgb name="albedo" value="0.1, 0.2, 0.3"/>
             <float name="sun_scale" value="0.5"/><float name="sky_scale" value="2"/>
             <float name="sun_aperture" value="1.5"/><boolean name="complex_sun" value="true"/></emitter>"#,
    ))
    .unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let Light::SunSky { sky, .. } = &f.scene.lights()[0] else { panic!("{:?}", f.scene.lights()) };
    assert!((sky.sun_direction() - Vec3::new(0.3, 0.2, 0.8).normalize()).length() < 1e-6);
    assert!(f.scene.lights()[0].is_infinite());
    // A time and place in a y-up frame: the local zenith +z turned to +y.
    let f = load(&scene(
        r#"<emitter type="sunsky"><float name="latitude" value="-33.9"/><float name="longitude" value="18.4"/>
             <float name="timezone" value="2"/><integer name="year" value="1999"/><integer name="month" value="12"/>
             <integer name="day" value="31"/><float name="hour" value="17"/><float name="minute" value="0"/>
             <float name="second" value="0"/><transform name="to_world"><rotate x="1" angle="-90"/></transform></emitter>"#,
    ))
    .unwrap();
    let Light::SunSky { sky, .. } = &f.scene.lights()[0] else { panic!() };
    let local = crate::light::sun_direction(
        &crate::light::DateTime { year: 1999, month: 12, day: 31, hour: 17.0, minute: 0.0, second: 0.0 },
        &crate::light::Location { latitude: -33.9, longitude: 18.4, timezone: 2.0 },
    );
    let world = crate::math::Transform::rotate(Vec3::X, -90.0).unwrap().apply_vector(local);
    assert!((sky.sun_direction() - world).length() < 1e-5, "{} vs {world}", sky.sun_direction());
    assert!(world.y > 0.5, "up is +y: {world}");
    // Midnight: the sun below the horizon, nothing emitted (Mitsuba warns too); a street lamp
    // lights the scene.
    let night =
        load(&scene(r#"<emitter type="sunsky"><float name="hour" value="1"/></emitter><emitter type="point"/>"#))
            .unwrap();
    assert!(night.warnings.iter().any(|w| w.contains("below the horizon")), "{:?}", night.warnings);
    // The sun alone at night: rendered black (as Mitsuba does), with a warning.
    let dark = load(&scene(r#"<emitter type="sunsky"><float name="hour" value="1"/></emitter>"#)).unwrap();
    assert!(dark.warnings.iter().any(|w| w.contains("emits nothing: only black")), "{:?}", dark.warnings);
    assert!(!night.warnings.iter().any(|w| w.contains("only black")), "{:?}", night.warnings);
    assert!(dark.scene.lights_are_off() && !night.scene.lights_are_off());
    for (body, expectation) in [
        (
            r#"<emitter type="sunsky"><vector name="sun_direction" x="0" y="0" z="1"/><float name="hour" value="9"/></emitter>"#,
            "either sun_direction or a time and place",
        ),
        (r#"<emitter type="sunsky"><float name="turbidity" value="11"/></emitter>"#, "turbidity 11 is outside [1, 10]"),
        (r#"<emitter type="sunsky"><float name="sun_scale" value="-1"/></emitter>"#, "sun_scale -1 must be"),
        (r#"<emitter type="sunsky"><float name="sun_aperture" value="0"/></emitter>"#, "sun_aperture 0°"),
        (r#"<emitter type="sunsky"><vector name="sun_direction" x="0" y="0" z="0"/></emitter>"#, "has no direction"),
        (r#"<emitter type="sunsky"><integer name="month" value="99999999999"/></emitter>"#, "out of range"),
        (r#"<emitter type="sunsky"><float name="year" value="2010"/></emitter>"#, "year"),
        (r#"<emitter type="sunsky"><rgb name="albedo" value="0.5, 1.5, 0.5"/></emitter>"#, "albedo"),
        (r#"<emitter type="sunsky"><texture type="checkerboard" name="albedo"/></emitter>"#, "the same everywhere"),
        (r#"<emitter type="sunsky"><float name="sun_radius" value="1"/></emitter>"#, "sun_radius"),
        (r#"<emitter type="sunsky"><float name="hour" value="1e39"/></emitter>"#, "'hour' must be finite"),
        (r#"<emitter type="timed_sunsky"><integer name="end_year" value="2024"/></emitter>"#, "end date is before"),
        (r#"<emitter type="timed_sunsky"><float name="window_end_time" value="6"/></emitter>"#, "ends before it starts"),
        (r#"<emitter type="timed_sunsky"><float name="shutter_close" value="0"/></emitter>"#, "after shutter_open"),
        (r#"<emitter type="timed_sunsky"><float name="window_start_time" value="25"/></emitter>"#, "an hour in [0, 24]"),
    ] {
        let e = err(&scene(body));
        assert!(e.contains(expectation), "expected '{expectation}' in:\n{e}");
        assert!(e.contains("test.xml:7:"), "located on the emitter's line: {e}");
    }
}

/// References to objects declared later in the file work, as in Mitsuba (nested objects too);
/// the object is built once; a reference cycle and an id declared nowhere are located errors.
#[test]
fn forward_references() {
    let f = load(&scene(
        r#"<shape type="sphere"><ref id="later"/></shape>
           <shape type="rectangle"><bsdf type="blendbsdf"><ref name="weight" id="w"/><ref id="later"/><ref id="later"/></bsdf></shape>
           <bsdf type="diffuse" id="later"><rgb name="reflectance" value="0.25, 0.5, 0.75"/></bsdf>
           <texture type="checkerboard" id="w"/>"#,
    ))
    .unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    assert!(matches!(&f.scene.bsdfs()[0], Bsdf::Diffuse(d) if d.reflectance.mean() == Rgb::new(0.25, 0.5, 0.75)));
    assert!(matches!(&f.scene.bsdfs()[1], Bsdf::Blend { .. }));
    let cycle = load(&scene(
        r#"<bsdf type="twosided" id="a"><ref id="b"/></bsdf><bsdf type="twosided" id="b"><ref id="a"/></bsdf>"#,
    ))
    .unwrap_err()
    .to_string();
    assert!(cycle.contains("circular reference") && cycle.contains("test.xml:7:"), "{cycle}");
    let missing = load(&scene(r#"<shape type="sphere"><ref id="nowhere"/></shape>"#)).unwrap_err().to_string();
    assert!(missing.contains("unknown id 'nowhere'"), "{missing}");
    let itself = load(&scene(r#"<bsdf type="twosided" id="a"><ref id="a"/></bsdf>"#)).unwrap_err().to_string();
    assert!(itself.contains("circular reference to 'a'"), "{itself}");
    // An alias of an id declared later.
    let f = load(&scene(
        r#"<alias id="later" as="other"/><shape type="sphere"><ref id="other"/></shape>
           <bsdf type="diffuse" id="later"><rgb name="reflectance" value="0.25"/></bsdf>"#,
    ))
    .unwrap();
    assert_eq!(f.scene.bsdfs().len(), 1);
}

/// References across included files bind as Mitsuba binds them, once the whole scene is read:
/// the main file may name an id that a later include declares, and an included file an id
/// that the main file declares after the include.
#[test]
fn forward_references_across_includes() {
    let dir = std::env::temp_dir().join(format!("neumann-xml-fwd-include-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("mats.xml"),
        r#"<scene version="3.0.0">
    <bsdf type="diffuse" id="green"><rgb name="reflectance" value="0.2, 0.8, 0.2"/></bsdf>
    <shape type="sphere"><point name="center" x="2" y="0" z="0"/><ref id="red"/></shape>
</scene>"#,
    )
    .unwrap();
    let main = scene(
        r#"<shape type="sphere"><ref id="green"/></shape>
    <include filename="mats.xml"/>
    <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.2, 0.2"/></bsdf>"#,
    );
    let f = load_scene_text(&dir.join("main.xml"), &main, &[]).unwrap();
    let reflectances: Vec<Rgb> =
        f.scene.bsdfs().iter().map(|b| b.diffuse_reflectance(&Default::default(), Vec3::Z)).collect();
    assert_eq!(reflectances.len(), 2, "{reflectances:?}");
    assert!(reflectances.contains(&Rgb::new(0.2, 0.8, 0.2)) && reflectances.contains(&Rgb::new(0.8, 0.2, 0.2)));
    std::fs::remove_dir_all(&dir).ok();
}

/// Each user mistake gives file:line:col, what was expected, and the source line.
#[test]
fn errors_name_the_place_and_the_expectation() {
    let cases: &[(&str, &str, &str)] = &[
        (r#"<shape type="sphere"><bsdf type="difuse"/></shape>"#, "test.xml:7:22:", "nearest is 'diffuse'"),
        (r#"<shape type="sphere"><float name="radius" value="big"/></shape>"#, "test.xml:7:", "expected a number"),
        (r#"<shape type="sphere"><string name="radius" value="1"/></shape>"#, "test.xml:7:22", "must be a <float>"),
        (r#"<shape type="sphere"><ref id="nothing"/></shape>"#, "test.xml:7:22", "unknown id 'nothing'"),
        (r#"<shape type="obj"><string name="filename" value="nope.obj"/></shape>"#, "test.xml:7:", "nope.obj"),
        (
            r#"<shape type="sphere"><float name="radius" value="$r"/></shape>"#,
            "test.xml:7:",
            "undefined parameter '$r'",
        ),
        (r#"<shape type="sphear"/>"#, "test.xml:7:1", "nearest is 'sphere'"),
        (
            r#"<shape type="sphere"><bsdf type="conductor"><string name="material" value="Gold"/></bsdf></shape>"#,
            "test.xml:7:",
            "unknown conductor material 'Gold'",
        ),
        (
            r#"<shape type="sphere"><bsdf type="dielectric"><string name="int_ior" value="glass"/></bsdf></shape>"#,
            "test.xml:7:",
            "unknown index of refraction",
        ),
        (r#"<shpe type="sphere"/>"#, "test.xml:7:1", "did you mean <shape>"),
        (
            r#"<shape type="sphere"><float name="radius" value="1"/><float name="radius" value="2"/></shape>"#,
            "test.xml:7:",
            "given twice",
        ),
        (r#"<emitter type="area"/>"#, "test.xml:7:1", "nested in the <shape>"),
        (
            r#"<shape type="sphere"><transform name="to_world"><rotate angle="90"/></transform></shape>"#,
            "test.xml:7:",
            "the rotation axis is zero",
        ),
        (r#"<medium type="homogeneous"><float name="albedo" value="-1"/></medium>"#, "test.xml:7:", "albedo"),
        (
            r#"<emitter type="constant"><texture type="checkerboard" name="radiance"/></emitter>"#,
            "test.xml:7:",
            "must be the same everywhere",
        ),
        // Mitsuba rejects RGB reflectances outside [0, 1] (a <float> or <spectrum> passes).
        (
            r#"<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="1.2, 0.5, 0.5"/></bsdf></shape>"#,
            "test.xml:7:",
            "an <rgb> value must lie in [0, 1]",
        ),
        (
            r#"<shape type="sphere"><bsdf type="dielectric"><rgb name="specular_transmittance" value="1.5"/></bsdf></shape>"#,
            "test.xml:7:",
            "an <rgb> value must lie in [0, 1]",
        ),
    ];
    for (body, position, expectation) in cases {
        let e = err(&scene(body));
        assert!(e.starts_with(position), "expected {position} in:\n{e}");
        assert!(e.contains(expectation), "expected '{expectation}' in:\n{e}");
        assert!(e.contains("\n7 | "), "the source line is quoted:\n{e}");
    }
    // Malformed XML, wrong root, missing version, no sensor.
    let e = err("<scene version=\"3.0.0\">\n  <shape type=\"sphere\">\n</scene>");
    assert!(e.starts_with("test.xml:3:") && e.contains("malformed XML"), "{e}");
    assert!(err("<bsdf type=\"diffuse\"/>").contains("expected a <scene> root"));
    assert!(err("<scene><sensor type=\"perspective\"/></scene>").contains("version"));
    assert!(err("<scene version=\"3.0.0\"/>").contains("no <sensor>"));
}

#[test]
fn unused_parameters_are_errors_as_in_mitsuba() {
    let e = err(&scene(
        r#"<shape type="sphere"><float name="radius" value="1"/><float name="raduis" value="2"/><integer name="k" value="2"/></shape>"#,
    ));
    assert!(
        e.contains("test.xml:7:")
            && e.contains("shape 'sphere' does not take the parameters float 'raduis', integer 'k'"),
        "{e}"
    );
    // Mitsuba's parameters that cannot change the image are read (and ignored).
    let f = load(&scene(
        r#"<integrator type="path"><integer name="block_size" value="32"/><integer name="samples_per_pass" value="4"/></integrator>
        <emitter type="constant"><float name="sampling_weight" value="2"/></emitter>"#,
    ))
    .unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
}

#[test]
fn meshes_load_relative_to_the_scene_with_mitsuba_options() {
    let dir = std::env::temp_dir().join(format!("neumann-xml-mesh-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(
        dir.join("meshes/quad.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("s.xml"),
        scene(
            r#"<shape type="obj"><string name="filename" value="meshes/quad.obj"/><boolean name="face_normals" value="true"/>
               <boolean name="flip_normals" value="true"/></shape>"#,
        ),
    )
    .unwrap();
    let f = load_scene_file(&dir.join("s.xml"), &[]).unwrap();
    match &f.scene.geometries()[0] {
        Geometry::Mesh(m) => {
            assert!(m.normals.is_empty() && m.flip_normals);
            // OBJ's v-up coordinates are flipped to Mitsuba's row-down convention.
            assert_eq!(m.uvs[0], crate::math::Vec2::new(0.0, 1.0));
        }
        g => panic!("{g:?}"),
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A scene of several mesh files reads them in parallel before the build: each shape still gets
/// its own file with its own options (a file named twice is copied for its first use, moved for
/// its last, each placed by its own `to_world`), and a file that cannot be read is reported at
/// the shape naming it, after the shapes before it were read.
#[test]
fn mesh_files_read_ahead_keep_their_shapes_and_errors() {
    let dir = std::env::temp_dir().join(format!("neumann-xml-prefetch-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n").unwrap();
    std::fs::write(dir.join("quad.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
    let shapes = r#"<shape type="obj"><string name="filename" value="tri.obj"/></shape>
        <shape type="obj"><string name="filename" value="quad.obj"/></shape>
        <shape type="obj"><string name="filename" value="tri.obj"/><boolean name="flip_tex_coords" value="false"/>
            <transform name="to_world"><translate z="5"/></transform></shape>"#;
    std::fs::write(dir.join("s.xml"), scene(shapes)).unwrap();
    let f = load_scene_file(&dir.join("s.xml"), &[]).unwrap();
    let mesh = |k: usize| match &f.scene.geometries()[k] {
        Geometry::Mesh(m) => m.clone(),
        g => panic!("{g:?}"),
    };
    let (a, b, c) = (mesh(0), mesh(1), mesh(2));
    assert_eq!((a.len(), b.len(), c.len()), (1, 2, 1));
    assert_eq!(a.uvs[0], crate::math::Vec2::new(0.0, 1.0), "flipped by default");
    assert_eq!(c.uvs[0], crate::math::Vec2::new(0.0, 0.0), "this shape's own option");
    assert_eq!((a.positions[1].z, c.positions[1].z), (0.0, 5.0), "each placed by its own to_world");
    let broken = format!("{shapes}\n<shape type=\"obj\"><string name=\"filename\" value=\"missing.obj\"/></shape>");
    std::fs::write(dir.join("t.xml"), scene(&broken)).unwrap();
    let e = load_scene_file(&dir.join("t.xml"), &[]).unwrap_err().to_string();
    assert!(e.contains("t.xml:") && e.contains("missing.obj"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Mitsuba's default BSDFs: diffuse 0.5 on plain shapes, black on emitters (a light source that
/// reflected light would add a bounce Mitsuba does not have).
#[test]
fn default_bsdfs_follow_mitsuba() {
    let f = load(&scene(
        r#"<shape type="sphere"/>
           <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#,
    ))
    .unwrap();
    let albedo = |shape: usize| match &f.scene.bsdfs()[f.scene.shapes()[shape].bsdf as usize] {
        Bsdf::Diffuse(d) => d.reflectance.mean(),
        b => panic!("{b:?}"),
    };
    assert_eq!(albedo(0), Rgb::splat(0.5));
    assert_eq!(albedo(1), Rgb::ZERO);
}

/// Bad input gives an error, never a panic: every scene of `scenes/` cut short at many places,
/// and with single bytes changed, is either loaded or refused with a message.
#[test]
fn mangled_scenes_never_panic() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut rng = crate::sampling::Pcg32::new(2026, 11);
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("xml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        // Truncations at char boundaries (scene comments may hold non-ASCII text).
        let cut = |k: usize| {
            let mut i = text.len() * k / 40;
            while !text.is_char_boundary(i) {
                i -= 1;
            }
            text[..i].to_string()
        };
        let mut variants: Vec<String> = (1..40).map(cut).collect();
        for _ in 0..60 {
            let mut bytes = text.clone().into_bytes();
            let i = rng.next_u32() as usize % bytes.len();
            bytes[i] = b"<>/=\"x0-9 $&."[rng.next_u32() as usize % 13];
            if let Ok(s) = String::from_utf8(bytes) {
                variants.push(s);
            }
        }
        for v in variants {
            let result = std::panic::catch_unwind(|| {
                // Small films keep the successful loads cheap.
                load_scene_text(&path, &v, &[("res".into(), "8".into())]).map(|_| ())
            });
            match result {
                Ok(Ok(())) => {}
                Ok(Err(e)) => assert!(!e.message.is_empty()),
                Err(_) => panic!("loading a mangled {} panicked:\n{v}", path.display()),
            }
            checked += 1;
        }
    }
    assert!(checked > 500, "{checked}");
}

#[test]
fn ptracer_and_radiosity_integrators() {
    use crate::integrator::{radiosity::Method, AnyIntegrator};
    let f = load(&scene(r#"<integrator type="ptracer"><integer name="max_depth" value="3"/><boolean name="hide_emitters" value="true"/></integrator>"#)).unwrap();
    assert!(
        matches!(f.integrator, AnyIntegrator::Ptracer(t) if t.settings.max_depth == 3 && t.settings.hide_emitters && t.settings.rr_depth == 5)
    );
    let f = load(&scene(
        r#"<integrator type="radiosity">
            <float name="patch_size" value="0.2"/><string name="method" value="shooting"/>
            <integer name="rays_per_patch" value="64"/><boolean name="smooth" value="true"/>
            <float name="tolerance" value="1e-3"/>
        </integrator>"#,
    ))
    .unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let AnyIntegrator::Radiosity(o) = f.integrator else { panic!("radiosity expected") };
    assert_eq!((o.patch_size, o.method, o.rays_per_patch, o.smooth), (0.2, Method::Shooting, 64, true));
    assert!((o.tolerance - 1e-3).abs() < 1e-9);
    let e = err(&scene(r#"<integrator type="radiosity"><string name="method" value="gauss-seidel"/></integrator>"#));
    assert!(e.contains("test.xml:") && e.contains("did you mean 'gauss_seidel'"), "{e}");
    let e = err(&scene(r#"<integrator type="radiosity"><float name="patch_size" value="0"/></integrator>"#));
    assert!(e.contains("patch_size"), "{e}");
    let e = err(&scene(r#"<integrator type="ptracr"/>"#));
    assert!(e.contains("ptracer"), "{e}");
}

#[test]
fn media_on_shapes_and_the_sensor() {
    use crate::medium::{Coefficients, PhaseFunction};
    let text = r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="7"/></integrator>
    <medium type="homogeneous" id="fog">
        <rgb name="sigma_t" value="0.5, 1, 0.25"/><float name="scale" value="2"/>
        <float name="albedo" value="0.9"/>
        <phase type="hg"><float name="g" value="0.3"/></phase>
    </medium>
    <sensor type="perspective">
        <ref id="fog"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <shape type="sphere">
        <bsdf type="null"/>
        <ref name="exterior" id="fog"/>
        <medium type="homogeneous" name="interior"><float name="sigma_t" value="3"/><rgb name="radiance" value="4, 2, 0"/></medium>
    </shape>
</scene>"#;
    let f = load(text).unwrap();
    // neumann's emissive media: `radiance`, any non-negative illuminant.
    assert!(f.scene.media()[0].radiance.is_none());
    let le = f.scene.media()[1].radiance.as_ref().expect("emissive").eval(crate::math::Vec3::ZERO);
    assert_eq!(le, Rgb::new(4.0, 2.0, 0.0));
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    assert!(matches!(f.integrator, crate::integrator::AnyIntegrator::VolPath(v) if v.settings.max_depth == 7));
    let s = &f.scene;
    assert_eq!(s.media().len(), 2);
    assert_eq!(s.camera_medium(), Some(0));
    let coefficients = |i: usize| match &s.media()[i].coefficients {
        Coefficients::Homogeneous(h) => h.clone(),
        other => panic!("{other:?}"),
    };
    assert_eq!(coefficients(0).sigma_t, Rgb::new(1.0, 2.0, 0.5));
    assert!(matches!(s.media()[0].phase, PhaseFunction::HenyeyGreenstein { g: 0.3 }));
    assert_eq!(coefficients(1).albedo, Rgb::splat(0.75), "Mitsuba's default albedo");
    assert!(matches!(s.media()[1].phase, PhaseFunction::Isotropic));
    assert_eq!((s.shapes()[0].interior, s.shapes()[0].exterior), (Some(1), Some(0)));
    assert!(matches!(s.bsdfs()[s.shapes()[0].bsdf as usize], Bsdf::Null));
    for (bad, what) in [
        (r#"<medium type="homogenous" id="m"/>"#, "the nearest is 'homogeneous'"),
        (
            r#"<medium type="homogeneous" id="m"><volume type="gridvolume" name="sigma_t"><string name="filename" value="scenes/assets/albedo.vol"/></volume></medium>"#,
            "give a heterogeneous medium this volume",
        ),
        (r#"<medium type="homogeneous" id="m"><float name="albedo" value="1.5"/></medium>"#, "albedo"),
        (r#"<medium type="homogeneous" id="m"><phase type="hg"><float name="g" value="1"/></phase></medium>"#, "'g'"),
        (r#"<medium type="homogeneous" id="m"><phase type="raleigh"/></medium>"#, "the nearest is 'rayleigh'"),
        (r#"<phase type="hg"/>"#, "nested in a <medium>"),
        (r#"<medium type="homogeneous" id="m"><float name="radiance" value="-1"/></medium>"#, "radiance"),
        (
            r#"<medium type="homogeneous" id="m"><volume type="constvolume" name="radiance"/></medium>"#,
            "a homogeneous medium's radiance",
        ),
        (r#"<medium type="heterogeneous" id="m"><float name="radiance" value="inf"/></medium>"#, "radiance"),
    ] {
        let e = err(&scene(bad));
        assert!(e.contains("test.xml:") && e.contains(what), "{bad}: {e}");
    }
}

/// Mitsuba's `homogeneous` reads its coefficients as volumes: a `constvolume` gives its value
/// (an rgb beyond 1 too, as an extinction), with `scale` applied.
#[test]
fn homogeneous_media_take_constant_volumes() {
    use crate::medium::Coefficients;
    let text = scene(
        r#"<medium type="homogeneous" id="m">
        <volume type="constvolume" name="sigma_t"><rgb name="value" value="0.6, 3, 0.15"/></volume>
        <float name="scale" value="2"/>
        <volume type="constvolume" name="albedo"><float name="value" value="0.5"/></volume></medium>
    <shape type="sphere"><bsdf type="null"/><ref name="interior" id="m"/></shape>"#,
    );
    let f = load(&text).unwrap_or_else(|e| panic!("{e}"));
    let Coefficients::Homogeneous(h) = &f.scene.media()[0].coefficients else { panic!() };
    assert_eq!((h.sigma_t, h.albedo), (Rgb::new(1.2, 6.0, 0.3), Rgb::splat(0.5)));
}

/// Mitsuba's `has_spectral_extinction` is read on both media: false where the extinction is
/// grey changes nothing; where it is not, neumann still tracks spectrally and warns at the
/// parameter (Mitsuba would track one channel, biased).
#[test]
fn has_spectral_extinction_is_read_and_warned_about_where_it_matters() {
    let medium = |ty: &str, sigma_t: &str| {
        scene(&format!(
            r#"<medium type="{ty}" id="m"><rgb name="sigma_t" value="{sigma_t}"/>
            <boolean name="has_spectral_extinction" value="false"/></medium>
    <shape type="sphere"><bsdf type="null"/><ref name="interior" id="m"/></shape>"#
        ))
    };
    for ty in ["homogeneous", "heterogeneous"] {
        let grey = load(&medium(ty, "0.5, 0.5, 0.5")).unwrap_or_else(|e| panic!("{e}"));
        assert!(grey.warnings.is_empty(), "{ty}: {:?}", grey.warnings);
        let chromatic = load(&medium(ty, "0.5, 1, 0.25")).unwrap();
        assert_eq!(chromatic.warnings.len(), 1, "{ty}: {:?}", chromatic.warnings);
        let w = &chromatic.warnings[0];
        assert!(w.contains("test.xml:8:") && w.contains("has_spectral_extinction"), "{w}");
    }
}

/// Mitsuba's `rayleigh`, `tabphase` and `blendphase` (weight a float or a `<volume>`, two
/// nested phases, nesting again) load with their parameters; a bad table, a missing weight or
/// the wrong number of nested phases is an error at its place.
#[test]
fn rayleigh_tabulated_and_blended_phases() {
    use crate::math::PI;
    use crate::medium::PhaseFunction;
    let medium = |phase: &str| {
        format!(
            r#"<medium type="homogeneous" id="m">{phase}</medium><shape type="sphere"><bsdf type="null"/><ref name="interior" id="m"/></shape>"#
        )
    };
    let (wo, wi, p) = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0), Vec3::ZERO);
    let phase_of = |xml: &str| load(&scene(&medium(xml))).unwrap().scene.media()[0].phase.clone();
    assert!(matches!(phase_of(r#"<phase type="rayleigh"/>"#), PhaseFunction::Rayleigh));
    // Forward (wi = -wo) under a table rising to 1 at cos θ = 1: 2 / 2π.
    let t = phase_of(r#"<phase type="tabphase"><string name="values" value="0, 0 1"/></phase>"#);
    assert!(matches!(t, PhaseFunction::Tabulated(_)) && (t.eval(p, wo, wi) - 1.0 / PI).abs() < 1e-6);
    let b = phase_of(
        r#"<phase type="blendphase"><float name="weight" value="0.25"/>
            <phase type="hg"><float name="g" value="0.5"/></phase>
            <phase type="blendphase"><volume type="constvolume" name="weight"><float name="value" value="1"/></volume>
                <phase type="isotropic"/><phase type="rayleigh"/></phase>
        </phase>"#,
    );
    // 0.75 HG(0.5) forward + 0.25 Rayleigh forward.
    let expected = 0.75 * 0.75 / (4.0 * PI * 0.125) + 0.25 * 3.0 / (8.0 * PI);
    assert!((b.eval(p, wo, wi) - expected).abs() < 1e-5, "{}", b.eval(p, wo, wi));
    for (bad, what) in [
        (r#"<phase type="tabphase"/>"#, "'values'"),
        (r#"<phase type="tabphase"><string name="values" value="1, x"/></phase>"#, "'x' is not a number"),
        (r#"<phase type="tabphase"><string name="values" value="1"/></phase>"#, "at least two"),
        (r#"<phase type="tabphase"><string name="values" value="1, -1"/></phase>"#, "non-negative"),
        (r#"<phase type="tabphase"><string name="values" value="0, 0"/></phase>"#, "no mass"),
        (r#"<phase type="blendphase"><phase type="isotropic"/><phase type="rayleigh"/></phase>"#, "'weight'"),
        (
            r#"<phase type="blendphase"><float name="weight" value="0.5"/><phase type="isotropic"/></phase>"#,
            "two nested",
        ),
        (
            r#"<phase type="blendphase"><float name="weight" value="0.5"/><phase type="isotropic"/><bsdf type="diffuse"/></phase>"#,
            "<bsdf> cannot be nested",
        ),
        (r#"<phase type="rayleigh"><float name="g" value="0.5"/></phase>"#, "'g'"),
    ] {
        let e = match load(&scene(&medium(bad))) {
            Ok(f) => f.warnings.join("; "),
            Err(e) => e.to_string(),
        };
        assert!(e.contains("test.xml:") && e.contains(what), "{bad}: {e}");
    }
}

/// The integrator's `light_sampler` picks the scene's light sampler (default the light BVH); a
/// wrong name is a located error naming the choices; integrators without next-event estimation
/// do not read it (an unused-parameter warning).
#[test]
fn light_sampler_parameter() {
    use crate::light::LightSamplerKind;
    let light = r#"<shape type="sphere"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>"#;
    let f = load(&scene(light)).unwrap();
    assert_eq!(f.scene.light_sampler_kind(), LightSamplerKind::Bvh);
    for &(kind, name, _) in <LightSamplerKind as crate::choice::Choice>::CHOICES {
        for integrator in ["path", "volpath", "direct"] {
            let body = format!(
                r#"<integrator type="{integrator}"><string name="light_sampler" value="{name}"/></integrator>{light}"#
            );
            let f = load(&scene(&body)).unwrap();
            assert_eq!(f.scene.light_sampler_kind(), kind, "{integrator} {name}");
            assert!(f.warnings.is_empty(), "{:?}", f.warnings);
        }
    }
    let e = load(&scene(&format!(
        r#"<integrator type="path"><string name="light_sampler" value="bhv"/></integrator>{light}"#
    )))
    .unwrap_err();
    assert!(e.to_string().contains("bvh, power, uniform") && e.to_string().contains("test.xml:"), "{e}");
    let e = err(&scene(&format!(
        r#"<integrator type="ptracer"><string name="light_sampler" value="power"/></integrator>{light}"#
    )));
    assert!(e.contains("light_sampler"), "{e}");
}

/// The `aov` integrator's `dp_du`, `dp_dv`, `duv_dx`, `duv_dy` on a rectangle (a mesh in
/// neumann, analytic in Mitsuba), a sphere, a disk and a cylinder, seen by a pinhole, a thin
/// lens and an orthographic camera: the values Mitsuba 3.9.1 computes for the same camera ray
/// (its `sample_ray_differential` at the same film position and lens sample, differentials
/// scaled by 1/√16, `ray_intersect`, `compute_uv_partials`).
#[test]
fn aov_derivatives_match_mitsuba() {
    use crate::integrator::aov::uv_partials;
    use crate::math::Vec2;
    let film = r#"<film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="30"/></film>"#;
    let view = r#"<lookat origin="1,3,7" target="0,0.5,0" up="0,1,0"/>"#;
    let sensor = |ty: &str, params: &str, scale: &str| {
        format!(r#"<sensor type="{ty}">{params}{film}<transform name="to_world">{scale}{view}</transform></sensor>"#)
    };
    let fov = r#"<float name="fov" value="50"/>"#;
    let lens = r#"<float name="aperture_radius" value="0.2"/><float name="focus_distance" value="6"/>"#;
    let sensors = [
        ("persp", sensor("perspective", fov, "")),
        ("thin", sensor("thinlens", &format!("{fov}{lens}"), "")),
        ("ortho", sensor("orthographic", "", r#"<scale x="3" y="3"/>"#)),
    ];
    let shapes = r#"<shape type="rectangle"><transform name="to_world"><scale x="5" y="3"/><rotate x="1" angle="-90"/><rotate y="1" angle="20"/></transform></shape>
        <shape type="sphere"><point name="center" x="-1.5" y="1" z="0"/><float name="radius" value="1"/></shape>
        <shape type="disk"><transform name="to_world"><scale value="0.8"/><rotate x="1" angle="-60"/><translate x="0" y="0.6" z="2"/></transform></shape>
        <shape type="cylinder"><point name="p0" x="-2" y="0.3" z="2"/><point name="p1" x="-1" y="1.3" z="2.5"/><float name="radius" value="0.3"/></shape>"#;
    // Sensor, film position; Mitsuba's p, uv, dp_du, dp_dv, duv_dx, duv_dy.
    type Row = (&'static str, [f32; 2], [f32; 3], [f32; 2], [f32; 3], [f32; 3], [f32; 2], [f32; 2]);
    #[rustfmt::skip]
    let expected: [Row; 13] = [
        ("persp", [20.3, 15.2], [0.238671, 0.962401, 1.3723], [0.953858, 0.199371], [0.250217, 0.379931, -0.65806], [-4.55406, 0.749808, -1.29871], [0.0163584, -0.00681694], [-0.052019, -0.00405044]),
        ("persp", [8.6, 14.1], [-1.1235, 1.32475, 2.17717], [0.181812, 0.884372], [-1.40409, 1.0936, 0.620986], [1.0, 1.0, 0.5], [-0.0125175, 0.0151531], [-0.0112354, -0.0281066]),
        ("persp", [27.5, 22.5], [1.28915, 0.0, 1.5783], [0.567159, 0.179329], [9.39693, 0.0, -3.4202], [-2.05212, 0.0, -5.63816], [0.00341875, -0.00119761], [-0.00254561, -0.0109205]),
        ("persp", [19.2, 25.4], [0.250634, 0.0, 2.45856], [0.439464, 0.100665], [9.39693, 0.0, -3.4202], [-2.05212, 0.0, -5.63816], [0.00303991, -0.00106497], [-0.00102739, -0.00892369]),
        ("persp", [5.5, 26.5], [-1.33074, 0.0, 2.92044], [0.275066, 0.118471], [9.39693, 0.0, -3.4202], [-2.05212, 0.0, -5.63816], [0.00292814, -0.00102571], [0.000532584, -0.00872331]),
        ("thin", [20.3, 15.2], [0.238408, 0.962187, 1.37267], [0.953249, 0.199396], [0.250101, 0.37995, -0.658094], [-4.55138, 0.748982, -1.29727], [0.0164425, -0.00683623], [-0.0515496, -0.00407969]),
        ("thin", [8.6, 14.1], [-1.11445, 1.33314, 2.18135], [0.181547, 0.893051], [-1.40417, 1.09507, 0.618209], [1.0, 1.0, 0.5], [-0.0125201, 0.0152538], [-0.0112198, -0.0285461]),
        ("thin", [27.5, 22.5], [1.28894, 0.0, 1.57873], [0.567125, 0.179272], [9.39693, 0.0, -3.4202], [-2.05212, 0.0, -5.63816], [0.00342471, -0.00119981], [-0.00244579, -0.0107676]),
        ("thin", [19.2, 25.4], [0.254976, 0.0, 2.4469], [0.440271, 0.102243], [9.39693, 0.0, -3.4202], [-2.05212, 0.0, -5.63816], [0.00305192, -0.00106909], [-0.000968447, -0.00883474]),
        ("thin", [5.5, 26.5], [-1.32902, 0.0, 2.90608], [0.275719, 0.120621], [9.39693, 0.0, -3.4202], [-2.05212, 0.0, -5.63816], [0.00294154, -0.0010305], [0.000570095, -0.00864745]),
        ("ortho", [20.3, 15.2], [0.241781, 0.961264, 1.37427], [0.952386, 0.198606], [0.253869, 0.379325, -0.657011], [-4.53978, 0.759577, -1.31563], [0.0176859, -0.00729136], [-0.0558471, -0.00446238]),
        ("ortho", [8.6, 14.1], [-1.58559, 0.911238, 0.992368], [0.627891, 0.0393504], [0.557706, -0.537803, 0.0], [-2.16408, -2.24417, -0.387385], [0.0328244, -0.0092826], [0.0363326, 0.00960901]),
        ("ortho", [27.5, 22.5], [1.39099, 0.0, 1.78198], [0.569763, 0.141623], [9.39693, 0.0, -3.4202], [-2.05212, 0.0, -5.63816], [0.00366983, -0.0012856], [-0.00231401, -0.0183492]),
    ];
    let close = |a: &[f32], b: &[f32], what: &str, row: &Row| {
        let scale = b.iter().fold(1e-3f32, |m, x| m.max(x.abs()));
        assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 2e-4 * scale), "{what} of {row:?}: {a:?}");
    };
    for row in &expected {
        let (sensor, film_pos, p, uv, dpdu, dpdv, dx, dy) = *row;
        let xml = &sensors.iter().find(|s| s.0 == sensor).unwrap().1;
        let f = load(&format!(r#"<scene version="3.0.0">{xml}{shapes}</scene>"#)).unwrap();
        let cam = f.scene.camera();
        let (film_pos, u_lens) = (Vec2::from_array(film_pos), Vec2::new(0.3, 0.7));
        let ray = cam.generate_ray(film_pos, u_lens);
        let differentials = cam.ray_differentials(film_pos, u_lens, &ray).scaled(&ray, 0.25);
        let si = f.scene.intersect_complete(&ray).expect("a hit");
        let (duv_dx, duv_dy) = uv_partials(&si, &differentials);
        close(&si.p.to_array(), &p, "p", row);
        close(&si.uv.to_array(), &uv, "uv", row);
        close(&si.dpdu.to_array(), &dpdu, "dp_du", row);
        close(&si.dpdv.to_array(), &dpdv, "dp_dv", row);
        close(&duv_dx.to_array(), &dx, "duv_dx", row);
        close(&duv_dy.to_array(), &dy, "duv_dy", row);
    }
    // The render hands the differentials, scaled by 1/√spp, through a `moment` to its nested
    // `aov`: the pixel of the fourth row above (well inside the rectangle) equals it to within
    // the change across the pixel.
    let f = load(&format!(
        r#"<scene version="3.0.0">{}{shapes}
           <integrator type="moment"><integrator type="aov" name="a"><string name="aovs" value="d:duv_dx"/></integrator></integrator>
           </scene>"#,
        sensors[0].1
    ))
    .unwrap();
    let settings = crate::render::RenderSettings { spp: 16, filter: Filter::BOX, ..Default::default() };
    let never = std::sync::atomic::AtomicBool::new(false);
    let out = crate::render::render_integrator(&f.scene, &f.integrator, &settings, &never).unwrap();
    let channels = out.film.aov_channels();
    let u = &channels.iter().find(|c| c.0 == "a.d.U").expect("the nested aov's channel").1;
    let (pixel, want) = (u[25 * 40 + 19], expected[3].6[0]);
    assert!((pixel / want - 1.0).abs() < 0.05, "duv_dx.U {pixel} vs {want}");
}

/// `moment` and `aov` nest camera-ray integrators, named as Mitsuba names them; a light tracer
/// cannot be nested; bad AOV lists are located errors.
#[test]
fn moment_and_aov_integrators() {
    use crate::integrator::{AnyIntegrator, Integrator};
    let f = load(&scene(
        r#"<integrator type="moment"><integrator type="direct" name="d"/><integrator type="path"/><integrator type="path"/></integrator>"#,
    ))
    .unwrap();
    let AnyIntegrator::Moment(m) = &f.integrator else { panic!("{:?}", f.integrator) };
    let names: Vec<&str> = m.nested.iter().map(|n| n.0.as_str()).collect();
    assert_eq!(names, ["d", "_arg_0", "_arg_1"]);
    assert_eq!(m.aov_names().len(), 18);
    assert_eq!(m.aov_count(), 18);
    assert_eq!(m.aov_names()[9], "m2_d.X");
    let f = load(&scene(
        r#"<integrator type="aov"><string name="aovs" value="dd.y:depth, nn:sh_normal"/><integrator type="path" name="img"/></integrator>"#,
    ))
    .unwrap();
    let AnyIntegrator::Aov(a) = &f.integrator else { panic!() };
    assert_eq!(a.aov_names(), ["img.R", "img.G", "img.B", "img.A", "dd.y.T", "nn.X", "nn.Y", "nn.Z"]);
    assert_eq!(a.aov_count(), 8);
    // Wrappers nest: a moment of an aov records the aov's channels and their second moments.
    let f = load(&scene(
        r#"<integrator type="moment"><integrator type="aov" name="a"><string name="aovs" value="d:depth"/><integrator type="path"/></integrator></integrator>"#,
    ))
    .unwrap();
    let m = f.integrator.camera().unwrap();
    assert_eq!(m.aov_count(), m.aov_names().len());
    assert_eq!(m.aov_names()[..6], ["a._arg_0.R", "a._arg_0.G", "a._arg_0.B", "a._arg_0.A", "a.d.T", "a.X"]);
    let e = err(&scene(r#"<integrator type="moment"><integrator type="ptracer"/></integrator>"#));
    assert!(e.contains("ptracer integrator cannot be nested"), "{e}");
    let e = err(&scene(r#"<integrator type="aov"><string name="aovs" value="x:curvature"/></integrator>"#));
    assert!(e.contains("unknown AOV type 'curvature'") && e.contains("test.xml:"), "{e}");
    let e = err(&scene(r#"<integrator type="aov"><string name="aovs" value="x:boundary_test"/></integrator>"#));
    assert!(e.contains("not implemented"), "{e}");
    let e = err(&scene(r#"<integrator type="moment"/>"#));
    assert!(e.contains("needs a nested <integrator>"), "{e}");
    // Mitsuba's differentiable variants render with the estimator they extend; volpathmis is its own.
    // Their default max_depth is Mitsuba 3.9.1's: 6 for the differentiable ones (its
    // ADIntegrator), -1 for the others; direct_projective is direct illumination whatever it is
    // given (Mitsuba overrides max_depth and rr_depth with 2).
    for (ty, kind, default_depth, depth_4) in [
        ("volpathmis", "volpathmis", -1, 4),
        ("prbvolpath", "volpath", 6, 4),
        ("prb", "path", 6, 4),
        ("prb_basic", "path", 6, 4),
        ("prb_projective", "path", 6, 4),
        ("direct_projective", "path", 2, 2),
    ] {
        let f = load(&scene(&format!(r#"<integrator type="{ty}"><integer name="max_depth" value="4"/></integrator>"#)))
            .unwrap();
        assert_eq!(f.integrator.name(), kind);
        assert_eq!(f.integrator.path_settings().unwrap().max_depth, depth_4, "{ty}");
        let f = load(&scene(&format!(r#"<integrator type="{ty}"/>"#))).unwrap();
        assert_eq!(f.integrator.path_settings().unwrap().max_depth, default_depth, "{ty}");
    }
    let f = load(&scene(
        r#"<integrator type="prb_projective"><integer name="sppc" value="32"/><integer name="sppp" value="8"/>
        <integer name="sppi" value="0"/><string name="guiding" value="grid"/><boolean name="guiding_proj" value="false"/>
        <integer name="guiding_rounds" value="2"/><string name="project_seed" value="bsdf"/></integrator>"#,
    ))
    .unwrap();
    assert_eq!(f.integrator.path_settings().unwrap().rr_depth, 5);
    let f = load(&scene(r#"<integrator type="depth"><boolean name="hide_emitters" value="true"/></integrator>"#)).unwrap();
    assert_eq!(f.integrator.kind(), crate::integrator::IntegratorKind::Depth);
    assert!(f.integrator.camera().is_some() && f.integrator.path_settings().is_none());
    let e = err(&scene(r#"<integrator type="depth"><integer name="max_depth" value="3"/></integrator>"#));
    assert!(e.contains("max_depth"), "{e}");
    let e = err(&scene(r#"<integrator type="direct_projective"><string name="guiding" value="kdtree"/></integrator>"#));
    assert!(e.contains("'guiding' must be one of octree, none, grid"), "{e}");
    let e = err(&scene(r#"<integrator type="prb_projective"><string name="project_seed" value="all"/></integrator>"#));
    assert!(e.contains("'project_seed' must be one of"), "{e}");
}

/// The orthographic sensor, `rawconstant` (a float or a vector, not an rgb, as Mitsuba) and
/// serialized meshes picked by `shape_index` (which the plugin type, not the extension, selects).
#[test]
fn orthographic_rawconstant_and_serialized() {
    use crate::camera::Projection;
    let f = load(
        r#"<scene version="3.0.0"><sensor type="orthographic"><transform name="to_world"><scale value="2"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
        <shape type="sphere"><bsdf type="plastic"><texture name="diffuse_reflectance" type="rawconstant">
        <float name="value" value="0.25"/></texture></bsdf></shape></scene>"#,
    )
    .unwrap();
    assert_eq!(f.scene.camera().projection(), Projection::Orthographic);
    let e = err(&scene(
        r#"<shape type="sphere"><bsdf type="diffuse"><texture name="reflectance" type="rawconstant"><rgb name="value" value="1,0,0"/></texture></bsdf></shape>"#,
    ));
    assert!(e.contains("must be a <float> or a <vector>"), "{e}");
    let dir = std::env::temp_dir().join(format!("neumann-ser-xml-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cube = crate::geometry::TriangleMesh::cube();
    let quad = crate::geometry::TriangleMesh::rectangle();
    let bytes = crate::load::serialized::tests::write_serialized(&[(&quad, false), (&cube, true)]);
    std::fs::write(dir.join("m.data"), bytes).unwrap();
    let text = scene(
        r#"<shape type="serialized"><string name="filename" value="m.data"/><integer name="shape_index" value="1"/></shape>"#,
    );
    let f = load_scene_text(&dir.join("s.xml"), &text, &[]).unwrap();
    assert_eq!(f.scene.primitive_count(), 12, "the cube, mesh 1");
    let text = scene(
        r#"<shape type="serialized"><string name="filename" value="m.data"/><integer name="shape_index" value="5"/></shape>"#,
    );
    let e = load_scene_text(&dir.join("s.xml"), &text, &[]).unwrap_err().to_string();
    assert!(e.contains("shape_index 5 is out of range") && e.contains("s.xml:"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Mitsuba 0.x scenes (version < 2.0.0) are read as Mitsuba 3.9 upgrades them: camelCase
/// parameter names become snake_case, a diffuse BSDF's `diffuseReflectance` its `reflectance`,
/// and `uoffset`/`uscale`… a `to_uv` transform; newer files keep their names. A version must have
/// three numbers.
#[test]
fn version_upgrade_of_old_scenes() {
    let old = r#"<scene version="0.6.0">
        <integrator type="path"><integer name="maxDepth" value="3"/></integrator>
        <sensor type="perspective"><float name="fov" value="40"/><string name="fovAxis" value="y"/>
            <transform name="toWorld"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
            <sampler type="independent"><integer name="sampleCount" value="7"/></sampler>
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
        <shape type="sphere"><bsdf type="diffuse"><texture name="diffuseReflectance" type="checkerboard">
            <float name="uscale" value="4"/><float name="voffset" value="0.5"/></texture></bsdf></shape>
        <shape type="sphere"><float name="radius" value="0.5"/><bsdf type="roughplastic"><float name="intIOR" value="1.6"/></bsdf></shape>
    </scene>"#;
    let f = load(old).unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    assert_eq!(f.spp, 7);
    assert!(matches!(f.integrator, crate::integrator::AnyIntegrator::Path(p) if p.settings.max_depth == 3));
    let Bsdf::Diffuse(d) = &f.scene.bsdfs()[0] else { panic!("{:?}", f.scene.bsdfs()[0]) };
    // to_uv = scale(4, 1) · translate(0, 0.5): (0.1, 0.1) → (0.4, 0.6): color1 (0.2) at (fu < ½, fv > ½).
    assert_eq!(d.reflectance.eval(crate::math::Vec2::new(0.1, 0.1)), Rgb::splat(0.2));
    assert_eq!(d.reflectance.eval(crate::math::Vec2::new(0.1, 0.6)), Rgb::splat(0.4));
    let e = err(&old.replace("0.6.0", "3.0.0"));
    assert!(
        e.contains("maxDepth") || e.contains("fovAxis") || e.contains("toWorld") || e.contains("sampleCount"),
        "{e}"
    );
    assert!(err(&scene("").replace("3.0.0", "3.0")).contains("three period-separated numbers"));
    // lookat without an up vector: Mitsuba's coordinate system of the view direction.
    let f = load(&scene("").replace(r#" up="0, 1, 0""#, "")).unwrap();
    let r = f.scene.camera().generate_ray(crate::math::Vec2::new(16.0, 0.0), crate::math::Vec2::ZERO);
    assert!(r.d.is_finite());
}

/// `mesh_attribute` textures read a PLY's colours at the hit point; a shape without the
/// attribute is a located error, as in Mitsuba.
#[test]
fn mesh_attribute_textures() {
    let dir = std::env::temp_dir().join(format!("neumann-meshattr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("quad.ply"),
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         property float r\nproperty float g\nproperty float b\nelement face 1\nproperty list uchar int vertex_indices\n\
         end_header\n-1 -1 0 0.2 0.2 0.2\n1 -1 0 0.2 0.2 0.2\n1 1 0 0.2 0.2 0.2\n-1 1 0 0.2 0.2 0.2\n4 0 1 2 3\n",
    )
    .unwrap();
    let body = |name: &str| {
        scene(&format!(
            r#"<shape type="ply"><string name="filename" value="quad.ply"/>
            <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="{name}"/></texture></bsdf></shape>"#
        ))
    };
    let f = load_scene_text(&dir.join("s.xml"), &body("vertex_color"), &[]).unwrap();
    let si = f.scene.intersect(&Ray::new(Vec3::new(0.1, 0.2, 5.0), -Vec3::Z)).unwrap();
    let ctx = f.scene.bsdf_context(&si);
    let albedo = f.scene.bsdfs()[0].diffuse_reflectance(&ctx, Vec3::Z);
    assert!((albedo - Rgb::splat(0.2)).abs().max_element() < 1e-6, "{albedo}");
    let e = load_scene_text(&dir.join("s.xml"), &body("face_color"), &[]).unwrap_err().to_string();
    assert!(e.contains("s.xml:") && e.contains("mesh attribute 'face_color'"), "{e}");
    let e = load_scene_text(&dir.join("s.xml"), &body("color"), &[]).unwrap_err().to_string();
    assert!(e.contains("starts with 'vertex_' or 'face_'"), "{e}");
    // Every textured parameter counts, nested BSDFs' too.
    let conductor = scene(
        r#"<shape type="ply"><string name="filename" value="quad.ply"/><bsdf type="twosided"><bsdf type="roughconductor">
        <texture type="mesh_attribute" name="alpha"><string name="name" value="face_color"/></texture></bsdf></bsdf></shape>"#,
    );
    let e = load_scene_text(&dir.join("s.xml"), &conductor, &[]).unwrap_err().to_string();
    assert!(e.contains("mesh attribute 'face_color'"), "{e}");
    let plastic = scene(
        r#"<shape type="ply"><string name="filename" value="quad.ply"/><bsdf type="plastic">
        <texture type="mesh_attribute" name="specular_reflectance"><string name="name" value="vertex_color"/></texture></bsdf></shape>"#,
    );
    let e = load_scene_text(&dir.join("s.xml"), &plastic, &[]).unwrap_err().to_string();
    assert!(e.contains("specular_reflectance cannot be a mesh_attribute"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Mitsuba's texture attributes: a texture nested by name in a shape (any shape: a sphere, a
/// cube mesh) is what the shape's `mesh_attribute` textures of that name read — colour and
/// scalar parameters, nested BSDFs, a referenced texture — so that a scene reading them renders
/// bit for bit as the same scene with the textures in place. Reads of an attribute the shape
/// lacks, and attributes that read themselves, are located errors.
#[test]
fn shape_texture_attributes() {
    let checker = r#"<rgb name="color0" value="0.9, 0.1, 0.1"/><rgb name="color1" value="0.1, 0.2, 0.8"/>
        <transform name="to_uv"><scale x="4" y="3"/></transform>"#;
    let rough = r#"<float name="color0" value="0.05"/><float name="color1" value="0.4"/>"#;
    let read = |param: &str, attr: &str| {
        format!(r#"<texture type="mesh_attribute" name="{param}"><string name="name" value="{attr}"/></texture>"#)
    };
    let lit = r#"<emitter type="constant"><rgb name="radiance" value="0.5, 0.6, 0.7"/></emitter>
        <emitter type="point"><point name="position" x="2" y="3" z="4"/><rgb name="intensity" value="20, 20, 20"/></emitter>
        <texture type="checkerboard" id="tiles"><rgb name="color0" value="0.7, 0.7, 0.2"/><rgb name="color1" value="0.2, 0.5, 0.5"/></texture>"#;
    let attributes = scene(&format!(
        r#"{lit}
        <shape type="sphere"><transform name="to_world"><translate x="-0.9"/></transform>
            <texture type="checkerboard" name="face_albedo">{checker}</texture>
            <texture type="checkerboard" name="vertex_alpha">{rough}</texture>
            <bsdf type="blendbsdf">{}<bsdf type="diffuse">{}</bsdf><bsdf type="roughconductor">{}</bsdf></bsdf></shape>
        <shape type="cube"><transform name="to_world"><scale value="0.6"/><rotate y="1" angle="30"/><translate x="1"/></transform>
            <ref name="face_tiles" id="tiles"/>
            <bsdf type="diffuse">{}</bsdf></shape>"#,
        read("weight", "vertex_alpha"),
        read("reflectance", "face_albedo"),
        read("alpha", "vertex_alpha"),
        read("reflectance", "face_tiles"),
    ));
    let in_place = scene(&format!(
        r#"{lit}
        <shape type="sphere"><transform name="to_world"><translate x="-0.9"/></transform>
            <bsdf type="blendbsdf"><texture type="checkerboard" name="weight">{rough}</texture>
            <bsdf type="diffuse"><texture type="checkerboard" name="reflectance">{checker}</texture></bsdf>
            <bsdf type="roughconductor"><texture type="checkerboard" name="alpha">{rough}</texture></bsdf></bsdf></shape>
        <shape type="cube"><transform name="to_world"><scale value="0.6"/><rotate y="1" angle="30"/><translate x="1"/></transform>
            <bsdf type="diffuse"><ref name="reflectance" id="tiles"/></bsdf></shape>"#
    ));
    let (a, b) = (load(&attributes).unwrap(), load(&in_place).unwrap());
    let (ia, ib) = (crate::load::test_support::render(&a, 4, 3), crate::load::test_support::render(&b, 4, 3));
    assert!(crate::load::test_support::mean(&ib) > 0.05);
    assert!(ia.iter().zip(&ib).all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits)));
    // Without the attribute the read is an error at the shape, naming the way to give it.
    let missing = scene(&format!(
        r#"<shape type="sphere"><bsdf type="diffuse">{}</bsdf></shape>"#,
        read("reflectance", "face_albedo")
    ));
    let e = err(&missing);
    assert!(e.contains("test.xml:7:") && e.contains("'face_albedo'") && e.contains("nested in the shape"), "{e}");
    // An attribute may read another; one that reads itself has no value.
    let chain = |second: &str| {
        scene(&format!(
            r#"<shape type="sphere">
            <texture type="checkerboard" name="face_a">{}</texture>
            <texture type="checkerboard" name="face_b">{second}</texture>
            <bsdf type="diffuse">{}</bsdf></shape>"#,
            read("color0", "face_b"),
            read("reflectance", "face_a"),
        ))
    };
    assert!(load(&chain(checker)).is_ok());
    let e = err(&chain(&read("color1", "face_a")));
    assert!(e.contains("test.xml:8:") && e.contains("reads itself"), "{e}");
    let e = err(&chain(&read("color1", "face_c")));
    assert!(e.contains("test.xml:9:") && e.contains("'face_b' reads the attribute 'face_c'"), "{e}");
    // A bounded number per shape (each may read another: lookups recurse along the chain).
    let many = |n: usize| {
        let attrs: String =
            (0..n).map(|k| format!(r#"<texture type="checkerboard" name="face_{k}">{checker}</texture>"#)).collect();
        let bsdf = read("reflectance", "face_0");
        scene(&format!(r#"<shape type="sphere">{attrs}<bsdf type="diffuse">{bsdf}</bsdf></shape>"#))
    };
    let limit = crate::load::limits::MAX_TEXTURE_ATTRIBUTES;
    assert!(load(&many(limit)).is_ok());
    let e = err(&many(limit + 1));
    // Located at the attribute one past the limit.
    assert!(e.contains("test.xml:") && e.contains("at most 16 texture attributes") && e.contains("face_16"), "{e}");
}

/// `-D` parameters the scene never substitutes come back as warnings (Mitsuba reports unused
/// parameters too); used ones, and undeclared ones that are used, do not.
#[test]
fn unused_command_line_parameters_are_reported() {
    let text =
        scene(r#"<default name="r" value="0.5"/><shape type="sphere"><float name="radius" value="$r"/></shape>"#);
    let defines = [("r".to_string(), "2".to_string()), ("spp".to_string(), "8".to_string())];
    let f = load_scene_text(Path::new("test.xml"), &text, &defines).unwrap();
    assert_eq!(f.warnings.len(), 1, "{:?}", f.warnings);
    assert!(f.warnings[0].contains("-D spp"), "{:?}", f.warnings);
}

/// Every parameter Mitsuba lets be a texture loads as one: the dielectrics' reflectance and
/// transmittance, the rough dielectric's roughness, the conductors' `eta` and `k`; `eta`, `k` and
/// roughness are unbounded (an <rgb> above 1 is accepted there, as in Mitsuba).
#[test]
fn dielectric_and_conductor_parameters_take_textures() {
    let checker = |name: &str| format!(r#"<texture type="checkerboard" name="{name}"/>"#);
    for (ty, params) in [
        ("dielectric", vec!["specular_reflectance", "specular_transmittance"]),
        ("thindielectric", vec!["specular_reflectance", "specular_transmittance"]),
        ("roughdielectric", vec!["specular_reflectance", "specular_transmittance", "alpha"]),
        ("roughdielectric", vec!["alpha_u", "alpha_v"]),
        ("conductor", vec!["eta", "k", "specular_reflectance"]),
        ("roughconductor", vec!["eta", "k", "alpha"]),
    ] {
        let inner: String = params.iter().map(|p| checker(p)).collect();
        let f = load(&scene(&format!(r#"<shape type="sphere"><bsdf type="{ty}">{inner}</bsdf></shape>"#)))
            .unwrap_or_else(|e| panic!("{ty} {params:?}: {e}"));
        let textured = f.scene.bsdfs()[0]
            .textures()
            .iter()
            .filter(|t| matches!(t, crate::texture::Texture::Checkerboard { .. }))
            .count();
        let expected = if params.contains(&"alpha") { params.len() + 1 } else { params.len() };
        assert_eq!(textured, expected, "{ty} {params:?}");
    }
    let unbounded = r#"<shape type="sphere"><bsdf type="roughconductor"><rgb name="eta" value="0.2, 0.4, 1.2"/>
        <rgb name="k" value="3, 2.5, 2"/><texture type="bitmap" name="alpha"><string name="filename" value="nope.png"/></texture></bsdf></shape>"#;
    let e = err(&scene(unbounded));
    assert!(e.contains("nope.png"), "eta and k above 1 pass, the missing image is the error: {e}");
}

/// `<spectrum type="…">` plugins as Mitsuba's RGB variants read them (values measured with
/// Mitsuba 3.9.1 scalar_rgb): `uniform` and `d65` are greys (unlike `<spectrum value="v">` for an
/// emitter, which is illuminant E), `srgb` its colour; `regular`/`irregular` reduce as the inline
/// sampled form does; `blackbody` and unknown types are located errors.
#[test]
fn spectrum_plugins() {
    let reflectance = |spectrum: &str| {
        let f = load(&scene(&format!(r#"<shape type="sphere"><bsdf type="diffuse">{spectrum}</bsdf></shape>"#)))
            .unwrap_or_else(|e| panic!("{spectrum}: {e}"));
        f.scene.bsdfs()[0].diffuse_reflectance(&crate::material::BsdfContext::default(), Vec3::Z)
    };
    let uniform =
        reflectance(r#"<spectrum type="uniform" name="reflectance"><float name="value" value="0.3"/></spectrum>"#);
    assert_eq!(uniform, Rgb::splat(0.3));
    let d65 = reflectance(r#"<spectrum type="d65" name="reflectance"><float name="scale" value="0.5"/></spectrum>"#);
    assert_eq!(d65, Rgb::splat(0.5));
    let srgb =
        reflectance(r#"<spectrum type="srgb" name="reflectance"><rgb name="color" value="0.1, 0.5, 0.9"/></spectrum>"#);
    assert_eq!(srgb, Rgb::new(0.1, 0.5, 0.9));
    let regular = reflectance(
        r#"<spectrum type="regular" name="reflectance"><float name="wavelength_min" value="400"/>
        <float name="wavelength_max" value="700"/><string name="values" value="0.1, 0.5, 0.9"/></spectrum>"#,
    );
    let inline = reflectance(r#"<spectrum name="reflectance" value="400:0.1, 550:0.5, 700:0.9"/>"#);
    assert_eq!(regular, inline);
    let irregular = reflectance(
        r#"<spectrum type="irregular" name="reflectance"><string name="wavelengths" value="400, 550, 700"/>
        <string name="values" value="0.1, 0.5, 0.9"/></spectrum>"#,
    );
    assert_eq!(irregular, inline);
    assert!(inline.x > inline.z + 0.3, "a reddish spectrum: {inline}");
    let texture =
        reflectance(r#"<texture type="srgb" name="reflectance"><rgb name="color" value="0.2, 0.4, 0.6"/></texture>"#);
    assert_eq!(texture, Rgb::new(0.2, 0.4, 0.6));
    for (body, expectation) in [
        (
            r#"<spectrum type="blackbody" name="reflectance"><float name="temperature" value="3000"/></spectrum>"#,
            "spectral rendering",
        ),
        (r#"<spectrum type="unifrom" name="reflectance"/>"#, "the nearest is 'uniform'"),
        (
            r#"<spectrum type="uniform" name="reflectance"><float name="scale" value="2"/></spectrum>"#,
            "no parameter 'scale'",
        ),
        (
            r#"<spectrum type="srgb" name="reflectance"><rgb name="color" value="2, 1, 1"/></spectrum>"#,
            "unless 'unbounded'",
        ),
        (
            r#"<texture type="srgb" name="reflectance"><rgb name="color" value="2, 1, 1"/></texture>"#,
            "unless 'unbounded'",
        ),
        (
            r#"<spectrum type="irregular" name="reflectance"><string name="wavelengths" value="400, 500"/><string name="values" value="1"/></spectrum>"#,
            "2 wavelengths but 1 values",
        ),
    ] {
        let e = err(&scene(&format!(r#"<shape type="sphere"><bsdf type="diffuse">{body}</bsdf></shape>"#)));
        assert!(e.starts_with("test.xml:7:") && e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
}

/// Mitsuba's `sdfgrid` from a `.vol` file: loads and is hit; its errors are located (a missing
/// or malformed file, a grid without surface, an area emitter on it, `flip_normals`, an unknown
/// `normals` mode).
#[test]
fn sdfgrid_shapes() {
    use crate::image::GridVolume;
    let dir = std::env::temp_dir().join(format!("neumann-sdfgrid-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let n = 8;
    let mut data = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = Vec3::new(x as f32, y as f32, z as f32) / (n - 1) as f32;
                data.push((p - Vec3::splat(0.5)).length() - 0.3);
            }
        }
    }
    let grid = GridVolume { res: [n; 3], channels: 1, bbox: [[0.0; 3], [1.0; 3]], data };
    std::fs::write(dir.join("ball.vol"), crate::load::volume::grid_volume_bytes(&grid)).unwrap();
    let empty = GridVolume { data: vec![1.0; n * n * n], ..grid.clone() };
    std::fs::write(dir.join("empty.vol"), crate::load::volume::grid_volume_bytes(&empty)).unwrap();
    std::fs::write(dir.join("bad.vol"), b"VOL\x03 not a grid").unwrap();
    let shape = |file: &str, extra: &str| {
        scene(&format!(
            r#"<shape type="sdfgrid"><string name="filename" value="{file}"/>{extra}
            <transform name="to_world"><translate x="-0.5" y="-0.5" z="-0.5"/></transform></shape>"#
        ))
    };
    let f = load_scene_text(&dir.join("s.xml"), &shape("ball.vol", ""), &[]).unwrap();
    let si = f.scene.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)).expect("the ball is hit");
    assert!((si.p.z - 0.3).abs() < 0.03 && si.ns.z > 0.99, "{} {}", si.p, si.ns);
    let f =
        load_scene_text(&dir.join("s.xml"), &shape("ball.vol", r#"<string name="normals" value="analytic"/>"#), &[]);
    assert!(f.is_ok());
    for (file, extra, expectation) in [
        ("nowhere.vol", "", "nowhere.vol"),
        ("bad.vol", "", "header"),
        ("empty.vol", "", "holds no surface"),
        ("ball.vol", r#"<emitter type="area"/>"#, "cannot be an area emitter"),
        ("ball.vol", r#"<boolean name="flip_normals" value="true"/>"#, "no flip_normals"),
        ("ball.vol", r#"<string name="normals" value="falcao"/>"#, "normals"),
    ] {
        let e = load_scene_text(&dir.join("s.xml"), &shape(file, extra), &[]).unwrap_err().to_string();
        assert!(e.contains("s.xml:7:") && e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Mitsuba's `linearcurve` and `bsplinecurve` from curve files: they load, are hit where the
/// tube is (the linear one's radius untouched by `to_world`); their errors are located (a
/// missing file, a bad line with its line and column, an area emitter, flip_normals, too few
/// points for a B-spline).
#[test]
fn linearcurve_shapes() {
    let dir = std::env::temp_dir().join(format!("neumann-linearcurve-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("c.txt"), "-1 0 0 0.25\n1 0 0 0.25\n").unwrap();
    std::fs::write(dir.join("bad.txt"), "-1 0 0 0.25\n1 0 zero 0.25\n").unwrap();
    let shape = |file: &str, extra: &str| {
        scene(&format!(
            r#"<shape type="linearcurve"><string name="filename" value="{file}"/>{extra}
            <transform name="to_world"><scale value="2"/></transform></shape>"#
        ))
    };
    let f = load_scene_text(&dir.join("s.xml"), &shape("c.txt", ""), &[]).unwrap();
    let si = f.scene.intersect(&Ray::new(Vec3::new(1.5, 0.0, 5.0), -Vec3::Z)).expect("the tube is hit");
    assert!((si.p.z - 0.25).abs() < 1e-4 && si.ns.z > 0.999, "{} {}", si.p, si.ns);
    assert!(f.scene.intersect(&Ray::new(Vec3::new(2.3, 0.0, 5.0), -Vec3::Z)).is_none(), "past the round end cap");
    for (file, extra, expectation) in [
        ("nowhere.txt", "", "nowhere.txt"),
        ("bad.txt", "", "bad.txt:2: column 5: expected a finite number (z;"),
        ("c.txt", r#"<emitter type="area"/>"#, "cannot be an area emitter"),
        ("c.txt", r#"<emitter type="directionalarea"/>"#, "cannot be a directionalarea emitter"),
        ("c.txt", r#"<boolean name="flip_normals" value="true"/>"#, "no flip_normals"),
    ] {
        let e = load_scene_text(&dir.join("s.xml"), &shape(file, extra), &[]).unwrap_err().to_string();
        assert!(e.contains("s.xml:7:") && e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
    // bsplinecurve: the same file format, four points at least; a straight B-spline's tube.
    std::fs::write(dir.join("b.txt"), "-3 0 0 0.25\n-1 0 0 0.25\n1 0 0 0.25\n3 0 0 0.25\n").unwrap();
    let spline = |file: &str| scene(&format!(r#"<shape type="bsplinecurve"><string name="filename" value="{file}"/></shape>"#));
    let f = load_scene_text(&dir.join("s.xml"), &spline("b.txt"), &[]).unwrap();
    let si = f.scene.intersect(&Ray::new(Vec3::new(0.5, 0.0, 5.0), -Vec3::Z)).expect("the tube is hit");
    assert!((si.p.z - 0.25).abs() < 1e-4 && si.ns.z > 0.999, "{} {}", si.p, si.ns);
    assert!(f.scene.intersect(&Ray::new(Vec3::new(1.1, 0.0, 5.0), -Vec3::Z)).is_none(), "past the open end");
    let e = load_scene_text(&dir.join("s.xml"), &spline("c.txt"), &[]).unwrap_err().to_string();
    assert!(e.contains("s.xml:7:") && e.contains("at least 4"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Every projective camera reads `focus_distance` as Mitsuba's do (default `far_clip`): the
/// perspective and orthographic cameras accept it (it cannot change their image), the thin lens
/// needs only `aperture_radius`; a non-positive distance is a located error.
#[test]
fn cameras_read_focus_distance() {
    let sensor = |ty: &str, params: &str| {
        format!(
            r#"<scene version="3.0.0"><sensor type="{ty}">{params}
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor></scene>"#
        )
    };
    for (ty, params) in [
        ("perspective", r#"<float name="focus_distance" value="6"/>"#),
        ("orthographic", r#"<float name="focus_distance" value="6"/>"#),
        ("thinlens", r#"<float name="aperture_radius" value="0.1"/>"#),
    ] {
        load(&sensor(ty, params)).unwrap_or_else(|e| panic!("{ty}: {e}"));
    }
    let e = load(&sensor("perspective", r#"<float name="focus_distance" value="0"/>"#)).unwrap_err().to_string();
    assert!(e.contains("test.xml:1:") && e.contains("focus_distance"), "{e}");
    let e = load(&sensor("thinlens", "")).unwrap_err().to_string();
    assert!(e.contains("'aperture_radius' is required"), "{e}");
}

/// `bumpmap` takes one nested bitmap (Mitsuba differentiates bitmaps only) and one BSDF;
/// `normalmap` needs its `normalmap` texture.
#[test]
fn bump_and_normal_map_parameters() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let shape = |bsdf: &str| scene(&format!(r#"<shape type="rectangle">{bsdf}</shape>"#));
    let bump = r#"<bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="assets/tiles.png"/></texture>
        <float name="scale" value="0.2"/><boolean name="use_shadowing_function" value="false"/><bsdf type="diffuse"/></bsdf>"#;
    let f = load_scene_text(&dir.join("test.xml"), &shape(bump), &[]).unwrap();
    assert!(matches!(&f.scene.bsdfs()[0], Bsdf::Perturbed(p) if !p.shadowing && p.flip_invalid_normals));
    for (bsdf, expectation) in [
        (r#"<bsdf type="bumpmap"><texture type="checkerboard"/><bsdf type="diffuse"/></bsdf>"#, "must be a bitmap"),
        (r#"<bsdf type="bumpmap"><bsdf type="diffuse"/></bsdf>"#, "exactly one nested <texture>"),
        (r#"<bsdf type="normalmap"><bsdf type="diffuse"/></bsdf>"#, "needs its 'normalmap' texture"),
        (r#"<bsdf type="normalmap"><rgb name="normalmap" value="0.5, 0.5, 1"/></bsdf>"#, "expects 1 nested <bsdf>"),
    ] {
        let e = load_scene_text(&dir.join("test.xml"), &shape(bsdf), &[]).unwrap_err().to_string();
        assert!(e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
}

/// A bitmap's storage `format`: `fp16` rounds every texel to half precision after decoding (as
/// Mitsuba stores it); `auto` and `variant` keep single precision, as Mitsuba's RGB CPU variants.
#[test]
fn bitmap_storage_format() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let pixels = |format: &str| {
        let bsdf = format!(
            r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
            <string name="filename" value="assets/tiles.png"/><string name="format" value="{format}"/></texture></bsdf></shape>"#
        );
        let f = load_scene_text(&dir.join("test.xml"), &scene(&bsdf), &[]).unwrap();
        match &f.scene.bsdfs()[0] {
            Bsdf::Diffuse(d) => match &d.reflectance {
                crate::texture::Texture::Bitmap { bitmap, .. } => bitmap.image.pixels.clone(),
                t => panic!("{t:?}"),
            },
            b => panic!("{b:?}"),
        }
    };
    let (single, half) = (pixels("variant"), pixels("fp16"));
    assert_eq!(pixels("auto"), single);
    assert!(single.iter().zip(&half).all(|(s, h)| s.map(crate::math::round_to_half) == *h));
    assert!(single.iter().zip(&half).any(|(s, h)| s != h), "sRGB-decoded texels are not all halves");
}

/// `principled` and `principledthin` take every parameter as a texture; a lobe left out (or
/// given as the float 0) is off, as Mitsuba's get_flag decides; `eta` and `specular` exclude
/// each other.
#[test]
fn principled_parameters() {
    let shape = |bsdf: &str| scene(&format!(r#"<shape type="sphere">{bsdf}</shape>"#));
    let f = load(&shape(
        r#"<bsdf type="principled"><texture type="checkerboard" name="roughness"/><float name="metallic" value="0"/>
        <float name="clearcoat" value="0.5"/><rgb name="base_color" value="0.2, 0.4, 0.6"/><float name="eta" value="1.33"/></bsdf>"#,
    ))
    .unwrap();
    let Bsdf::Principled(p) = &f.scene.bsdfs()[0] else { panic!("not principled") };
    assert!(p.metallic.is_none() && p.clearcoat.is_some() && (p.eta - 1.33).abs() < 1e-6);
    assert!(matches!(p.roughness, crate::texture::Texture::Checkerboard { .. }));
    let f = load(&shape(r#"<bsdf type="principled"><float name="specular" value="0.5"/></bsdf>"#)).unwrap();
    let Bsdf::Principled(p) = &f.scene.bsdfs()[0] else { panic!("not principled") };
    assert!((p.eta - (2.0 / (1.0 - 0.04f32.sqrt()) - 1.0)).abs() < 1e-5, "{}", p.eta);
    let e = err(&shape(
        r#"<bsdf type="principled"><float name="eta" value="1.5"/><float name="specular" value="0.5"/></bsdf>"#,
    ));
    assert!(e.contains("either 'eta' or 'specular'"), "{e}");
    let f = load(&shape(
        r#"<bsdf type="principledthin"><float name="diff_trans" value="1.2"/><texture type="checkerboard" name="eta"/></bsdf>"#,
    ))
    .unwrap();
    assert!(matches!(&f.scene.bsdfs()[0], Bsdf::PrincipledThin(t) if t.diff_trans.is_some() && t.spec_trans.is_none()));
    let e = err(&shape(r#"<bsdf type="principledthin"><float name="clearcoat" value="0.5"/></bsdf>"#));
    assert!(e.contains("clearcoat"), "{e}");
}

/// neumann's `nanovdb` and `blackbody` volumes in Mitsuba XML: the grid named `grid` of the file
/// (relative to the scene), `value` × its density in the space of `to_world`, the medium's box
/// the grid's world box carried there; black-body `radiance` from a temperature grid; errors
/// are located: a missing grid (unless not `required`), a missing file or temperature, bad
/// values.
#[test]
fn nanovdb_volumes() {
    use crate::medium::Coefficients;
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/nanovdb");
    let medium = |body: &str| {
        scene(&format!(
            r#"<medium type="heterogeneous" id="smoke">{body}</medium>
            <shape type="sphere"><float name="radius" value="3"/><bsdf type="null"/><ref name="interior" id="smoke"/></shape>"#
        ))
    };
    let text = medium(
        r#"<volume type="nanovdb" name="sigma_t"><string name="filename" value="blob.nvdb"/>
             <rgb name="value" value="1, 0.5, 0.25"/><transform name="to_world"><translate x="2"/></transform></volume>
           <float name="scale" value="4"/><rgb name="albedo" value="0.5"/>
           <volume type="blackbody" name="radiance">
             <volume type="nanovdb" name="temperature"><string name="filename" value="blob.nvdb"/>
               <string name="grid" value="temperature"/><transform name="to_world"><translate x="2"/></transform></volume>
             <float name="temperature_offset" value="1"/><float name="temperature_scale" value="150"/></volume>"#,
    );
    let f = load_scene_text(&dir.join("s.xml"), &text, &[]).unwrap_or_else(|e| panic!("{e}"));
    let m = &f.scene.media()[0];
    let Coefficients::Heterogeneous(h) = &m.coefficients else { panic!() };
    let g = crate::load::nanovdb::load_nanovdb(&dir.join("blob.nvdb"), "density").unwrap().unwrap();
    let [lo, hi] = g.world_bbox();
    let b = h.sigma_t.bounds();
    assert!((b.min - Vec3::new(lo[0] as f32 + 2.0, lo[1] as f32, lo[2] as f32)).abs().max_element() < 1e-6, "{b:?}");
    assert!((b.max - Vec3::new(hi[0] as f32 + 2.0, hi[1] as f32, hi[2] as f32)).abs().max_element() < 1e-6, "{b:?}");
    let p = [0.1f32, 0.2, 0.05];
    let d = g.sample(g.world_to_index(p));
    assert!(d > 0.1, "{d}");
    let got = h.sigma_t.eval(Vec3::new(p[0] + 2.0, p[1], p[2]));
    assert!((got - Rgb::new(1.0, 0.5, 0.25) * d).abs().max_element() < 1e-6, "{got} vs {d}");
    assert!((h.majorant() - 4.0 * g.range().1).abs() < 1e-5, "{}", h.majorant());
    let le = m.radiance.as_ref().expect("radiance").eval(Vec3::new(2.0, 0.0, 0.2));
    assert!(le.x > le.y && le.y >= le.z && le.x > 0.0, "a red glow: {le}");
    // A grid the file lacks: no radiance where not required.
    let text = medium(
        r#"<float name="sigma_t" value="1"/><volume type="blackbody" name="radiance"><volume type="nanovdb" name="temperature">
             <string name="filename" value="voxels.nvdb"/><string name="grid" value="temperature"/><boolean name="required" value="false"/></volume></volume>"#,
    );
    let f = load_scene_text(&dir.join("s.xml"), &text, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert!(f.scene.media()[0].radiance.is_none());
    for (body, expectation) in [
        (r#"<volume type="nanovdb" name="sigma_t"><string name="filename" value="blob.nvdb"/><string name="grid" value="smoke"/></volume>"#, "no grid named \"smoke\""),
        (r#"<float name="sigma_t" value="1"/><volume type="blackbody" name="radiance"><volume type="nanovdb" name="temperature"><string name="filename" value="voxels.nvdb"/><string name="grid" value="temperature"/></volume></volume>"#, "no grid named \"temperature\""),
        (r#"<float name="sigma_t" value="1"/><volume type="blackbody" name="radiance"/>"#, "needs its 'temperature'"),
        (r#"<float name="sigma_t" value="1"/><volume type="blackbody" name="radiance"><rgb name="temperature" value="0.1, 0.2, 0.3"/></volume>"#, "grey"),
        (r#"<volume type="nanovdb" name="sigma_t"><string name="filename" value="missing.nvdb"/></volume>"#, "missing.nvdb"),
        (r#"<volume type="nanovdb" name="sigma_t"><string name="filename" value="blob_ref.txt"/></volume>"#, "not a NanoVDB file"),
        (r#"<volume type="nanovdb" name="sigma_t"><string name="filename" value="blob.nvdb"/><rgb name="value" value="-1"/></volume>"#, "non-negative"),
        (r#"<float name="sigma_t" value="1"/><volume type="blackbody" name="radiance"><float name="temperature" value="3000"/><float name="scale" value="-1"/></volume>"#, "scale must be ≥ 0"),
        (r#"<float name="sigma_t" value="1"/><volume type="blackbody" name="radiance"><float name="temperature" value="3000"/><float name="weight" value="-1"/></volume>"#, "non-negative"),
    ] {
        let e = load_scene_text(&dir.join("s.xml"), &medium(body), &[]).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("s.xml:") && e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
}

/// Mitsuba's `heterogeneous` medium: `gridvolume` and `constvolume` volumes (and plain
/// constants, which are constant volumes over the unit cube), `scale`, `sample_emitters`; the
/// medium's extent is the `sigma_t` volume's box; the majorant is `scale` × the grid's largest
/// value. Errors are located: negative extinction, albedo above 1, a 6-channel grid, an
/// unknown volume plugin or filter, a missing file.
#[test]
fn heterogeneous_media() {
    use crate::image::GridVolume;
    use crate::medium::Coefficients;
    let dir = std::env::temp_dir().join(format!("neumann-hetero-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let grid = |channels: usize, values: &[f32]| GridVolume {
        res: [2, 2, 2],
        channels,
        bbox: [[0.0; 3], [1.0; 3]],
        data: values.iter().copied().cycle().take(8 * channels).collect(),
    };
    let write = |name: &str, g: &GridVolume| std::fs::write(dir.join(name), crate::load::volume::grid_volume_bytes(g)).unwrap();
    write("density.vol", &grid(1, &[0.0, 0.5, 1.0, 2.0]));
    write("colour.vol", &grid(3, &[0.2, 0.5, 0.9]));
    write("negative.vol", &grid(1, &[0.5, -1.0]));
    write("six.vol", &grid(6, &[0.5]));
    let medium = |body: &str| {
        scene(&format!(
            r#"<medium type="heterogeneous" id="smoke">{body}</medium>
            <shape type="cube"><bsdf type="null"/><ref name="interior" id="smoke"/></shape>"#
        ))
    };
    let text = medium(
        r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="density.vol"/>
             <transform name="to_world"><scale value="2"/><translate x="-1" y="-1" z="-1"/></transform></volume>
           <volume type="gridvolume" name="albedo"><string name="filename" value="colour.vol"/>
             <string name="filter_type" value="nearest"/><string name="wrap_mode" value="repeat"/></volume>
           <float name="scale" value="3"/><boolean name="sample_emitters" value="false"/>
           <phase type="hg"><float name="g" value="0.4"/></phase>"#,
    );
    let f = load_scene_text(&dir.join("s.xml"), &text, &[]).unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let m = &f.scene.media()[0];
    assert!(!m.sample_emitters && m.is_heterogeneous());
    let Coefficients::Heterogeneous(h) = &m.coefficients else { panic!() };
    assert_eq!(h.majorant(), 6.0);
    assert_eq!(h.sigma_t.bounds(), crate::math::Bounds3::new(-Vec3::ONE, Vec3::ONE));
    assert_eq!(h.albedo.eval(Vec3::new(0.1, 0.1, 0.1)), Rgb::new(0.2, 0.5, 0.9));
    // A float is a constant volume over the unit cube (Mitsuba's props.volume).
    let f = load_scene_text(&dir.join("s.xml"), &medium(r#"<float name="sigma_t" value="2"/><rgb name="albedo" value="0.5, 0.6, 0.7"/>"#), &[]).unwrap();
    let Coefficients::Heterogeneous(h) = &f.scene.media()[0].coefficients else { panic!() };
    assert_eq!((h.majorant(), h.sigma_t.bounds()), (2.0, crate::math::Bounds3::new(Vec3::ZERO, Vec3::ONE)));
    assert_eq!(h.albedo.eval(Vec3::splat(0.5)), Rgb::new(0.5, 0.6, 0.7));
    for (body, expectation) in [
        (r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="negative.vol"/></volume>"#, "'sigma_t' must be ≥ 0"),
        (r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="six.vol"/></volume>"#, "6-channel"),
        (r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="missing.vol"/></volume>"#, "missing.vol"),
        (r#"<volume type="gridvolume" name="albedo"><string name="filename" value="density.vol"/></volume>"#, "'albedo' must be in [0, 1]"),
        (r#"<volume type="gridvolume" name="sigma_t"><string name="filename" value="density.vol"/><string name="filter_type" value="cubic"/></volume>"#, "nearest"),
        (r#"<volume type="voxelvolume" name="sigma_t"/>"#, "gridvolume"),
        (r#"<volume type="constvolume" name="sigma_t"><float name="value" value="-1"/></volume>"#, "non-negative"),
        (r#"<texture type="bitmap" name="sigma_t"/>"#, "<volume>"),
    ] {
        let e = load_scene_text(&dir.join("s.xml"), &medium(body), &[]).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("s.xml:") && e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Mitsuba's `sggx` phase function: its `S` is a six-channel `gridvolume`; the heterogeneous
/// medium it sits in becomes a microflake medium (extinction × the flakes' projected area, the
/// majorant × their largest). What neumann or Mitsuba refuse is a located error: `S` missing,
/// of another channel count, a `constvolume`; an sggx phase in a homogeneous medium or a blend.
#[test]
fn sggx_phase_functions() {
    use crate::image::GridVolume;
    use crate::medium::{Coefficients, PhaseFunction};
    let dir = std::env::temp_dir().join(format!("neumann-sggx-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let grid = |channels: usize, values: &[f32]| GridVolume {
        res: [2, 1, 1],
        channels,
        bbox: [[0.0; 3], [1.0; 3]],
        data: values.iter().copied().cycle().take(2 * channels).collect(),
    };
    let write = |name: &str, g: &GridVolume| std::fs::write(dir.join(name), crate::load::volume::grid_volume_bytes(g)).unwrap();
    write("flakes.vol", &grid(6, &[1.0, 0.2, 0.05, 0.0, 0.0, 0.0, 4.0, 1.0, 1.0, 0.0, 0.0, 0.0]));
    write("grey.vol", &grid(1, &[0.5]));
    let s_grid =
        |file: &str| format!(r#"<volume type="gridvolume" name="S"><string name="filename" value="{file}"/></volume>"#);
    let medium = |ty: &str, phase: &str| {
        scene(&format!(
            r#"<medium type="{ty}" id="fibres"><float name="sigma_t" value="3"/>{phase}</medium>
            <shape type="cube"><bsdf type="null"/><ref name="interior" id="fibres"/></shape>"#
        ))
    };
    let f = load_scene_text(
        &dir.join("s.xml"),
        &medium("heterogeneous", &format!(r#"<phase type="sggx">{}</phase>"#, s_grid("flakes.vol"))),
        &[],
    )
    .unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let m = &f.scene.media()[0];
    let PhaseFunction::Sggx(flakes) = &m.phase else { panic!("{:?}", m.phase) };
    let Coefficients::Heterogeneous(h) = &m.coefficients else { panic!() };
    // The second texel's largest eigenvalue is 4: σ ≤ 2, so the majorant is 3 × 2.
    assert_eq!((flakes.max_projected_area(), h.majorant()), (2.0, 6.0));
    let p = Vec3::new(0.25, 0.5, 0.5); // the first texel's centre
    assert!((h.sigma_t_at(p, Vec3::Y).x - 3.0 * 0.2f32.sqrt()).abs() < 1e-5);
    assert!((h.sigma_t_at(p, -Vec3::X).x - 3.0).abs() < 1e-5);
    for (ty, phase, expectation) in [
        ("heterogeneous", r#"<phase type="sggx"/>"#.to_string(), "needs its 'S'"),
        ("heterogeneous", format!(r#"<phase type="sggx">{}</phase>"#, s_grid("grey.vol")), "grids of 6 channels, this one has 1"),
        (
            "heterogeneous",
            r#"<phase type="sggx"><volume type="constvolume" name="S"><float name="value" value="1"/></volume></phase>"#.to_string(),
            "gridvolume of six channels",
        ),
        ("homogeneous", format!(r#"<phase type="sggx">{}</phase>"#, s_grid("flakes.vol")), "needs a heterogeneous medium"),
        (
            "heterogeneous",
            format!(r#"<phase type="blendphase"><float name="weight" value="0.5"/><phase type="isotropic"/><phase type="sggx">{}</phase></phase>"#, s_grid("flakes.vol")),
            "cannot be blended",
        ),
    ] {
        let e = load_scene_text(&dir.join("s.xml"), &medium(ty, &phase), &[]).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains("s.xml:") && e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
    std::fs::remove_dir_all(&dir).ok();
    let f = load_scene_file(&shared("sggx.xml"), &[]).expect("sggx.xml loads");
    assert!(f.warnings.is_empty() && matches!(f.scene.media()[0].phase, PhaseFunction::Sggx(_)), "{:?}", f.warnings);
}

/// Hostile numbers are located errors, not NaN geometry, crashes or black images (issue 24's
/// probe): overflowing transforms (a huge rotation angle, scales that multiply past f32), mesh
/// coordinates that overflow, an emitter whose power overflows, PLY face indices that are not
/// non-negative integers, and a PLY element of a huge count without properties (once a hang).
#[test]
fn hostile_numbers_are_located_errors() {
    for (body, expectation) in [
        (
            r#"<shape type="sphere"><transform name="to_world"><rotate x="1" angle="1e300"/></transform></shape>"#,
            "not finite after this operation",
        ),
        (
            r#"<shape type="sphere"><transform name="to_world"><scale value="1e30"/><scale value="1e30"/></transform></shape>"#,
            "not finite after this operation",
        ),
        (
            r#"<shape type="rectangle"><transform name="to_world"><scale value="2e38"/></transform></shape>"#,
            "coordinates are not finite",
        ),
        (
            r#"<shape type="rectangle"><transform name="to_world"><scale value="1e18"/></transform>
               <emitter type="area"><rgb name="radiance" value="1e30"/></emitter></shape>"#,
            "power overflows",
        ),
    ] {
        let e = err(&scene(body));
        assert!(e.contains("test.xml:") && e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
    let dir = std::env::temp_dir().join(format!("neumann-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("huge.obj"), "v 0 0 0\nv 1 0 0\nv 3.4e39 1 0\nf 1 2 3\n").unwrap();
    let ply = |face: &str, extra: &str| {
        format!(
            "ply\nformat ascii 1.0\n{extra}element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n{face}\n"
        )
    };
    std::fs::write(dir.join("negative.ply"), ply("3 0 1 -1", "")).unwrap();
    std::fs::write(
        dir.join("fraction.ply"),
        ply("3 0 1 1.7", "").replace("property list uchar int vertex_indices", "property list uchar float vertex_indices"),
    )
    .unwrap();
    std::fs::write(dir.join("empty_element.ply"), ply("3 0 1 2", "element junk 4000000000\n")).unwrap();
    for (file, expectation) in [
        ("huge.obj", "huge.obj:3"),
        ("negative.ply", "vertex index -1"),
        ("fraction.ply", "vertex index 1.7"),
    ] {
        let text = scene(&format!(r#"<shape type="{}"><string name="filename" value="{file}"/></shape>"#, &file[file.len() - 3..]));
        let e = load_scene_text(&dir.join("s.xml"), &text, &[]).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
    let text = scene(r#"<shape type="ply"><string name="filename" value="empty_element.ply"/></shape>"#);
    let start = std::time::Instant::now();
    load_scene_text(&dir.join("s.xml"), &text, &[]).unwrap();
    assert!(start.elapsed().as_secs_f32() < 5.0, "an element without properties is skipped, whatever its count");
    std::fs::remove_dir_all(&dir).ok();
}

/// Tiny files that once took gigabytes, hung or crashed (issue 24's probe) load quickly or are
/// located errors: 30 nested single-child `twosided`, a 40-level chain of `blendbsdf`s naming
/// the previous one twice (shared, not copied), an include fan-out (16 files of 10 includes
/// each), `/dev/zero` as an include and as a spectrum file, 100 000 nested elements, an include
/// of a file that is not XML (not quoted back), and a binary scene file (its position given).
#[test]
fn resource_bombs_are_bounded() {
    let dir = std::env::temp_dir().join(format!("neumann-bombs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let timed = |what: &str, text: &str| {
        let start = std::time::Instant::now();
        let r = load_scene_text(&dir.join("s.xml"), text, &[]).map(|_| ()).map_err(|e| e.to_string());
        assert!(start.elapsed().as_secs_f32() < 10.0, "{what} took {:?}", start.elapsed());
        r
    };
    let nested = format!(
        "{}<bsdf type=\"diffuse\"/>{}",
        "<bsdf type=\"twosided\">".repeat(30),
        "</bsdf>".repeat(30)
    );
    timed("nested twosided", &scene(&format!("<shape type=\"sphere\">{nested}</shape>"))).unwrap();
    let mut chain = String::from(r#"<bsdf type="diffuse" id="b0"/>"#);
    for k in 1..=40 {
        chain += &format!(
            r#"<bsdf type="blendbsdf" id="b{k}"><float name="weight" value="0.5"/><ref id="b{}"/><ref id="b{}"/></bsdf>"#,
            k - 1,
            k - 1
        );
    }
    chain += r#"<shape type="sphere"><ref id="b40"/></shape>"#;
    let e = timed("blend chain", &scene(&chain)).unwrap_err();
    assert!(e.contains("BSDF evaluations") && e.lines().all(|l| l.chars().count() < 200), "{e}");
    for k in 0..16 {
        let includes: String = (0..10).map(|_| format!(r#"<include filename="f{}.xml"/>"#, (k + 1) % 16)).collect();
        std::fs::write(dir.join(format!("f{k}.xml")), format!(r#"<scene version="3.0.0">{includes}</scene>"#)).unwrap();
    }
    let e = timed("include fan-out", &scene(r#"<include filename="f0.xml"/>"#)).unwrap_err();
    assert!(e.contains("included files") || e.contains("nested more than"), "{e}");
    let e = timed("/dev/zero include", &scene(r#"<include filename="/dev/zero"/>"#)).unwrap_err();
    assert!(e.contains("test.xml:") || e.contains("s.xml:"), "{e}");
    assert!(e.contains("not a regular file"), "{e}");
    let e = timed(
        "/dev/zero spectrum",
        &scene(r#"<shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" filename="/dev/zero"/></bsdf></shape>"#),
    )
    .unwrap_err();
    assert!(e.contains("not a regular file"), "{e}");
    let deep = format!("{}{}", "<bsdf type=\"twosided\">".repeat(100_000), "</bsdf>".repeat(100_000));
    let e = timed("deep nesting", &scene(&format!("<shape type=\"sphere\">{deep}</shape>"))).unwrap_err();
    assert!(e.contains("nested more than") || e.contains("malformed XML"), "{e}");
    std::fs::write(dir.join("secret.txt"), "password=hunter2\n").unwrap();
    let e = timed("text include", &scene(r#"<include filename="secret.txt"/>"#)).unwrap_err();
    assert!(e.contains("not an XML scene file") && !e.contains("hunter2"), "{e}");
    std::fs::write(dir.join("binary.xml"), b"<scene version=\"3.0.0\">\n\x00\xff\xfe</scene>").unwrap();
    let e = crate::load::mitsuba::load_scene_file(&dir.join("binary.xml"), &[]).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("binary.xml:2: column 2: not UTF-8"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Command-line flags as overrides of the scene's objects: the sampler's `sample_count` and
/// `seed`, the film's size, the integrator's `max_depth` (a `moment`'s nested path tracer's), an
/// integrator switch that keeps the path settings, objects created where the file has none, and
/// errors located at the flag ("command line", quoting it) in the plugins' own words.
#[test]
fn flags_override_the_scene_objects() {
    use crate::load::overrides::{Override, Overrides, Target};
    let dir = std::env::temp_dir().join(format!("neumann-overrides-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s.xml");
    let int = crate::props::Value::Integer;
    let flags = |settings: Vec<Override>, integrator: Option<crate::integrator::IntegratorKind>| Overrides {
        integrator: integrator.map(|k| (k, format!("--integrator {}", crate::choice::Choice::name(k)))),
        settings,
    };
    let load_with = |text: &str, o: &Overrides| {
        std::fs::write(&path, text).unwrap();
        crate::load::mitsuba::load_scene_file_with(&path, &[], o)
    };
    let base = scene(r#"<integrator type="moment"><integrator type="path"><integer name="max_depth" value="9"/></integrator></integrator>"#);
    let o = flags(
        vec![
            Override::new(Target::Sampler, "sample_count", int(7), "--spp 7"),
            Override::new(Target::Sampler, "seed", int(11), "--seed 11"),
            Override::new(Target::Film, "width", int(10), "--res 10x6"),
            Override::new(Target::Film, "height", int(6), "--res 10x6"),
            Override::new(Target::Integrator, "max_depth", int(3), "--max-depth 3"),
        ],
        None,
    );
    let f = load_with(&base, &o).unwrap();
    assert_eq!((f.spp, f.seed), (7, 11));
    assert_eq!((f.scene.camera().width(), f.scene.camera().height()), (10, 6));
    assert_eq!(f.integrator.name(), "moment");
    assert_eq!(f.integrator.path_settings().unwrap().max_depth, 3, "the moment's nested path tracer");
    // Switching keeps max_depth; a scene without an integrator gets one.
    let f = load_with(&base, &flags(vec![], Some(crate::integrator::IntegratorKind::Volpath))).unwrap();
    assert_eq!((f.integrator.name(), f.integrator.path_settings().unwrap().max_depth), ("volpath", 9));
    let bare = scene("");
    let f = load_with(&bare, &flags(vec![Override::new(Target::Integrator, "max_depth", int(2), "--max-depth 2")], None))
        .unwrap();
    assert_eq!((f.integrator.name(), f.integrator.path_settings().unwrap().max_depth), ("path", 2));
    for (o, expectation) in [
        (flags(vec![Override::new(Target::Integrator, "max_depth", int(-5), "--max-depth -5")], None), "max_depth must be"),
        (
            flags(
                vec![Override::new(Target::Integrator, "max_depth", int(3), "--max-depth 3")],
                Some(crate::integrator::IntegratorKind::Radiosity),
            ),
            "does not take the parameter integer 'max_depth'",
        ),
        (flags(vec![Override::new(Target::Film, "width", int(0), "--res 0")], None), "width"),
    ] {
        let e = load_with(&bare, &o).map(|_| ()).unwrap_err();
        let text = e.to_string();
        assert!(text.starts_with("command line:1:1:") && text.contains(expectation), "{text}");
        assert!(text.contains(&o.settings[0].source), "the flag is quoted: {text}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A diffuse reflectance above 1 (a <float> or <spectrum>: Mitsuba accepts it) is kept but
/// warned about at its position; one within [0, 1] is not.
#[test]
fn reflectance_above_one_is_warned_about() {
    let f = load(&scene(r#"<shape type="sphere"><bsdf type="diffuse"><float name="reflectance" value="2"/></bsdf></shape>"#))
        .unwrap();
    assert!(f.warnings.len() == 1 && f.warnings[0].contains("test.xml:7:") && f.warnings[0].contains("exceeds 1"), "{:?}", f.warnings);
    let f = load(&scene(r#"<shape type="sphere"><bsdf type="plastic"><float name="diffuse_reflectance" value="0.9"/></bsdf></shape>"#))
        .unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let f = load(&scene(
        r#"<shape type="sphere"><bsdf type="dielectric"><float name="specular_transmittance" value="1.5"/></bsdf></shape>"#,
    ))
    .unwrap();
    assert!(f.warnings.len() == 1 && f.warnings[0].contains("specular_transmittance"), "{:?}", f.warnings);
}

/// Emitters look their textures up by uv: a texture that varies with position (a 3D pattern, a
/// projection) as an emitter's parameter is an error, never a lookup at the wrong point.
#[test]
fn emitters_refuse_textures_that_vary_with_position() {
    let area = r#"<shape type="sphere"><emitter type="area"><texture type="fbm" name="radiance"/></emitter></shape>"#;
    let e = err(&scene(area));
    assert!(e.contains("varies with position"), "{e}");
    let spot = r#"<emitter type="spot"><texture type="bilerp" name="texture"><string name="mapping" value="spherical"/></texture></emitter>"#;
    let e = err(&scene(spot));
    assert!(e.contains("varies with position") && e.contains("spot"), "{e}");
    // A 2D pattern over uv is fine.
    let uv = r#"<shape type="rectangle"><emitter type="area"><texture type="bilerp" name="radiance"/></emitter></shape>"#;
    load(&scene(uv)).unwrap_or_else(|e| panic!("{e}"));
}

/// Mitsuba's `measured`: the RGL tensor file named by `filename` (relative to the scene), shared
/// between the BSDFs that name it; a missing file, a file that is not a tensor file and one
/// that lacks a field are errors at the parameter's line naming what is wrong.
#[test]
fn measured_bsdf_reads_its_tensor_file() {
    let f = load_scene_file(&shared("measured.xml"), &[]).expect("measured.xml loads");
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    let measured: Vec<&str> = f
        .scene
        .bsdfs()
        .iter()
        .filter_map(|b| match b {
            Bsdf::Measured(m) => Some(m.description.as_str()),
            _ => None,
        })
        .collect();
    assert_eq!(measured.len(), 2, "{measured:?}");
    assert!(measured[0].contains("isotropic") && measured[1].contains("anisotropic"), "{measured:?}");
    let dir = std::env::temp_dir().join(format!("neumann-measured-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("junk.bsdf"), b"not a tensor file").unwrap();
    let mut partial = crate::tensor::TensorFile::default();
    partial.fields.insert("theta_i".into(), crate::tensor::TensorField::from_f32(&[2], &[0.0, 1.0]));
    std::fs::write(dir.join("partial.bsdf"), crate::load::tensor_file::tensor_file_bytes(&partial)).unwrap();
    for (file, what) in [
        ("nope.bsdf", "nope.bsdf: cannot read"),
        ("junk.bsdf", "not a tensor file"),
        ("partial.bsdf", "the file has no field 'phi_i'"),
    ] {
        let text = scene(&format!(
            "<shape type=\"sphere\">\n<bsdf type=\"measured\"><string name=\"filename\" value=\"{file}\"/></bsdf></shape>"
        ));
        let e = match load_scene_text(&dir.join("s.xml"), &text, &[]) {
            Ok(_) => panic!("{file}: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains("s.xml:8:23:") && e.contains(what), "{file}: {e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Mitsuba 3's `<rotate>` does not normalize its axis: `x="1" y="1"` at 30° is the matrix
/// Mitsuba 3.9.1 prints for it (a rotation that also stretches); a zero axis is an error, as
/// in Mitsuba 3.9.1 ("rotation axis cannot be zero"); one number as `value` is that number on
/// all three axes (Mitsuba's `value` expansion), and it cannot be mixed with `x`, `y`, `z`.
#[test]
fn rotate_keeps_the_axis_as_written() {
    let f = load(&scene(r#"<shape type="cube"><transform name="to_world"><rotate x="1" y="1" angle="30"/></transform></shape>"#)).unwrap();
    // Said, with the position, since it is rarely what the author meant.
    assert!(
        f.warnings.len() == 1 && f.warnings[0].contains("test.xml:7:") && f.warnings[0].contains("not a unit vector"),
        "{:?}",
        f.warnings
    );
    let Geometry::Mesh(m) = &f.scene.geometries()[0] else { panic!("a cube is a mesh") };
    // Mitsuba: [[1, 0.133975, 0.5], [0.133975, 1, -0.5], [-0.5, 0.5, 0.866025]]; the cube's
    // corner (1, 1, 1) goes to the rows' sums.
    let corner = m.positions.iter().copied().find(|p| (*p - Vec3::new(1.633975, 0.633975, 0.866025)).length() < 1e-5);
    assert!(corner.is_some(), "{:?}", m.positions);
    let e = err(&scene(r#"<shape type="sphere"><transform name="to_world"><rotate angle="60"/></transform></shape>"#));
    assert!(e.contains("test.xml:7:") && e.contains("the rotation axis is zero"), "{e}");
    let one = r#"<rotate value="1" angle="30"/>"#;
    let f = load(&scene(&format!(r#"<shape type="cube"><transform name="to_world">{one}</transform></shape>"#))).unwrap();
    let written = r#"<rotate x="1" y="1" z="1" angle="30"/>"#;
    let g = load(&scene(&format!(r#"<shape type="cube"><transform name="to_world">{written}</transform></shape>"#))).unwrap();
    let (Geometry::Mesh(a), Geometry::Mesh(b)) = (&f.scene.geometries()[0], &g.scene.geometries()[0]) else {
        panic!("cubes are meshes")
    };
    assert_eq!(a.positions, b.positions);
    // A unit axis, even one written to six digits, is a rotation: nothing to say.
    let unit = r#"<rotate x="0.584436" y="0.528244" z="0.615949" angle="30"/>"#;
    let f = load(&scene(&format!(r#"<shape type="cube"><transform name="to_world">{unit}</transform></shape>"#))).unwrap();
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
}

/// Mitsuba 3.9.1's attribute rules (its parser's `check_attributes` and `value` expansion):
/// an attribute an element does not take is a located error, `value` and `x`/`y`/`z` never
/// mix, a `<point>` or `<vector>` needs all of `x`, `y`, `z` (or `value`), and one number as a
/// `<translate>`'s `value` moves along all three axes. Each verdict is Mitsuba 3.9.1's on the
/// same element.
#[test]
fn attributes_follow_mitsubas_rules() {
    let sphere = |inner: &str| format!(r#"<shape type="sphere">{inner}</shape>"#);
    let to_world = |op: &str| sphere(&format!(r#"<transform name="to_world">{op}</transform>"#));
    for (body, expectation) in [
        (to_world(r#"<scale x="2" foo="1"/>"#), r#"unexpected attribute "foo" in <scale>"#),
        (sphere(r#"<float name="radius" value="2" foo="x"/>"#), r#"unexpected attribute "foo" in <float>"#),
        (to_world(r#"<scale y="-1" value="0.7"/>"#), "cannot mix"),
        (to_world(r#"<translate value="1" z="2"/>"#), "cannot mix"),
        (sphere(r#"<point name="center" x="1"/>"#), r#"<point> needs "y""#),
        (sphere(r#"<point name="center" value="1" x="1"/>"#), "cannot mix"),
        (to_world(r#"<lookat origin="0,0,1" target="0,0,0" upp="0,1,0"/>"#), r#"did you mean "up"?"#),
        (r#"<shape type="sphere" idd="a"/>"#.to_string(), r#"unexpected attribute "idd" in <shape>"#),
        // Nothing nests in a property (Mitsuba: "cannot occur as child of a property").
        (
            sphere(r#"<float name="radius" value="1"><shape type="sphere"/></float>"#),
            "<shape> cannot be nested in the property <float>",
        ),
        (
            sphere(r#"<point name="center" value="1"><float name="x" value="1"/></point>"#),
            "<float> cannot be nested in the property <point>",
        ),
        (
            r#"<bsdf type="diffuse" id="b"/><shape type="sphere"><ref id="b" foo="1"/></shape>"#.to_string(),
            r#"unexpected attribute "foo" in <ref>"#,
        ),
        (sphere(r#"<boolean name="flip_normals" value="1"/>"#), "expected true or false"),
        (r#"<default name="r" value="1" foo="2"/>"#.to_string(), r#"unexpected attribute "foo" in <default>"#),
        (r#"<include filename="x.xml" id="i"/>"#.to_string(), r#"unexpected attribute "id" in <include>"#),
        (r#"<path value="." id="p"/>"#.to_string(), r#"unexpected attribute "id" in <path>"#),
        (
            r#"<bsdf type="diffuse" id="b"/><alias id="b" as="c" name="n"/>"#.to_string(),
            r#"unexpected attribute "name" in <alias>"#,
        ),
    ] {
        let e = err(&scene(&body));
        assert!(e.contains("test.xml:7:") && e.contains(expectation), "expected '{expectation}' in:\n{e}");
    }
    // A misspelt operation is named as such, not by its attributes.
    let e = err(&scene(&to_world(r#"<translat x="1"/>"#)));
    assert!(e.contains("unknown transform operation <translat>"), "{e}");
    let f = load(&scene(&to_world(r#"<translate value="1"/>"#))).unwrap();
    let Geometry::Sphere(s) = &f.scene.geometries()[0] else { panic!("a sphere") };
    assert_eq!(s.center, Vec3::ONE);
    let f = load(&scene(&sphere(r#"<point name="center" value="2"/>"#))).unwrap();
    let Geometry::Sphere(s) = &f.scene.geometries()[0] else { panic!("a sphere") };
    assert_eq!(s.center, Vec3::splat(2.0));
}

/// What Mitsuba 3.9.1 refuses, checked against it: a `twosided` around a BSDF with a
/// transmission or null lobe (by its flags: a `principled` with `spec_trans` given, any
/// `principledthin`, a mask, a blend or normal map of one), a `blendbsdf` without `weight`,
/// and one of `alpha_u`, `alpha_v` without the other; and what it takes: a spot's
/// `beam_width` beyond its `cutoff_angle`.
#[test]
fn twosided_and_blendbsdf_refuse_what_mitsuba_refuses() {
    let shape = |bsdf: &str| format!(r#"<shape type="sphere">{bsdf}</shape>"#);
    let two = |inner: &str| shape(&format!(r#"<bsdf type="twosided">{inner}</bsdf>"#));
    for (inner, name) in [
        (r#"<bsdf type="dielectric"/>"#, "dielectric"),
        (r#"<bsdf type="thindielectric"/>"#, "thindielectric"),
        (r#"<bsdf type="roughdielectric"/>"#, "roughdielectric"),
        (r#"<bsdf type="null"/>"#, "null"),
        (r#"<bsdf type="mask"><bsdf type="diffuse"/></bsdf>"#, "mask"),
        (r#"<bsdf type="principled"><float name="spec_trans" value="0.5"/></bsdf>"#, "principled"),
        (r#"<bsdf type="principledthin"/>"#, "principledthin"),
        (r#"<bsdf type="hair"/>"#, "hair"),
        (r#"<bsdf type="polarizer"/>"#, "polarizer"),
        (r#"<bsdf type="diffuse"/><bsdf type="dielectric"/>"#, "dielectric"),
        (
            r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/><bsdf type="dielectric"/></bsdf>"#,
            "blendbsdf",
        ),
        (
            r#"<bsdf type="normalmap"><rgb name="normalmap" value="0.5, 0.5, 1"/><bsdf type="dielectric"/></bsdf>"#,
            "normalmap",
        ),
    ] {
        let e = err(&scene(&two(inner)));
        assert!(
            e.contains("test.xml:7:") && e.contains(&format!("a '{name}' cannot be nested in a 'twosided'")),
            "{inner}:\n{e}"
        );
    }
    for inner in [
        r#"<bsdf type="principled"/>"#,
        r#"<bsdf type="principled"><float name="spec_trans" value="0"/></bsdf>"#,
        r#"<bsdf type="plastic"/>"#,
        r#"<bsdf type="diffuse"/><bsdf type="roughconductor"/>"#,
    ] {
        load(&scene(&two(inner))).unwrap_or_else(|e| panic!("{inner}: {e}"));
    }
    let e = err(&scene(&shape(r#"<bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#)));
    assert!(e.contains("test.xml:7:") && e.contains("needs its 'weight'"), "{e}");
    // Anisotropic roughness comes in pairs, constant or textured.
    for bsdf in ["roughconductor", "roughdielectric"] {
        let e = err(&scene(&shape(&format!(r#"<bsdf type="{bsdf}"><float name="alpha_u" value="0.2"/></bsdf>"#))));
        assert!(e.contains("test.xml:7:") && e.contains("'alpha_u' needs 'alpha_v' too"), "{e}");
    }
    // A spot's beam wider than its cutoff is the cutoff, as Mitsuba renders it (not an error).
    let spot = |beam: &str| {
        let text = scene(&format!(
            r#"<emitter type="spot"><float name="cutoff_angle" value="20"/><float name="beam_width" value="{beam}"/></emitter>"#
        ));
        format!("{:?}", load(&text).unwrap().scene.lights())
    };
    assert_eq!(spot("30"), spot("20"));
    let checker = r#"<texture type="checkerboard" name="alpha_v"/>"#;
    let e = err(&scene(&shape(&format!(r#"<bsdf type="roughconductor">{checker}</bsdf>"#))));
    assert!(e.contains("'alpha_v' needs 'alpha_u' too"), "{e}");
}

/// Mitsuba 3.9.1's `ellipsoids` and `ellipsoidsmesh` on the same 3D-Gaussian file, placed by a
/// rotating, scaling `to_world`, with `scale_factor`, `extent` and `extent_adaptive_clamping`
/// (tools/mitsuba/make_ellipsoids.py printed these rays and Mitsuba's hits: distance, normal,
/// ellipsoid index; a tenth of the rays start inside the cloud). The analytic shells are seen
/// from outside only; the mesh shells (uv_sphere) from both sides.
#[test]
#[allow(clippy::excessive_precision)] // Mitsuba's printed digits
fn ellipsoids_hit_what_mitsuba_hits() {
    type Row = ([f32; 3], [f32; 3], Option<(f32, [f32; 3], u32)>);
    let analytic: &[Row] = &[
        ([2.1072872, -0.5960616, 0.6172155], [-0.9511400, -0.2971698, -0.0838022], Some((2.619102, [0.195268, -0.099077, -0.975733], 31))),
        ([-1.3476745, -3.5055504, -1.3765500], [0.2967659, 0.8812186, 0.3679452], None),
        ([-1.3769757, -3.7523298, -0.1547859], [0.2905698, 0.9159951, 0.2766263], Some((2.726715, [-0.812799, -0.460368, 0.356957], 31))),
        ([2.0387263, 2.8120437, 1.9839369], [-0.4648314, -0.7645642, -0.4465124], None),
        ([1.6117326, -2.3020227, 2.8465786], [-0.3940401, 0.5163689, -0.7603260], Some((3.529282, [-0.856647, -0.052187, 0.513257], 39))),
        ([-2.7089360, 0.6410566, -2.8724053], [0.8212791, -0.2671223, 0.5041293], Some((4.651535, [-0.240105, 0.336917, -0.910404], 43))),
        ([-1.3677709, -3.7581429, -0.0745986], [0.4655826, 0.8839539, -0.0431089], None),
        ([-1.5547289, 3.6277781, 0.6496497], [0.4649172, -0.8467823, 0.2584798], None),
        ([3.8376551, 0.4126475, 1.0498217], [-0.9182506, -0.2258991, -0.3252468], Some((2.874027, [0.375164, 0.852284, 0.364505], 46))),
        ([0.2206870, -3.9855258, -0.2586119], [0.0054084, 0.9989244, 0.0460511], Some((3.333229, [-0.353840, -0.550809, 0.755915], 38))),
        ([0.2311490, -0.6231031, 0.1502562], [0.8375383, 0.4728023, -0.2738385], Some((0.067483, [-0.069623, -0.882007, 0.466064], 39))),
        ([0.1686483, -3.7516382, -1.3772324], [0.0112784, 0.9349455, 0.3546120], Some((3.264217, [0.220125, -0.959822, -0.174031], 38))),
        ([-0.4623179, -3.3568707, -2.1254838], [0.4178609, 0.6143044, 0.6693447], None),
        ([0.9559180, -1.6325276, -3.5243545], [-0.1851665, 0.3602396, 0.9142980], Some((4.838882, [-0.287187, -0.839210, -0.461790], 16))),
        ([-3.6310365, -0.2850426, -1.6535791], [0.8297614, 0.0696365, 0.5537569], None),
        ([-0.7411117, -3.4997156, -1.7896215], [0.1947362, 0.8041497, 0.5616236], Some((3.228334, [-0.669162, -0.741250, 0.052634], 35))),
        ([3.0402327, -0.0561901, -2.5988128], [-0.7919526, -0.1871450, 0.5811952], Some((4.297102, [-0.239653, 0.534760, -0.810308], 33))),
        ([-2.0122056, 3.1393313, 1.4476284], [0.6351400, -0.7593716, -0.1412512], Some((3.228056, [-0.953957, 0.223884, -0.199603], 13))),
        ([2.7791824, -1.1303797, -2.6454465], [-0.5218061, 0.2682637, 0.8097857], Some((2.984362, [0.538508, -0.773791, -0.333553], 46))),
        ([-1.8216437, 3.5585816, -0.1345776], [0.4946397, -0.8329820, 0.2479366], Some((3.766182, [-0.354266, 0.924664, 0.139612], 16))),
        ([3.5193043, 0.9128739, -1.6676807], [-0.8229547, -0.1738619, 0.5408489], Some((3.556421, [0.675752, 0.236271, -0.698237], 8))),
        ([-2.1108601, 3.0684669, 1.4590342], [0.7389723, -0.6219925, -0.2589310], Some((4.571259, [0.185078, 0.779686, -0.598194], 3))),
    ];
    let mesh: &[Row] = &[
        ([-0.8194467, -0.2743192, 0.5699380], [0.5931068, -0.1301582, 0.7945333], None),
        ([3.2031100, 1.5081694, 1.8615882], [-0.8422465, -0.4957909, -0.2116891], Some((4.356437, [0.169382, 0.660478, 0.731491], 27))),
        ([-1.6739633, -2.2213104, 2.8746526], [0.3340530, 0.6721248, -0.6608002], Some((3.599922, [0.246286, -0.969097, -0.013968], 20))),
        ([1.9742565, -2.7626319, 2.1142790], [-0.5366860, 0.7923547, -0.2900727], Some((3.526750, [0.182499, -0.948261, -0.259800], 16))),
        ([2.9782128, 1.6867671, 2.0700400], [-0.8766525, -0.2905764, -0.3834655], Some((3.071074, [0.757495, -0.564680, -0.327625], 13))),
        ([0.2668976, -0.7975195, -3.9105918], [-0.0654847, 0.1999879, 0.9776076], Some((4.926040, [-0.670227, -0.549917, -0.498384], 16))),
        ([-1.3689752, -1.9866275, 3.1904888], [0.2698446, 0.6995500, -0.6616750], None),
        ([-1.6445726, 1.8324634, 3.1523736], [0.3403302, -0.3481149, -0.8734938], None),
        ([2.7020080, -0.6916487, -2.8671894], [-0.4520102, 0.2118336, 0.8664948], Some((3.252316, [0.913218, 0.374558, -0.160438], 0))),
        ([3.6796100, 1.4842324, -0.5074677], [-0.9010491, -0.4172047, 0.1185361], None),
        ([0.0414664, 1.3523575, 0.4116407], [0.3352337, -0.3942316, 0.8556867], Some((0.623808, [-0.773570, 0.619711, -0.132466], 13))),
        ([-0.9913228, -3.0718668, 2.3623958], [0.4319187, 0.6920239, -0.5784023], None),
        ([3.3405910, 1.7414304, 1.3445715], [-0.8364344, -0.5061595, -0.2101905], None),
        ([0.4936853, 1.7895553, 3.5431294], [0.0129769, -0.3847328, -0.9229367], Some((4.234068, [0.220918, 0.487424, 0.844757], 45))),
        ([0.7901128, 3.9204962, 0.0736941], [-0.1333498, -0.9752449, 0.1763948], Some((3.511881, [-0.018607, 0.991836, -0.126158], 11))),
        ([-3.1366379, -0.8680003, 2.3255272], [0.7859105, 0.2147206, -0.5798618], Some((4.565945, [0.143654, 0.365460, 0.919675], 45))),
        ([2.6978972, -2.3099046, 1.8400248], [-0.5636451, 0.5916076, -0.5764587], Some((3.016374, [0.451097, -0.214512, 0.866312], 44))),
        ([-3.7773352, 0.2831502, -1.2851322], [0.9704316, -0.0627558, 0.2330753], Some((4.085865, [-0.674034, 0.241380, -0.698150], 45))),
        ([3.1263330, 1.9645418, 1.5383816], [-0.7964187, -0.5134138, -0.3195676], Some((3.265050, [0.538913, -0.402170, 0.740156], 8))),
        ([-1.3016348, -3.5277655, 1.3640443], [0.3905224, 0.8723655, -0.2940589], Some((2.555039, [0.569333, -0.478446, 0.668543], 31))),
        ([1.7027634, 0.2476180, -3.6109946], [-0.3747686, -0.0773294, 0.9238878], Some((3.435399, [-0.225055, -0.084122, -0.970708], 45))),
        ([-2.7747293, 2.0809145, -1.9926546], [0.6109855, -0.5345845, 0.5838802], Some((3.565376, [-0.147453, 0.830973, -0.536415], 24))),
    ];
    let file = shared("assets/ellipsoids.ply");
    for (ty, rows, shell) in [("ellipsoids", analytic, ""), ("ellipsoidsmesh", mesh, r#"<string name="shell" value="uv_sphere"/>"#)] {
        let text = scene(&format!(
            r#"<shape type="{ty}"><string name="filename" value="{}"/>{shell}
            <float name="scale_factor" value="0.8"/><float name="extent" value="2.5"/>
            <boolean name="extent_adaptive_clamping" value="true"/>
            <transform name="to_world"><scale value="1.3"/><rotate x="1" y="1" angle="30"/><translate x="0.2" y="-0.1" z="0.4"/></transform>
            </shape>"#,
            file.display()
        ));
        let f = load(&text).unwrap();
        for (o, d, expected) in rows {
            let ray = Ray::new(Vec3::from(*o), Vec3::from(*d));
            let hit = f.scene.intersect(&ray);
            match (expected, hit) {
                (None, None) => {}
                (Some((t, n, prim)), Some(si)) => {
                    // Mitsuba's analytic test is off by up to 2·10⁻⁴ of t on a lone ellipsoid (its
                    // distances against the exact root, measured by the script); neumann's hits
                    // lie on the shell to 10⁻⁵ (geometry::ellipsoids' tests). The meshes agree to
                    // rounding.
                    let (dt, dn) = if ty == "ellipsoids" { (2e-3, 2e-2) } else { (2e-5, 2e-4) };
                    assert!((si.t - t).abs() < dt * t, "{ty} {o:?}: t {} against Mitsuba's {t}", si.t);
                    assert!((si.ng - Vec3::from(*n)).length() < dn, "{ty} {o:?}: n {} against {n:?}", si.ng);
                    // The mesh's triangles are numbered per shell (72 a shell, as Mitsuba's).
                    let index = if ty == "ellipsoids" { si.prim } else { si.prim / 72 };
                    assert_eq!(index, *prim, "{ty} {o:?}");
                }
                (e, h) => panic!("{ty} {o:?} {d:?}: Mitsuba {e:?}, neumann {:?}", h.map(|s| s.t)),
            }
        }
    }
}

/// The ellipsoid shapes' parameters and errors: a nested mesh as the shell, a point file of
/// the wrong layout, what they cannot be or take, and adaptive clamping without opacities (a
/// warning, as Mitsuba's).
#[test]
fn ellipsoid_parameters_and_errors() {
    let file = shared("assets/ellipsoids.ply");
    let shape = |ty: &str, inner: &str| {
        scene(&format!(r#"<shape type="{ty}"><string name="filename" value="{}"/>{inner}</shape>"#, file.display()))
    };
    // A cube as the template: 12 triangles a shell, 48 ellipsoids.
    let f = load(&shape("ellipsoidsmesh", r#"<shape type="cube" name="shell"/>"#)).unwrap();
    let Geometry::Mesh(m) = &f.scene.geometries()[0] else { panic!("an ellipsoidsmesh is a mesh") };
    assert_eq!((m.len(), m.faces_per_primitive), (12 * 48, 12));
    // The AOV prim_index counts ellipsoids (Mitsuba 3.9.1's: 0 to 47 on this file), not triangles.
    let aov = load(&format!(
        r#"<scene version="3.0.0"><integrator type="aov"><string name="aovs" value="pi:prim_index"/></integrator>{}</scene>"#,
        shape("ellipsoidsmesh", "").trim_start_matches(r#"<scene version="3.0.0">"#).trim_end().trim_end_matches("</scene>")
    ))
    .unwrap();
    let settings = crate::render::RenderSettings { spp: 1, filter: Filter::BOX, ..Default::default() };
    let integrator = aov.integrator.camera().unwrap();
    let out = crate::render::render(&aov.scene, integrator, &settings, &std::sync::atomic::AtomicBool::new(false)).unwrap();
    let indices = &out.film.aov_channels().into_iter().find(|c| c.0 == "pi.I").unwrap().1;
    let max = indices.iter().fold(0.0f32, |a, &b| a.max(b));
    assert!(max > 12.0 && max <= 47.0 && indices.iter().all(|v| v.fract() == 0.0), "largest index {max}");
    // A mesh's flip_normals turns the shells' normals inward (Mitsuba's mesh takes it).
    let ray = (0..100)
        .map(|k| Ray::new(Vec3::new(-1.0 + 0.02 * k as f32, 0.05, 5.0), -Vec3::Z))
        .find(|r| f.scene.intersect(r).is_some())
        .expect("a ray across the cloud hits a shell");
    let outward = f.scene.intersect(&ray).unwrap().ng;
    assert!(outward.z > 0.0, "{outward}");
    let flipped = r#"<shape type="cube" name="shell"/><boolean name="flip_normals" value="true"/><boolean name="face_normals" value="true"/>"#;
    let flipped = load(&shape("ellipsoidsmesh", flipped)).unwrap();
    assert_eq!(flipped.scene.intersect(&ray).unwrap().ng, -outward);
    for (ty, inner, expected) in [
        ("ellipsoids", r#"<boolean name="flip_normals" value="true"/>"#, "have no flip_normals"),
        ("ellipsoids", r#"<boolean name="face_normals" value="true"/>"#, "does not take the parameter"),
        ("ellipsoids", r#"<float name="extent" value="0"/>"#, "extent"),
        ("ellipsoidsmesh", r#"<string name="shell" value="cone"/>"#, "unknown shell 'cone'"),
        ("ellipsoidsmesh", r#"<shape type="sphere" name="shell"/>"#, "shell must be a triangle mesh"),
        ("ellipsoids", r#"<emitter type="area"/>"#, "ellipsoids cannot be an area"),
        ("ellipsoidsmesh", r#"<emitter type="area"/>"#, "an ellipsoidsmesh cannot be an area"),
        ("ellipsoids", r#"<string name="shell" value="box"/>"#, "does not take the parameter"),
    ] {
        let e = load(&shape(ty, inner)).unwrap_err().to_string();
        assert!(e.contains("test.xml:") && e.contains(expected), "{ty} {inner}: {e}");
    }
    // A mesh file is not a point file of ellipsoids.
    let knot = shared("assets/knot_colors.ply");
    let text = scene(&format!(r#"<shape type="ellipsoids"><string name="filename" value="{}"/></shape>"#, knot.display()));
    let e = load(&text).unwrap_err().to_string();
    assert!(e.contains("test.xml:") && e.contains("must begin with 'x y z nx ny nz'"), "{e}");
    // Adaptive clamping needs opacities: without them, a warning and the fixed extent.
    let dir = std::env::temp_dir().join(format!("neumann-ellipsoids-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("one.ply"),
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n\
         property float ny\nproperty float nz\nproperty float scale_0\nproperty float scale_1\nproperty float scale_2\n\
         property float rot_0\nproperty float rot_1\nproperty float rot_2\nproperty float rot_3\nend_header\n\
         0 0 0 0 0 0 0 0 0 1 0 0 0\n",
    )
    .unwrap();
    let text = scene(r#"<shape type="ellipsoids"><string name="filename" value="one.ply"/><float name="extent" value="1.5"/>
        <boolean name="extent_adaptive_clamping" value="true"/></shape>"#);
    let f = load_scene_text(&dir.join("s.xml"), &text, &[]).unwrap();
    assert!(f.warnings.iter().any(|w| w.contains("s.xml:") && w.contains("no opacities")), "{:?}", f.warnings);
    let si = f.scene.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)).unwrap();
    assert!((si.t - 3.5).abs() < 1e-5, "a unit sphere times 1.5: {}", si.t);
    assert_eq!((si.uv, si.dpdu), (crate::math::Vec2::ZERO, Vec3::ZERO), "no parameterization");
}

/// Mitsuba's polarizing elements as its RGB variants sample them (weights printed by Mitsuba
/// 3.9.1's `scalar_rgb`): a straight-through null lobe of weight ½ × transmittance (polarizer,
/// circular) or 1 (retarder), their polarizing parameters read and not used.
#[test]
fn polarizing_elements_pass_their_share() {
    for (bsdf, name, weight) in [
        (r#"<bsdf type="polarizer"><float name="theta" value="30"/><float name="transmittance" value="0.6"/></bsdf>"#, "polarizer", 0.3),
        (r#"<bsdf type="polarizer"><boolean name="polarizing" value="false"/></bsdf>"#, "polarizer", 0.5),
        (r#"<bsdf type="circular"><boolean name="left_handed" value="true"/></bsdf>"#, "circular", 0.5),
        (r#"<bsdf type="retarder"><float name="delta" value="45"/><float name="theta" value="10"/></bsdf>"#, "retarder", 1.0),
    ] {
        let f = load(&scene(&format!(r#"<shape type="sphere">{bsdf}</shape>"#))).unwrap();
        let b = &f.scene.bsdfs()[0];
        assert_eq!(b.plugin_name(), name);
        let si = f.scene.intersect(&Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z)).unwrap();
        let ctx = f.scene.bsdf_context(&si);
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let s = b.sample(&ctx, wo, 0.3, crate::math::Vec2::new(0.2, 0.7)).unwrap();
        assert_eq!((s.wi, s.delta, s.pdf), (-wo, true, 1.0));
        assert!((s.weight - Rgb::splat(weight)).abs().max_element() < 1e-6, "{name}: {}", s.weight);
        assert_eq!(b.eval(&ctx, wo, -wo), Rgb::ZERO);
    }
    let e = load(&scene(r#"<shape type="sphere"><bsdf type="circular"><float name="theta" value="20"/></bsdf></shape>"#))
        .unwrap_err()
        .to_string();
    assert!(e.contains("does not take the parameter") && e.contains("theta"), "{e}");
}

/// Mitsuba's `timed_sunsky` for rays at one time (the sensor's shutter closed, as by default):
/// the sky of the moment Mitsuba maps that time to — here the time is 0.435 of the emitter's
/// shutter, 126 of the 291 days from 20 March 2025, at 12.913 h of a 9–16.5 h window — equal to
/// Mitsuba 3.9.1's (its `eval` at four directions, the sun off) and to a `sunsky` at that
/// moment. A sensor whose shutter opens over an interval would need a time per ray: an error.
#[test]
fn timed_sunsky_is_the_sky_of_its_moment() {
    let place = r#"<float name="latitude" value="48.85"/><float name="longitude" value="2.35"/><float name="timezone" value="1"/>
        <float name="turbidity" value="4"/><float name="sun_scale" value="0"/>"#;
    let timed = format!(
        r#"<emitter type="timed_sunsky"><float name="shutter_open" value="-1"/><float name="shutter_close" value="1.3"/>
        <integer name="start_month" value="3"/><integer name="start_day" value="20"/><integer name="end_year" value="2026"/>
        <integer name="end_month" value="1"/><integer name="end_day" value="5"/><float name="window_start_time" value="9"/>
        <float name="window_end_time" value="16.5"/>{place}</emitter>"#
    );
    let fixed = format!(
        r#"<emitter type="sunsky"><integer name="year" value="2025"/><integer name="month" value="3"/>
        <integer name="day" value="146"/><float name="hour" value="12.913021"/>{place}</emitter>"#
    );
    let sky = |body: &str| {
        let f = load(&scene(body)).unwrap();
        match &f.scene.lights()[0] {
            crate::light::Light::SunSky { sky, .. } => sky.clone(),
            other => panic!("a sunsky, not {other:?}"),
        }
    };
    let (timed, fixed) = (sky(&timed), sky(&fixed));
    // Mitsuba 3.9.1 scalar_rgb, `eval` of the timed_sunsky with time 0 (radiance from d).
    for (d, mitsuba) in [
        ([0.0, 0.0, 1.0], [0.0551924, 0.0755641, 0.124287]),
        ([1.0, 0.0, 0.3], [0.120841, 0.172585, 0.258084]),
        ([0.0, 1.0, 0.5], [0.0532458, 0.0905881, 0.1632]),
        ([-0.5, -0.5, 0.7], [0.0326062, 0.0601146, 0.118377]),
    ] {
        let d = Vec3::from(d).normalize();
        let (a, b) = (timed.eval(d), fixed.eval(d));
        // (The hour given to the sunsky is rounded to a microhour.)
        assert!(((a - b) / b).abs().max_element() < 1e-5, "{d}: the same moment, {a} against {b}");
        let m = Rgb::new(mitsuba[0], mitsuba[1], mitsuba[2]);
        assert!(((a - m) / m).abs().max_element() < 2e-3, "{d}: {a} against Mitsuba's {m}");
    }
    let open = scene(r#"<emitter type="timed_sunsky"/>"#).replace(
        r#"<float name="fov" value="40"/>"#,
        r#"<float name="fov" value="40"/><float name="shutter_close" value="0.5"/>"#,
    );
    let e = load(&open).unwrap_err().to_string();
    assert!(e.contains("shutter is open from 0 to 0.5") && e.contains("test.xml:"), "{e}");
}

/// neumann's `pbrt_subsurface` from Mitsuba XML: a rough boundary where `alpha` is given, the
/// coefficients as given (an rgb above 1: unbounded), the relative index from `int_ior`; the
/// errors of a half-given or doubly given medium, and of an index-matched boundary.
#[test]
fn pbrt_subsurface_from_xml() {
    let bsdf = |params: &str| {
        scene(&format!(
            r#"<shape type="sphere"><bsdf type="pbrt_subsurface">{params}</bsdf></shape><integrator type="volpath"/>"#
        ))
    };
    let f = load(&bsdf(
        r#"<rgb name="sigma_a" value="0.5, 1, 2"/><rgb name="sigma_s" value="20, 10, 5"/><float name="scale" value="2"/><float name="int_ior" value="1.4"/><float name="alpha" value="0.2"/>"#,
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    let Bsdf::Subsurface(s) = &f.scene.bsdfs()[0] else { panic!("{:?}", f.scene.bsdfs()[0]) };
    let (sa, ss) = s.sigma(&crate::material::BsdfContext::default());
    assert_eq!((sa, ss), (Rgb::new(1.0, 2.0, 4.0), Rgb::new(40.0, 20.0, 10.0)));
    // (Mitsuba's default `ext_ior` is air's, 1.000277.)
    assert!(matches!(*s.surface, Bsdf::RoughDielectric(_)) && (s.eta - 1.4 / 1.000277).abs() < 1e-5);
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    for (params, what) in [
        (r#"<rgb name="sigma_a" value="1, 1, 1"/>"#, "sigma_s is missing"),
        (r#"<rgb name="mfp" value="1, 1, 1"/>"#, "mfp needs a reflectance"),
        (
            r#"<rgb name="sigma_a" value="1, 1, 1"/><rgb name="sigma_s" value="1, 1, 1"/><rgb name="reflectance" value="0.5, 0.5, 0.5"/>"#,
            "not both",
        ),
        (r#"<float name="int_ior" value="1"/><float name="ext_ior" value="1"/>"#, "relative index is 1"),
    ] {
        let e = err(&bsdf(params));
        assert!(e.contains("test.xml:") && e.contains(what), "{params}: {e}");
    }
}

/// neumann's film `sensor` (pbrt-v4's named cameras) and `white_balance`: the camera's matrix,
/// balanced for 6500 K unless told otherwise; located errors for an unknown camera (naming the
/// nearest) and for a camera asked for no white balance.
#[test]
fn film_camera_sensors() {
    use crate::film::sensor;
    let film = |props: &str| {
        scene("").replace(
            r#"<integer name="height" value="24"/></film>"#,
            &format!(r#"<integer name="height" value="24"/>{props}</film>"#),
        )
    };
    let f = load(&film(r#"<string name="sensor" value="sony_ilce_9"/>"#)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(f.transform.matrix, sensor::camera("sony_ilce_9", 6500.0));
    let f =
        load(&film(r#"<string name="sensor" value="nikon_d850"/><float name="white_balance" value="3200"/>"#)).unwrap();
    assert_eq!(f.transform.matrix, sensor::camera("nikon_d850", 3200.0));
    assert_ne!(f.transform.matrix, sensor::camera("nikon_d850", 6500.0));
    let f = load(&film(r#"<string name="sensor" value="cie1931"/>"#)).unwrap();
    assert!(f.transform.is_identity());
    let e = err(&film(r#"<string name="sensor" value="nikon_d8500"/>"#));
    assert!(e.contains("test.xml:5:") && e.contains("did you mean 'nikon_d850'"), "{e}");
    let e = err(&film(r#"<string name="sensor" value="canon_eos_5d"/><float name="white_balance" value="0"/>"#));
    assert!(e.contains("test.xml:5:") && e.contains("needs a white balance"), "{e}");
    // The clamp measured in the output RGB (default) or, as pbrt-v4, in the sensor's RGB.
    let f = load(&film(r#"<float name="max_component" value="2"/>"#)).unwrap();
    assert_eq!((f.transform.max_component, f.transform.clamp_basis), (2.0, None));
    let f = load(&film(r#"<float name="max_component" value="2"/><string name="max_component_of" value="sensor"/>"#))
        .unwrap();
    assert_eq!(f.transform.clamp_basis, Some(sensor::cie1931_sensor_basis()));
    let f = load(&film(
        r#"<string name="sensor" value="nikon_d850"/><float name="max_component" value="2"/><string name="max_component_of" value="sensor"/>"#,
    ))
    .unwrap();
    assert_eq!(f.transform.clamp_basis, sensor::camera_sensor_basis("nikon_d850", 6500.0));
    let e = err(&film(r#"<string name="max_component_of" value="input"/>"#));
    assert!(e.contains("test.xml:5:") && e.contains("output, sensor"), "{e}");
}

/// neumann's moving sensor in Mitsuba XML (what pbrt-v4's animated camera transform
/// translates to): a perspective sensor with `to_world_end` slides from x = 0 to x = 4 past a
/// black strip at x = 2 and sees it over its central ray for an eighth of the shutter; with
/// `shutter_close` 0 (Mitsuba's default) it stays at its start. A moving radiancemeter is an
/// error at its `to_world_end`.
#[test]
fn sensors_move_with_to_world_end() {
    let scene = |sensor: &str, shutter: f32| {
        let fov = if sensor == "perspective" { r#"<float name="fov" value="0.5"/>"# } else { "" };
        format!(
            r#"<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="1"/></integrator>
<sensor type="{sensor}">{fov}<float name="shutter_close" value="{shutter}"/>
<transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
<transform name="to_world_end"><lookat origin="4, 0, 0" target="4, 0, 1" up="0, 1, 0"/></transform>
<film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film></sensor>
<shape type="rectangle"><transform name="to_world"><scale value="50"/><rotate y="1" angle="180"/><translate z="10"/></transform>
<emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
<shape type="rectangle"><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
<transform name="to_world"><scale x="0.25" y="4"/><translate x="2" z="5"/></transform></shape></scene>"#
        )
    };
    let mean = |text: &str| {
        let f = load(text).unwrap_or_else(|e| panic!("{e}"));
        crate::load::test_support::mean(&crate::load::test_support::render(&f, 4096, 2))
    };
    let m = mean(&scene("perspective", 1.0));
    assert!((m - 0.875).abs() < 0.025, "moving sensor: {m}");
    let f = load(&scene("perspective", 0.0)).unwrap();
    assert!(f.scene.motion_shutter().is_some_and(|s| s == (0.0, 0.0)));
    assert_eq!(crate::load::test_support::mean(&crate::load::test_support::render(&f, 64, 1)), 1.0);
    let e = err(&scene("radiancemeter", 1.0));
    assert!(e.contains("test.xml:") && e.contains("radiancemeter cannot move"), "{e}");
}

/// neumann's motion blur in Mitsuba XML: a rectangle with `to_world_end` slides over the
/// shutter (`shutter_open` 0 to `shutter_close` 1) in front of a white emitter and covers the
/// camera's central ray for its share of the time; a shape that does not move may give the same
/// `to_world_end` as its `to_world`; a moving sphere, a moving emitter, an irradiancemeter on
/// a moving shape and `motion_start` without `to_world_end` are errors where they are written.
/// An `instance` with `to_world_end` moves its shapegroup's shapes with it.
#[test]
fn shapes_move_with_to_world_end() {
    let scene = |strip: &str| {
        format!(
            r#"<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="1"/></integrator>
<sensor type="perspective"><float name="fov" value="0.5"/><float name="shutter_close" value="1"/>
<transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
<film type="hdrfilm"><integer name="width" value="1"/><integer name="height" value="1"/></film></sensor>
<shape type="rectangle"><transform name="to_world"><scale value="50"/><rotate y="1" angle="180"/><translate z="10"/></transform>
<emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
{strip}</scene>"#
        )
    };
    let strip = |end: &str, more: &str| {
        format!(
            r#"<shape type="{}"><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
<transform name="to_world"><scale x="0.25" y="4"/><translate x="-2" z="5"/></transform>
<transform name="to_world_end"><scale x="0.25" y="4"/><translate x="{end}" z="5"/></transform>{more}</shape>"#,
            if more.contains("sphere") { "sphere" } else { "rectangle" }
        )
    };
    let mean = |text: &str| {
        let f = load(text).unwrap_or_else(|e| panic!("{e}"));
        crate::load::test_support::mean(&crate::load::test_support::render(&f, 4096, 1))
    };
    let m = mean(&scene(&strip("2", "")));
    assert!((m - 0.875).abs() < 0.025, "{m}");
    // At rest at x = -2: the ray is never covered; and no time is drawn.
    let f = load(&scene(&strip("-2", ""))).unwrap();
    assert!(f.scene.motion_shutter().is_none());
    assert_eq!(crate::load::test_support::mean(&crate::load::test_support::render(&f, 64, 1)), 1.0);
    // With motion_end 2 the strip is halfway when the shutter closes: covered for 1/8 again,
    // at the shutter's end (x from -2 to 0).
    let m = mean(&scene(&strip("2", r#"<float name="motion_end" value="2"/>"#)));
    assert!((m - 0.875).abs() < 0.025, "{m}");
    let e = err(&scene(&strip("2", "<!-- sphere -->")));
    assert!(e.contains("test.xml:") && e.contains("scales unevenly"), "{e}");
    let e = err(&scene(&strip("2", r#"<emitter type="area"/>"#)));
    assert!(e.contains("test.xml:") && e.contains("cannot emit"), "{e}");
    let e = err(&scene(&strip("2", r#"<sensor type="irradiancemeter"><film type="hdrfilm"/></sensor>"#)));
    assert!(e.contains("test.xml:") && e.contains("cannot measure a moving shape"), "{e}");
    let e = err(&scene(r#"<shape type="rectangle"><float name="motion_start" value="0"/></shape>"#));
    assert!(e.contains("motion_start"), "{e}");
    // An instance with `to_world_end` moves its shapegroup's shapes (pbrt-v4's animated
    // instances): the same strip, defined in a shapegroup, slides with its instance.
    let group = |shape: &str, end: &str| {
        format!(
            r#"<shape type="shapegroup" id="g">{shape}</shape>
<shape type="instance"><ref id="g"/><transform name="to_world"><translate x="-2"/></transform>
<transform name="to_world_end"><translate x="{end}"/></transform></shape>"#
        )
    };
    let strip_in_group = r#"<shape type="rectangle"><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
<transform name="to_world"><scale x="0.25" y="4"/><translate z="5"/></transform></shape>"#;
    let m = mean(&scene(&group(strip_in_group, "2")));
    assert!((m - 0.875).abs() < 0.025, "moving instance: {m}");
    let f = load(&scene(&group(strip_in_group, "-2"))).unwrap();
    assert!(f.scene.motion_shutter().is_none(), "an instance at rest draws no time");
    // A sphere of radius 0.25 in the moving instance covers the central ray as the strip does.
    let ball = r#"<shape type="sphere"><float name="radius" value="0.25"/><point name="center" x="0" y="0" z="5"/>
<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></shape>"#;
    let m = mean(&scene(&group(ball, "2")));
    assert!((m - 0.875).abs() < 0.025, "moving sphere in an instance: {m}");
    let e = err(&scene(&group(&strip("2", ""), "2")));
    assert!(e.contains("test.xml:") && e.contains("cannot move by itself"), "{e}");
}
