//! Image files as linear RGB: PNG (8- or 16-bit), JPEG, BMP, TGA and binary PPM (sRGB-decoded
//! unless `raw`, as Mitsuba reads them), OpenEXR, Radiance HDR and PFM (float, linear). Used by
//! bitmap textures and environment maps.

use super::{limits, LoadError};
use crate::load::memory::{Channel, EncodedImage};
use crate::math::color::srgb_decode;
use crate::math::Rgb;
use std::path::Path;

pub use crate::image::Image;

/// Loads a `.png` or `.exr` image. 8- and 16-bit PNGs are sRGB-encoded unless `raw` (data such as
/// roughness maps), in which case values are only scaled to [0, 1].
pub fn load_image(path: &Path, raw: bool) -> Result<Image, LoadError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    if matches!(ext.as_deref(), Some("png" | "exr" | "jpg" | "jpeg" | "bmp" | "tga" | "hdr" | "pfm" | "ppm")) {
        // A file that cannot be opened is an I/O error, not a malformed image.
        std::fs::File::open(path).map_err(|e| LoadError::io(path, e))?;
    }
    match ext.as_deref() {
        Some("png") => load_png(path, raw).map_err(|e| LoadError::format(path, e)),
        Some("exr") => load_exr(path).map_err(|e| LoadError::format(path, e)),
        Some("jpg" | "jpeg" | "bmp" | "tga" | "hdr") => load_decoded(path, raw).map_err(|e| LoadError::format(path, e)),
        Some("ppm") => load_ppm(path, raw).map_err(|e| LoadError::format(path, e)),
        Some("pfm") => {
            let (width, height, pixels) =
                crate::film::output::read_pfm(path).map_err(|e| LoadError::format(path, e.to_string()))?;
            Ok(Image { width, height, pixels })
        }
        _ => Err(LoadError::Unsupported {
            path: path.to_path_buf(),
            message: "unsupported image format (expected .png, .exr, .jpg, .bmp, .tga, .hdr, .pfm or .ppm)".into(),
        }),
    }
}

/// Checks a PNG's chunk structure before the decoder sees it: the signature, chunk lengths
/// within the file, a palette of whole RGB triples (at most 256; the `png` crate panics on
/// others) and the size the header claims against [`limits::MAX_IMAGE_PIXELS`].
fn check_png(path: &Path, bytes: &[u8]) -> Result<(), String> {
    const SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";
    let bad = |m: &str| m.to_string();
    if !bytes.starts_with(SIGNATURE) {
        return Err(bad("not a PNG file (no PNG signature)"));
    }
    let mut pos = SIGNATURE.len();
    while pos + 8 <= bytes.len() {
        let len = u32::from_be_bytes(bytes[pos..pos + 4].try_into().expect("4 bytes")) as usize;
        let kind = &bytes[pos + 4..pos + 8];
        let data = pos + 8;
        let Some(end) = data.checked_add(len).filter(|&e| e + 4 <= bytes.len()) else {
            return Err(bad("a PNG chunk runs past the end of the file"));
        };
        match kind {
            b"IHDR" if len >= 8 => {
                let w = u32::from_be_bytes(bytes[data..data + 4].try_into().expect("4 bytes"));
                let h = u32::from_be_bytes(bytes[data + 4..data + 8].try_into().expect("4 bytes"));
                limits::check_image_size(path, w.into(), h.into()).map_err(message)?;
            }
            b"PLTE" if !len.is_multiple_of(3) || len > 768 => {
                return Err(bad(&format!(
                    "the PNG palette has {len} bytes (whole RGB entries, at most 256, are needed)"
                )));
            }
            b"IEND" => break,
            _ => {}
        }
        pos = end + 4;
    }
    Ok(())
}

/// A load error's message without its file (the caller names the file).
fn message(e: LoadError) -> String {
    match e {
        LoadError::Format { message, .. } | LoadError::Unsupported { message, .. } => message,
        LoadError::Io { source, .. } => source.to_string(),
    }
}

