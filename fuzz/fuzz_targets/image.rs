//! Images (PNG, EXR, JPEG, BMP, TGA, HDR, PFM) from arbitrary bytes: the first byte picks the
//! format, the rest is the file (written to a temporary file, as the loaders read files).
#![no_main]
use libfuzzer_sys::fuzz_target;

const EXTENSIONS: [&str; 7] = ["png", "exr", "jpg", "bmp", "tga", "hdr", "pfm"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else { return };
    let ext = EXTENSIONS[pick as usize % EXTENSIONS.len()];
    let path = std::env::temp_dir().join(format!("neumann-fuzz-{}.{ext}", std::process::id()));
    if std::fs::write(&path, body).is_ok() {
        let _ = neumann::load::image::load_image(&path, pick & 0x80 != 0);
    }
});
