//! With the `oidn` feature, the binaries find Open Image Denoise where `OIDN_DIR` points (e.g.
//! the library inside PyPI's `pyoidn` wheel) without `LD_LIBRARY_PATH`: its `lib` folder goes
//! into their run-time search path. Without the feature this does nothing.

fn main() {
    println!("cargo:rerun-if-env-changed=OIDN_DIR");
    if std::env::var_os("CARGO_FEATURE_OIDN").is_none() {
        return;
    }
    if let Some(dir) = std::env::var_os("OIDN_DIR") {
        let lib = std::path::Path::new(&dir).join("lib");
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", lib.display());
    }
}