fn load_png(path: &Path, raw: bool) -> Result<Image, String> {
    let bytes = limits::read_bounded(path, limits::MAX_FILE_BYTES).map_err(message)?;
    let decoded = decode_png(path, &bytes)?;
    Ok(decoded.image(Channel::Rgb, raw))
}

/// A PNG's values as stored (grey replicated to RGB; alpha 1 where it has none), checked first
/// ([`check_png`]); `path` names it in size-limit messages.
fn decode_png(path: &Path, bytes: &[u8]) -> Result<EncodedImage, String> {
    decode_png_channels(path, bytes).map(|(image, _)| image)
}

/// [`decode_png`] and the file's channel count (1 grey, 2 grey and alpha, 3 RGB, 4 RGBA; a
/// palette counts as RGB, as pbrt-v4 reads palettes: without their transparency).
fn decode_png_channels(path: &Path, bytes: &[u8]) -> Result<(EncodedImage, usize), String> {
    check_png(path, bytes)?;
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| format!("not a readable PNG: {e}"))?;
    // The file's own layout: a palette is RGB (its transparency dropped), as pbrt-v4 reads it.
    let file_channels = match reader.info().color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb | png::ColorType::Indexed => 3,
        png::ColorType::Rgba => 4,
    };
    let mut buf = vec![0u8; reader.output_buffer_size().ok_or("PNG too large")?];
    let info = reader.next_frame(&mut buf).map_err(|e| format!("corrupt PNG data: {e}"))?;
    let (w, h) = (info.width, info.height);
    let channels = info.color_type.samples();
    let sixteen = info.bit_depth == png::BitDepth::Sixteen;
    let sample = |i: usize| -> f32 {
        if sixteen {
            u16::from_be_bytes([buf[2 * i], buf[2 * i + 1]]) as f32 / 65535.0
        } else {
            buf[i] as f32 / 255.0
        }
    };
    let mut rgba = Vec::with_capacity((w * h) as usize);
    for p in 0..(w * h) as usize {
        let base = p * channels;
        rgba.push(match channels {
            1 => {
                let v = sample(base);
                [v, v, v, 1.0]
            }
            2 => [sample(base), sample(base), sample(base), sample(base + 1)],
            3 => [sample(base), sample(base + 1), sample(base + 2), 1.0],
            _ => [sample(base), sample(base + 1), sample(base + 2), sample(base + 3)],
        });
    }
    Ok((EncodedImage { width: w, height: h, rgba, linear: false }, file_channels))
}

