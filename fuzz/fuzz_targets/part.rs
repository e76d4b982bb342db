//! Parts of split renders (OpenEXR with neumann's header attributes) from arbitrary bytes: read,
//! then merged with themselves and alone (the merge must refuse or merge, never panic).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("neumann-fuzz-part-{}.exr", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        if let Ok(part) = neumann::film::part::read_part(&path) {
            let _ = neumann::film::part::merge_parts(std::slice::from_ref(&part), true);
            let _ = neumann::film::part::merge_parts(&[part.clone(), part], false);
        }
    }
});
