//! Mitsuba tensor files (measured BSDFs' `.bsdf`) from arbitrary bytes: parsed, and where they
//! parse, built into a measured BSDF that is then evaluated, its density taken and sampled.
#![no_main]
use libfuzzer_sys::fuzz_target;
use neumann::material::{BsdfContext, Measured};
use neumann::math::{Vec2, Vec3};

fuzz_target!(|data: &[u8]| {
    let Ok(file) = neumann::load::tensor_file::parse_tensor_file(data) else { return };
    let Ok(m) = Measured::from_tensor_file(&file) else { return };
    let ctx = BsdfContext::default();
    for (wo, wi) in [
        (Vec3::new(0.3, 0.2, 0.93), Vec3::new(-0.25, -0.2, 0.947)),
        (Vec3::new(-0.8, 0.15, 0.45), Vec3::new(0.7, 0.6, 0.2)),
        (Vec3::Z, Vec3::new(0.1, -0.5, 0.7)),
    ] {
        let (wo, wi) = (wo.normalize(), wi.normalize());
        let _ = (m.eval(&ctx, wo, wi), m.pdf(&ctx, wo, wi));
        let _ = m.sample(&ctx, wo, Vec2::new(0.3, 0.7));
    }
});