/// An image read as pbrt-v4 reads a float image texture (its `MIPMap` of the file): one value
/// per pixel, in every channel of the result — the alpha of an RGBA file whose alpha is not 1
/// everywhere, else the mean of its red, green and blue, else its one grey channel (a grey PNG
/// with alpha is read as grey: pbrt-v4 drops that alpha). `decode` maps the stored 8- and 16-bit
/// values to linear ones (pbrt-v4's encoding: sRGB, linear or a gamma), alpha included, as
/// pbrt-v4 decodes every channel of such images; float files (EXR, HDR, PFM) are linear, an
/// EXR's alpha read by the same rule (HDR and PFM files have none).
pub fn load_pbrt_scalar(path: &Path, decode: &dyn Fn(f32) -> f32) -> Result<Image, LoadError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    let (width, height, channels, rgba) = match ext.as_deref() {
        Some("png") => {
            let bytes = limits::read_bounded(path, limits::MAX_FILE_BYTES)?;
            let (image, channels) = decode_png_channels(path, &bytes).map_err(|e| LoadError::format(path, e))?;
            (image.width, image.height, channels, image.rgba)
        }
        Some("jpg" | "jpeg" | "bmp" | "tga") => {
            std::fs::File::open(path).map_err(|e| LoadError::io(path, e))?;
            let decoded = image::ImageReader::open(path)
                .and_then(|r| r.with_guessed_format())
                .map_err(|e| LoadError::format(path, format!("cannot read: {e}")))?
                .decode()
                .map_err(|e| LoadError::format(path, format!("not a readable image: {e}")))?;
            let channels = decoded.color().channel_count() as usize;
            let rgba = decoded.to_rgba32f();
            (rgba.width(), rgba.height(), channels, rgba.pixels().map(|p| p.0).collect())
        }
        Some("exr") => {
            let (w, h, rgba) =
                load_exr_pixels(path, |r, g, b, a| [r, g, b, a]).map_err(|e| LoadError::format(path, e))?;
            // Linear floats: `decode` (for 8- and 16-bit values) does not apply.
            let alpha = rgba.iter().any(|p| p[3] != 1.0);
            let pixels =
                rgba.iter().map(|p| Rgb::splat(if alpha { p[3] } else { (p[0] + p[1] + p[2]) / 3.0 })).collect();
            return Ok(Image { width: w, height: h, pixels });
        }
        _ => {
            let rgb = load_image(path, true)?;
            let pixels = rgb.pixels.iter().map(|c| Rgb::splat((c.x + c.y + c.z) / 3.0)).collect();
            return Ok(Image { width: rgb.width, height: rgb.height, pixels });
        }
    };
    let alpha = channels == 4 && rgba.iter().any(|p| decode(p[3]) != 1.0);
    let pixels = rgba
        .iter()
        .map(|p| {
            Rgb::splat(match channels {
                _ if alpha => decode(p[3]),
                1 | 2 => decode(p[0]),
                _ => (decode(p[0]) + decode(p[1]) + decode(p[2])) / 3.0,
            })
        })
        .collect();
    Ok(Image { width, height, pixels })
}

/// An 8- or 16-bit PNG or JPEG held in memory (glTF's images), as stored: sRGB values not yet
/// decoded, with alpha. `name` names it in messages.
pub fn decode_encoded(name: &Path, bytes: &[u8]) -> Result<EncodedImage, String> {
    if bytes.starts_with(b"\x89PNG") {
        return decode_png(name, bytes);
    }
    if !bytes.starts_with(&[0xFF, 0xD8]) {
        return Err("not a PNG or JPEG image (the formats glTF allows)".into());
    }
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes));
    reader.set_format(image::ImageFormat::Jpeg);
    let (w, h) = reader.into_dimensions().map_err(|e| format!("not a readable JPEG: {e}"))?;
    limits::check_image_size(name, w.into(), h.into()).map_err(message)?;
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes));
    reader.set_format(image::ImageFormat::Jpeg);
    let decoded = reader.decode().map_err(|e| format!("not a readable JPEG: {e}"))?.to_rgba32f();
    let rgba = decoded.pixels().map(|p| p.0).collect();
    Ok(EncodedImage { width: decoded.width(), height: decoded.height(), rgba, linear: false })
}

/// JPEG, BMP, TGA (8-bit, sRGB-encoded unless `raw`, as Mitsuba reads them) and Radiance HDR
/// (RGBE, linear), through the `image` crate's decoders (which bound their allocations).
fn load_decoded(path: &Path, raw: bool) -> Result<Image, String> {
    let reader = image::ImageReader::open(path)
        .map_err(|e| format!("cannot open: {e}"))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read: {e}"))?;
    decode_rgb(reader, raw)
}

/// The image `reader` decodes, as linear RGB: 8- and 16-bit samples sRGB-decoded unless `raw`,
/// float samples as they are.
fn decode_rgb<R: std::io::BufRead + std::io::Seek>(reader: image::ImageReader<R>, raw: bool) -> Result<Image, String> {
    let decoded = reader.decode().map_err(|e| format!("not a readable image: {e}"))?;
    let linear = matches!(decoded, image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_));
    let rgb = decoded.to_rgb32f();
    let decode = |v: f32| if raw || linear { v } else { srgb_decode(v) };
    let pixels = rgb.pixels().map(|p| Rgb::new(decode(p[0]), decode(p[1]), decode(p[2]))).collect();
    Ok(Image { width: rgb.width(), height: rgb.height(), pixels })
}

