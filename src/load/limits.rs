//! Resource limits that a hostile file cannot exceed: how large a file neumann reads, how many
//! pixels an image may claim before anything is allocated for it, how deep and how many scene
//! files may include one another, and how deeply objects may nest.
//!
//! The limits are far above real scenes (a 16k × 16k environment map, a 4 GiB mesh) and turn a
//! tiny file that claims a huge size into an error naming the limit.

use super::LoadError;
use std::io::Read;
use std::path::Path;

/// The largest file read (bytes): 4 GiB.
pub const MAX_FILE_BYTES: u64 = 4 << 30;
/// The most pixels one image may have: 2²⁸ (a 16k × 16k map), 3 GiB as linear RGB.
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;
/// Scene files one scene may include, all levels together.
pub const MAX_INCLUDES: usize = 1024;
/// Bytes of scene text (the main file and its includes) one scene may have: 1 GiB.
pub const MAX_SCENE_BYTES: usize = 1 << 30;
/// The most numbers one glTF accessor may hold (2²⁸: 1 GiB as f32 during loading).
pub const MAX_ACCESSOR_VALUES: usize = 1 << 28;
/// How deeply objects may nest in a scene file.
pub const MAX_NESTING: usize = 128;
/// Texture attributes one shape may carry: each may read another, so this bounds how deep a
/// lookup recurses (chain × texture nesting) and keeps the per-shape checks small.
pub const MAX_TEXTURE_ATTRIBUTES: usize = 16;

/// The bytes of the regular file `path`, if it is at most `max` bytes. Devices, pipes and
/// folders are refused before reading (`/dev/zero` would never end).
pub fn read_bounded(path: &Path, max: u64) -> Result<Vec<u8>, LoadError> {
    let meta = std::fs::metadata(path).map_err(|e| LoadError::io(path, e))?;
    if !meta.is_file() {
        return Err(LoadError::format(path, "not a regular file"));
    }
    if meta.len() > max {
        return Err(LoadError::format(path, format!("the file has {} bytes, more than the limit of {max}", meta.len())));
    }
    let file = std::fs::File::open(path).map_err(|e| LoadError::io(path, e))?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(max + 1).read_to_end(&mut bytes).map_err(|e| LoadError::io(path, e))?;
    if bytes.len() as u64 > max {
        return Err(LoadError::format(path, format!("the file grew past the limit of {max} bytes while read")));
    }
    Ok(bytes)
}

/// [`read_bounded`] with the default limit, as UTF-8 text; invalid UTF-8 is an error at the
/// line and column of the first bad byte.
pub fn read_text(path: &Path) -> Result<String, LoadError> {
    let bytes = read_bounded(path, MAX_FILE_BYTES)?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = valid.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = valid.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
        let byte = e.as_bytes()[valid.len()];
        LoadError::Format {
            path: path.to_path_buf(),
            line: Some(line),
            message: format!("column {column}: not UTF-8 text (byte 0x{byte:02x}); is this a binary file?"),
        }
    })
}

/// Refuses an image of `width × height` pixels above [`MAX_IMAGE_PIXELS`] (before decoding).
pub fn check_image_size(path: &Path, width: u64, height: u64) -> Result<(), LoadError> {
    match width.checked_mul(height) {
        Some(n) if n <= MAX_IMAGE_PIXELS => Ok(()),
        _ => Err(LoadError::format(
            path,
            format!("the image claims {width} × {height} pixels, more than the limit of {MAX_IMAGE_PIXELS}"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_large_files_and_binary_text_are_refused() {
        let e = read_bounded(Path::new("/dev/zero"), MAX_FILE_BYTES).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
        let dir = std::env::temp_dir().join(format!("neumann-limits-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("ten"), [b'a'; 10]).unwrap();
        assert!(read_bounded(&dir.join("ten"), 9).unwrap_err().to_string().contains("more than the limit of 9"));
        assert_eq!(read_bounded(&dir.join("ten"), 10).unwrap().len(), 10);
        std::fs::write(dir.join("bin"), b"<scene>\n  ab\xffcd").unwrap();
        let e = read_text(&dir.join("bin")).unwrap_err().to_string();
        assert!(e.contains("bin:2: column 5: not UTF-8 text (byte 0xff)"), "{e}");
        assert!(check_image_size(Path::new("x.png"), 100_000, 100_000).is_err());
        assert!(check_image_size(Path::new("x.png"), u64::MAX, 2).is_err());
        assert!(check_image_size(Path::new("x.png"), 16384, 16384).is_ok());
        std::fs::remove_dir_all(&dir).ok();
    }
}
