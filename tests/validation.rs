//! neumann against Mitsuba 3 on every scene with a committed reference (see src/validate.rs and
//! tools/mitsuba/references.py): at equal spp, relMSE ≤ the scene's bound × Mitsuba's (1.5; tighter
//! where an issue asked for it, e.g. 1.2 on the small-light scenes) and the image mean within 0.5 %
//! of the reference.

use neumann::validate::{read_references, validate};
use std::path::Path;

#[test]
fn every_scene_agrees_with_mitsuba() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let refs = read_references(&root.join("references")).expect("references.csv");
    assert!(refs.len() >= 11, "expected the 3 shared and 8 own scenes, found {}", refs.len());
    let mut report = Vec::new();
    for r in &refs {
        let v = validate(&root.join("scenes"), &root.join("references"), r, 0).expect("renders");
        report.push(format!(
            "{:<16} relMSE {:.4e} vs Mitsuba {:.4e} (×{:.3}, bound ×{}), mean diff {:+.3} %",
            r.scene,
            v.relmse,
            r.mitsuba_relmse,
            v.relmse_ratio(),
            r.max_relmse_ratio,
            100.0 * v.mean_difference()
        ));
        if !v.passed() {
            panic!("{} failed validation:\n{}", r.scene, report.join("\n"));
        }
    }
    println!("{}", report.join("\n"));
}