/// A binary PPM (`P6`, 8 or 16 bits per sample, the latter most significant byte first as the
/// format defines it), sRGB-decoded unless `raw`, as Mitsuba reads PPM files; Mitsuba reads no
/// other kind of PNM (ASCII `P3`, grey `P5`, …), and neither does neumann.
fn load_ppm(path: &Path, raw: bool) -> Result<Image, String> {
    let bytes = limits::read_bounded(path, limits::MAX_FILE_BYTES).map_err(message)?;
    if !bytes.starts_with(b"P6") {
        let magic = String::from_utf8_lossy(&bytes[..bytes.len().min(2)]).into_owned();
        return Err(format!("not a binary PPM (its magic number is \"{magic}\"; Mitsuba reads only \"P6\")"));
    }
    // Decoded from the bytes already read (not a second read of the file).
    decode_rgb(image::ImageReader::with_format(std::io::Cursor::new(&bytes[..]), image::ImageFormat::Pnm), raw)
}

fn load_exr(path: &Path) -> Result<crate::load::image::Image, String> {
    let (width, height, pixels) = load_exr_pixels(path, |r, g, b, _| Rgb::new(r, g, b))?;
    Ok(Image { width, height, pixels })
}

/// The first RGBA layer of an OpenEXR file: width, height and each pixel made by `pixel` from
/// its red, green, blue and alpha (1 where the file has no alpha channel), row by row from the
/// top.
fn load_exr_pixels<T: Clone + 'static>(
    path: &Path,
    pixel: fn(f32, f32, f32, f32) -> T,
) -> Result<(u32, u32, Vec<T>), String> {
    use exr::prelude::*;
    // The sizes the header claims, checked before any pixel memory is allocated.
    let meta =
        exr::meta::MetaData::read_from_file(path, false).map_err(|e| format!("not a readable OpenEXR file: {e}"))?;
    for header in &meta.headers {
        let size = header.layer_size;
        limits::check_image_size(path, size.width() as u64, size.height() as u64).map_err(message)?;
    }
    crate::image::exr_chunks_fit(path)?;
    let image = read_first_rgba_layer_from_file(
        path,
        move |resolution, _| {
            (resolution.width(), vec![pixel(0.0, 0.0, 0.0, 1.0); resolution.width() * resolution.height()])
        },
        move |(width, px): &mut (usize, Vec<T>), pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * *width + pos.x()] = pixel(r, g, b, a);
        },
    )
    .map_err(|e| format!("not a readable OpenEXR file: {e}"))?;
    let size = image.layer_data.size;
    Ok((size.width() as u32, size.height() as u32, image.layer_data.channel_data.pixels.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A PNG of `w × h` pixels of `channels` 8-bit samples each (1 grey, 2 grey and alpha, 3
    /// RGB, 4 RGBA).
    fn png_bytes(w: u32, h: u32, channels: usize, samples: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, w, h);
            enc.set_color(match channels {
                1 => png::ColorType::Grayscale,
                2 => png::ColorType::GrayscaleAlpha,
                3 => png::ColorType::Rgb,
                _ => png::ColorType::Rgba,
            });
            enc.set_depth(png::BitDepth::Eight);
            enc.write_header().unwrap().write_image_data(samples).unwrap();
        }
        out
    }

    /// pbrt-v4's float image textures: an RGBA file's alpha where it is not 1 everywhere
    /// (decoded like the colour, as pbrt-v4 decodes every channel of 8-bit images), else the
    /// mean of the colour — not its luminance —, a grey file's grey (its alpha dropped, as pbrt
    /// reads grey PNGs); linear where asked.
    #[test]
    fn pbrt_scalar_images() {
        let dir = std::env::temp_dir().join(format!("neumann-pbrt-scalar-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let read = |name: &str, channels: usize, samples: &[u8], raw: bool| {
            let path = dir.join(name);
            std::fs::write(&path, png_bytes(2, 1, channels, samples)).unwrap();
            let decode = |v: f32| if raw { v } else { srgb_decode(v) };
            load_pbrt_scalar(&path, &decode).unwrap().pixels.iter().map(|c| c.x).collect::<Vec<f32>>()
        };
        let d = |b: u8| srgb_decode(b as f32 / 255.0);
        let close = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6);
        let cut = read("cut.png", 4, &[255, 0, 0, 128, 0, 255, 0, 255], false);
        assert!(close(&cut, &[d(128), 1.0]), "{cut:?}");
        let cut_raw = read("cut.png", 4, &[255, 0, 0, 128, 0, 255, 0, 255], true);
        assert!(close(&cut_raw, &[128.0 / 255.0, 1.0]), "{cut_raw:?}");
        let opaque = read("opaque.png", 4, &[255, 0, 0, 255, 0, 51, 204, 255], false);
        assert!(close(&opaque, &[1.0 / 3.0, (d(51) + d(204)) / 3.0]), "{opaque:?}");
        let rgb = read("rgb.png", 3, &[255, 0, 0, 10, 20, 30], true);
        assert!(close(&rgb, &[1.0 / 3.0, 20.0 / 255.0]), "{rgb:?}");
        let grey_alpha = read("ga.png", 2, &[100, 0, 200, 50], true);
        assert!(close(&grey_alpha, &[100.0 / 255.0, 200.0 / 255.0]), "{grey_alpha:?}");
        // A palette with transparency: its colours' mean, the transparency dropped (pbrt-v4).
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, 2, 1);
            enc.set_color(png::ColorType::Indexed);
            enc.set_depth(png::BitDepth::Eight);
            enc.set_palette(vec![30u8, 60, 90, 255, 255, 255]);
            enc.set_trns(vec![10u8, 255]);
            enc.write_header().unwrap().write_image_data(&[0, 1]).unwrap();
        }
        std::fs::write(dir.join("palette.png"), out).unwrap();
        let palette = load_pbrt_scalar(&dir.join("palette.png"), &|v| v).unwrap();
        assert!(close(&[palette.pixels[0].x, palette.pixels[1].x], &[60.0 / 255.0, 1.0]), "{:?}", palette.pixels);
        // OpenEXR: linear, never decoded; the alpha where it is not 1 everywhere, else the mean.
        let exr = |name: &str, px: [[f32; 4]; 2]| {
            let path = dir.join(name);
            exr::prelude::write_rgba_file(&path, 2, 1, |x, _| (px[x][0], px[x][1], px[x][2], px[x][3])).unwrap();
            load_pbrt_scalar(&path, &|v| v * 100.0).unwrap().pixels.iter().map(|c| c.x).collect::<Vec<f32>>()
        };
        let cut = exr("cut.exr", [[0.2, 0.4, 0.6, 0.25], [3.0, 0.0, 0.0, 1.0]]);
        assert!(close(&cut, &[0.25, 1.0]), "{cut:?}");
        let opaque = exr("opaque.exr", [[0.2, 0.4, 0.6, 1.0], [3.0, 0.0, 0.0, 1.0]]);
        assert!(close(&opaque, &[0.4, 1.0]), "{opaque:?}");
        // Without an alpha channel at all: the mean.
        let path = dir.join("rgb.exr");
        let colour = |x: usize| if x == 0 { (0.2f32, 0.4f32, 0.6f32) } else { (3.0, 0.0, 0.0) };
        exr::prelude::write_rgb_file(&path, 2, 1, |x, _| colour(x)).unwrap();
        let rgb = load_pbrt_scalar(&path, &|v| v).unwrap().pixels.iter().map(|c| c.x).collect::<Vec<f32>>();
        assert!(close(&rgb, &[0.4, 1.0]), "{rgb:?}");
    }
    use crate::film::output::{write_image, ImageInfo};

    /// An OpenEXR chunk that declares more bytes than the file holds is refused before the
    /// decoder allocates them (a 2×2 image whose first chunk claims a gigabyte; the intact file
    /// loads); a chunk offset past the end of the file too.
    #[test]
    fn exr_chunks_larger_than_the_file_are_errors() {
        let dir = std::env::temp_dir().join(format!("neumann-img-chunk-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("ok.exr");
        let px = vec![Rgb::new(0.25, 2.0, 0.0); 4];
        write_image(&path, 2, 2, &px, &ImageInfo::default()).unwrap();
        assert!(load_image(&path, false).is_ok());
        let bytes = std::fs::read(&path).unwrap();
        // The first chunk's offset, read as the decoder reads it.
        let mut read = exr::io::PeekRead::new(std::io::Cursor::new(&bytes));
        exr::meta::magic_number::validate_exr(&mut read).unwrap();
        let requirements = exr::meta::Requirements::read(&mut read).unwrap();
        let headers = exr::meta::header::Header::read_all(&mut read, &requirements, false).unwrap();
        let tables = exr::meta::MetaData::read_offset_tables(&mut read, &headers).unwrap();
        let first = tables[0][0] as usize;
        // The byte count (i32) after the block's coordinates: a tile's four, a scan line's y.
        let at = first + if matches!(headers[0].blocks, exr::meta::BlockDescription::Tiles(_)) { 16 } else { 4 };
        let mut huge = bytes.clone();
        huge[at..at + 4].copy_from_slice(&1_000_000_000i32.to_le_bytes());
        std::fs::write(dir.join("huge.exr"), &huge).unwrap();
        let e = load_image(&dir.join("huge.exr"), false).unwrap_err().to_string();
        assert!(e.contains("declares 1000000000 bytes"), "{e}");
        let mut negative = bytes.clone();
        negative[at..at + 4].copy_from_slice(&(-7i32).to_le_bytes());
        std::fs::write(dir.join("negative.exr"), &negative).unwrap();
        let e = load_image(&dir.join("negative.exr"), false).unwrap_err().to_string();
        assert!(e.contains("declares a negative size (-7 bytes)"), "{e}");
        let mut far = bytes.clone();
        let table_at = first - 8 * tables[0].len();
        far[table_at..table_at + 8].copy_from_slice(&(1u64 << 40).to_le_bytes());
        std::fs::write(dir.join("far.exr"), &far).unwrap();
        let e = load_image(&dir.join("far.exr"), false).unwrap_err().to_string();
        assert!(e.contains("beyond the file"), "{e}");
    }

    #[test]
    fn exr_and_png_round_trip() {
        let dir = std::env::temp_dir().join(format!("neumann-img-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let px =
            vec![Rgb::new(0.25, 2.0, 0.0), Rgb::new(0.5, 0.1, 1.0), Rgb::new(0.0, 0.0, 0.0), Rgb::new(8.0, 1.0, 0.3)];
        write_image(&dir.join("a.exr"), 2, 2, &px, &ImageInfo::default()).unwrap();
        let back = load_image(&dir.join("a.exr"), false).unwrap();
        assert_eq!((back.width, back.height), (2, 2));
        assert_eq!(back.pixels, px);
        write_image(&dir.join("a.png"), 2, 2, &px, &ImageInfo::default()).unwrap();
        let png = load_image(&dir.join("a.png"), false).unwrap();
        // 8-bit sRGB round trip: within quantization, clamped to [0, 1].
        for (a, b) in png.pixels.iter().zip(&px) {
            assert!((*a - b.clamp(Rgb::ZERO, Rgb::ONE)).abs().max_element() < 0.01, "{a} vs {b}");
        }
        let missing = load_image(&dir.join("missing.png"), false).unwrap_err();
        assert!(matches!(missing, LoadError::Io { .. }) && missing.to_string().contains("missing.png"), "{missing}");
        let gif = load_image(&dir.join("a.gif"), false).unwrap_err();
        assert!(matches!(gif, LoadError::Unsupported { .. }) && gif.to_string().contains("a.gif"), "{gif}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Hostile images are errors before any large allocation or a decoder panic: a PNG whose
    /// palette is not whole RGB triples (the `png` crate panicked), PNG and EXR headers that
    /// claim 100000² pixels, a truncated chunk, a device instead of a file.
    #[test]
    fn hostile_images_are_refused() {
        let dir = std::env::temp_dir().join(format!("neumann-img-hostile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let chunk = |kind: &[u8], data: &[u8]| {
            let mut c = (data.len() as u32).to_be_bytes().to_vec();
            c.extend(kind);
            c.extend(data);
            c.extend([0u8; 4]); // CRC (never reached)
            c
        };
        let png = |w: u32, h: u32, colour: u8, extra: Vec<u8>| {
            let mut ihdr = w.to_be_bytes().to_vec();
            ihdr.extend(h.to_be_bytes());
            ihdr.extend([8, colour, 0, 0, 0]);
            let mut f = b"\x89PNG\r\n\x1a\n".to_vec();
            f.extend(chunk(b"IHDR", &ihdr));
            f.extend(extra);
            f.extend(chunk(b"IDAT", &[0; 8]));
            f.extend(chunk(b"IEND", &[]));
            f
        };
        std::fs::write(dir.join("palette.png"), png(4, 4, 3, chunk(b"PLTE", &[1, 2, 3, 4]))).unwrap();
        std::fs::write(dir.join("huge.png"), png(100_000, 100_000, 2, Vec::new())).unwrap();
        let mut cut = png(4, 4, 2, Vec::new());
        cut.truncate(30);
        std::fs::write(dir.join("cut.png"), cut).unwrap();
        // A 1×1 EXR whose data and display windows are patched to claim 100000².
        write_image(&dir.join("one.exr"), 1, 1, &[Rgb::ONE], &ImageInfo::default()).unwrap();
        let mut exr = std::fs::read(dir.join("one.exr")).unwrap();
        for name in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
            let at = exr.windows(name.len()).position(|w| w == name).unwrap() + name.len() + 4;
            exr[at + 8..at + 12].copy_from_slice(&99_999i32.to_le_bytes());
            exr[at + 12..at + 16].copy_from_slice(&99_999i32.to_le_bytes());
        }
        std::fs::write(dir.join("huge.exr"), exr).unwrap();
        for (file, expectation) in [
            ("palette.png", "palette has 4 bytes"),
            ("huge.png", "more than the limit"),
            ("cut.png", "runs past the end"),
            ("huge.exr", "more than the limit"),
        ] {
            let e = load_image(&dir.join(file), false).unwrap_err().to_string();
            assert!(e.contains(file) && e.contains(expectation), "expected '{expectation}' in: {e}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// JPEG, BMP, TGA and HDR files decode to linear RGB (8-bit formats through the sRGB curve
    /// unless `raw`; HDR as stored), and PFM through the film's reader.
    #[test]
    fn other_formats_decode_to_linear_rgb() {
        let dir = std::env::temp_dir().join(format!("neumann-img-formats-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bytes: [u8; 12] = [255, 0, 0, 0, 128, 0, 0, 0, 255, 188, 188, 188];
        let rgb8 = image::RgbImage::from_raw(2, 2, bytes.to_vec()).unwrap();
        // JPEG is lossy (and subsamples chroma): a flat colour survives it.
        let flat = image::RgbImage::from_fn(16, 16, |_, _| image::Rgb([200, 120, 60]));
        flat.save(dir.join("flat.jpg")).unwrap();
        let (img, raw) =
            (load_image(&dir.join("flat.jpg"), false).unwrap(), load_image(&dir.join("flat.jpg"), true).unwrap());
        for c in 0..3 {
            let v = [200.0f32, 120.0, 60.0][c] / 255.0;
            assert!((raw.pixels[37][c] - v).abs() < 0.02 && (img.pixels[37][c] - srgb_decode(v)).abs() < 0.02);
        }
        for name in ["a.bmp", "a.tga"] {
            rgb8.save(dir.join(name)).unwrap();
            let img = load_image(&dir.join(name), false).unwrap();
            let raw = load_image(&dir.join(name), true).unwrap();
            assert_eq!((img.width, img.height), (2, 2), "{name}");
            let tol = 1e-6;
            for (k, (p, q)) in img.pixels.iter().zip(&raw.pixels).enumerate() {
                for c in 0..3 {
                    let v = bytes[3 * k + c] as f32 / 255.0;
                    assert!((q[c] - v).abs() <= tol, "{name} raw pixel {k}: {} vs {v}", q[c]);
                    assert!((p[c] - srgb_decode(q[c])).abs() <= 1e-6, "{name} pixel {k}: sRGB-decoded");
                }
            }
        }
        // Binary PPM, 8-bit and 16-bit (big-endian samples); an ASCII one is refused, as by Mitsuba.
        let mut ppm = b"P6\n2 2\n255\n".to_vec();
        ppm.extend_from_slice(&bytes);
        std::fs::write(dir.join("a.ppm"), &ppm).unwrap();
        let (img, raw) =
            (load_image(&dir.join("a.ppm"), false).unwrap(), load_image(&dir.join("a.ppm"), true).unwrap());
        for (k, (p, q)) in img.pixels.iter().zip(&raw.pixels).enumerate() {
            for c in 0..3 {
                let v = bytes[3 * k + c] as f32 / 255.0;
                assert!((q[c] - v).abs() <= 1e-6 && (p[c] - srgb_decode(v)).abs() <= 1e-6, "ppm pixel {k}");
            }
        }
        let mut ppm16 = b"P6 1 1 65535\n".to_vec();
        ppm16.extend_from_slice(&[0x80, 0x00, 0xff, 0xff, 0x00, 0x01]);
        std::fs::write(dir.join("b.ppm"), &ppm16).unwrap();
        let q = load_image(&dir.join("b.ppm"), true).unwrap().pixels[0];
        assert!((q - Rgb::new(32768.0 / 65535.0, 1.0, 1.0 / 65535.0)).abs().max_element() < 1e-6, "{q}");
        std::fs::write(dir.join("c.ppm"), b"P3\n1 1\n255\n1 2 3\n").unwrap();
        let e = load_image(&dir.join("c.ppm"), false).unwrap_err().to_string();
        assert!(e.contains("c.ppm") && e.contains("P6"), "{e}");
        let hdr = image::Rgb32FImage::from_raw(1, 1, vec![4.0, 0.5, 0.25]).unwrap();
        image::DynamicImage::ImageRgb32F(hdr).save(dir.join("a.hdr")).unwrap();
        let img = load_image(&dir.join("a.hdr"), false).unwrap();
        assert!((img.pixels[0] - Rgb::new(4.0, 0.5, 0.25)).abs().max_element() < 0.02, "{:?}", img.pixels[0]);
        let px = [Rgb::new(3.0, 0.25, 1e-3), Rgb::new(0.0, 7.5, 2.0)];
        write_image(&dir.join("a.pfm"), 2, 1, &px, &ImageInfo::default()).unwrap();
        assert_eq!(load_image(&dir.join("a.pfm"), false).unwrap().pixels, px);
        std::fs::write(dir.join("bad.jpg"), b"not a jpeg").unwrap();
        assert!(matches!(load_image(&dir.join("bad.jpg"), false), Err(LoadError::Format { .. })));
        std::fs::remove_dir_all(&dir).ok();
    }
}
