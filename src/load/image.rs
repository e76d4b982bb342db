//! Image files as linear RGB: PNG (8- or 16-bit), JPEG, BMP and TGA (sRGB-decoded unless `raw`,
//! as Mitsuba reads them), OpenEXR, Radiance HDR and PFM (float, linear). Used by bitmap textures
//! and environment maps.

use super::LoadError;
use crate::math::color::srgb_decode;
use crate::math::Rgb;
use std::path::Path;

pub use crate::image::Image;

/// Loads a `.png` or `.exr` image. 8- and 16-bit PNGs are sRGB-encoded unless `raw` (data such as
/// roughness maps), in which case values are only scaled to [0, 1].
pub fn load_image(path: &Path, raw: bool) -> Result<Image, LoadError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    if matches!(ext.as_deref(), Some("png" | "exr" | "jpg" | "jpeg" | "bmp" | "tga" | "hdr" | "pfm")) {
        // A file that cannot be opened is an I/O error, not a malformed image.
        std::fs::File::open(path).map_err(|e| LoadError::io(path, e))?;
    }
    match ext.as_deref() {
        Some("png") => load_png(path, raw).map_err(|e| LoadError::format(path, e)),
        Some("exr") => load_exr(path).map_err(|e| LoadError::format(path, e)),
        Some("jpg" | "jpeg" | "bmp" | "tga" | "hdr") => load_decoded(path, raw).map_err(|e| LoadError::format(path, e)),
        Some("pfm") => {
            let (width, height, pixels) =
                crate::film::output::read_pfm(path).map_err(|e| LoadError::format(path, e.to_string()))?;
            Ok(Image { width, height, pixels })
        }
        _ => Err(LoadError::Unsupported {
            path: path.to_path_buf(),
            message: "unsupported image format (expected .png, .exr, .jpg, .bmp, .tga, .hdr or .pfm)".into(),
        }),
    }
}

fn load_png(path: &Path, raw: bool) -> Result<Image, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| format!("not a readable PNG: {e}"))?;
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
    let decode = |v: f32| if raw { v } else { srgb_decode(v) };
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for p in 0..(w * h) as usize {
        let base = p * channels;
        let c = match channels {
            1 | 2 => Rgb::splat(decode(sample(base))),
            _ => Rgb::new(decode(sample(base)), decode(sample(base + 1)), decode(sample(base + 2))),
        };
        pixels.push(c);
    }
    Ok(Image { width: w, height: h, pixels })
}

/// JPEG, BMP, TGA (8-bit, sRGB-encoded unless `raw`, as Mitsuba reads them) and Radiance HDR
/// (RGBE, linear), through the `image` crate's decoders (which bound their allocations).
fn load_decoded(path: &Path, raw: bool) -> Result<Image, String> {
    let decoded = image::ImageReader::open(path)
        .map_err(|e| format!("cannot open: {e}"))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read: {e}"))?
        .decode()
        .map_err(|e| format!("not a readable image: {e}"))?;
    let linear = matches!(decoded, image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_));
    let rgb = decoded.to_rgb32f();
    let decode = |v: f32| if raw || linear { v } else { srgb_decode(v) };
    let pixels = rgb.pixels().map(|p| Rgb::new(decode(p[0]), decode(p[1]), decode(p[2]))).collect();
    Ok(Image { width: rgb.width(), height: rgb.height(), pixels })
}

fn load_exr(path: &Path) -> Result<crate::load::image::Image, String> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |resolution, _| crate::load::image::Image {
            width: resolution.width() as u32,
            height: resolution.height() as u32,
            pixels: vec![Rgb::ZERO; resolution.width() * resolution.height()],
        },
        |img: &mut crate::load::image::Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            img.pixels[pos.y() * img.width as usize + pos.x()] = Rgb::new(r, g, b);
        },
    )
    .map_err(|e| format!("not a readable OpenEXR file: {e}"))?;
    Ok(image.layer_data.channel_data.pixels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::output::{write_image, ImageInfo};

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
