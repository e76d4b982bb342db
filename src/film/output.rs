//! Image files: OpenEXR (float32 — or float16, uint32 — RGB or RGBA, linear, plus any named AOV channels such as
//! `albedo.R` or `m2__arg_0.X`), PNG (8-bit sRGB-encoded, with exposure; RGB or RGBA) and PFM
//! (float32 RGB, linear), chosen by the file extension.

use crate::math::color::{luminance, srgb_encode, srgb_to_xyz};
use crate::math::Rgb;
use std::path::{Path, PathBuf};

/// Information stored alongside the pixels.
#[derive(Clone, Debug, Default)]
pub struct ImageInfo {
    /// Samples per pixel actually rendered (written to the EXR header as `spp`).
    pub spp: u32,
    /// Exposure in stops applied when writing 8-bit formats (`× 2^exposure`).
    pub exposure: f32,
    /// What the colour channels hold (the film's `pixel_format`).
    pub colors: ColorChannels,
    /// The number type of an EXR's channels (the film's `component_format`).
    pub component: ComponentFormat,
}

/// The number type of every channel of a written EXR: Mitsuba's `component_format`. PNG (8-bit
/// sRGB) and PFM (float32) have their own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ComponentFormat {
    /// 32-bit floats (`float32`, the default).
    #[default]
    Float32,
    /// 16-bit floats (`float16`): values beyond the largest half float (65504) are written as
    /// that largest value, not as infinity (which Mitsuba writes).
    Float16,
    /// 32-bit unsigned integers (`uint32`), as Mitsuba converts to them: each value clamped to
    /// [0, 1] and scaled to [0, 2³² − 1], rounded to the nearest (in double precision; Mitsuba's
    /// single-precision product differs in the last units, e.g. 1 → 4294967040).
    UInt32,
}

crate::choices!(ComponentFormat, "component format", {
    ComponentFormat::Float32 => "float32", "32-bit floats";
    ComponentFormat::Float16 => "float16", "16-bit floats, clamped to ±65504";
    ComponentFormat::UInt32 => "uint32", "32-bit unsigned integers: [0, 1] scaled to 2³² − 1";
});

impl ComponentFormat {
    /// One channel's finite values in this format.
    fn samples(self, values: impl Iterator<Item = f32>) -> exr::prelude::FlatSamples {
        use exr::prelude::{f16, FlatSamples};
        match self {
            ComponentFormat::Float32 => FlatSamples::F32(values.collect()),
            ComponentFormat::Float16 => {
                FlatSamples::F16(values.map(|v| f16::from_f32(v.clamp(f16::MIN.to_f32(), f16::MAX.to_f32()))).collect())
            }
            ComponentFormat::UInt32 => FlatSamples::U32(
                values.map(|v| (f64::from(v.clamp(0.0, 1.0)) * 4_294_967_295.0).round() as u32).collect(),
            ),
        }
    }
}

/// What the colour channels of a written image hold: Mitsuba's `pixel_format` without its
/// alpha. The film holds linear sRGB; the others are derived from it as Mitsuba's RGB variants
/// derive them (CIE Y and XYZ of linear sRGB under D65).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ColorChannels {
    /// R, G, B (`rgb`, `rgba`).
    #[default]
    Rgb,
    /// Y, the luminance (`luminance`, `luminance_alpha`): one channel in EXR and PFM, grey in PNG.
    Luminance,
    /// X, Y, Z (`xyz`, `xyza`): EXR only.
    Xyz,
}

impl ColorChannels {
    /// The channel names, as Mitsuba writes them.
    pub fn names(self) -> &'static [&'static str] {
        match self {
            ColorChannels::Rgb => &["R", "G", "B"],
            ColorChannels::Luminance => &["Y"],
            ColorChannels::Xyz => &["X", "Y", "Z"],
        }
    }

    /// Channel `k` (of [`ColorChannels::names`]) of the linear sRGB colour `c`.
    pub fn channel(self, c: Rgb, k: usize) -> f32 {
        match self {
            ColorChannels::Rgb => c[k],
            ColorChannels::Luminance => luminance(c),
            ColorChannels::Xyz => srgb_to_xyz(c)[k],
        }
    }
}

/// Supported output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// OpenEXR, float32 RGB.
    Exr,
    /// PNG, 8-bit sRGB.
    Png,
    /// Portable float map, float32 RGB.
    Pfm,
    /// Radiance RGBE (`.hdr`, `.rgbe`): RGB of a shared 8-bit exponent, Mitsuba's `rgbe`.
    Hdr,
}

/// An image that could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// The file name's extension names no format neumann writes.
    #[error("cannot tell the image format of '{}' from its extension {}: use .exr, .png, .pfm or .hdr", path.display(), extension.as_ref().map_or("(none)".to_string(), |e| format!("'.{e}'")))]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// Its extension, if any.
        extension: Option<String>,
    },
    /// The format cannot hold what was asked (an alpha channel in PFM).
    #[error("cannot write '{}': {message}", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What it cannot hold.
        message: String,
    },
    /// Creating, encoding or writing the file failed.
    #[error("cannot write '{}': {message}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The encoder's or the operating system's message.
        message: String,
    },
}

impl Format {
    /// The format for a file name's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Format, WriteError> {
        match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
            Some("exr") => Ok(Format::Exr),
            Some("png") => Ok(Format::Png),
            Some("pfm") => Ok(Format::Pfm),
            Some("hdr" | "rgbe") => Ok(Format::Hdr),
            other => Err(WriteError::UnknownFormat { path: path.to_path_buf(), extension: other.map(str::to_string) }),
        }
    }
}

/// Writes `pixels` (row-major from the top-left, linear radiance) to `path` in the format its
/// extension names. Non-finite values are written as 0.
pub fn write_image(path: &Path, width: u32, height: u32, pixels: &[Rgb], info: &ImageInfo) -> Result<(), WriteError> {
    write_image_alpha(path, width, height, pixels, None, info)
}

/// [`write_image`] with an optional alpha channel (coverage in [0, 1], not premultiplied into
/// the colours), written as the A channel of EXR and PNG; PFM has no alpha and refuses it.
pub fn write_image_alpha(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Rgb],
    alpha: Option<&[f32]>,
    info: &ImageInfo,
) -> Result<(), WriteError> {
    write_image_layers(path, width, height, pixels, alpha, &[], info)
}

/// One named image channel beyond R, G, B and A (an AOV): its name (`albedo.R`, `dd.T`, …) and
/// its values, row-major from the top-left.
pub type Channel = (String, Vec<f32>);

/// [`write_image_alpha`] with further named channels, written beside R, G, B (and A) in one
/// EXR, as Mitsuba 3 writes its AOVs; PNG and PFM hold no extra channels and refuse them.
pub fn write_image_layers(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Rgb],
    alpha: Option<&[f32]>,
    channels: &[Channel],
    info: &ImageInfo,
) -> Result<(), WriteError> {
    assert_eq!(pixels.len(), (width * height) as usize);
    if let Some(a) = alpha {
        assert_eq!(a.len(), pixels.len());
    }
    for (_, v) in channels {
        assert_eq!(v.len(), pixels.len());
    }
    let fail = |message: String| WriteError::Write { path: path.to_path_buf(), message };
    let format = Format::from_path(path)?;
    if !channels.is_empty() && format != Format::Exr {
        return Err(WriteError::Unsupported {
            path: path.to_path_buf(),
            message: format!("only OpenEXR holds the {} AOV channels: write .exr", channels.len()),
        });
    }
    if info.colors == ColorChannels::Xyz && format != Format::Exr {
        return Err(WriteError::Unsupported {
            path: path.to_path_buf(),
            message: "only OpenEXR holds the X, Y, Z channels of pixel_format xyz: write .exr".into(),
        });
    }
    if matches!(format, Format::Pfm | Format::Hdr) && alpha.is_some() {
        let name = if format == Format::Pfm { "PFM" } else { "RGBE" };
        return Err(WriteError::Unsupported {
            path: path.to_path_buf(),
            message: format!("{name} has no alpha channel: write .exr or .png for pixel_format rgba"),
        });
    }
    write_atomically(path, |tmp| match format {
        Format::Exr => write_exr(tmp, width, height, pixels, alpha, channels, info),
        Format::Png => write_png(tmp, width, height, pixels, alpha, info),
        Format::Pfm => write_pfm(tmp, width, height, pixels, info.colors),
        Format::Hdr => write_rgbe(tmp, width, height, pixels, info.colors),
    })
    .map_err(fail)
}

/// Writes `path` through `write` to a temporary file beside it, flushed to disk, then renamed
/// over `path`: an interrupted or failed write leaves any earlier file at `path` whole (and
/// the temporary file is removed on failure).
pub fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<(), String>) -> Result<(), String> {
    let name = path.file_name().ok_or("the output path names no file")?.to_string_lossy().into_owned();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let result = write(&tmp).and_then(|()| {
        std::fs::File::open(&tmp).and_then(|f| f.sync_all()).map_err(|e| format!("cannot flush: {e}"))?;
        std::fs::rename(&tmp, path).map_err(|e| format!("cannot move the finished file into place: {e}"))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Checks before rendering that `path` can be written: a known extension, an existing folder,
/// and permission to create files in it (tested by creating and removing an empty one).
pub fn check_destination(path: &Path) -> Result<(), WriteError> {
    Format::from_path(path)?;
    let fail = |message: String| WriteError::Write { path: path.to_path_buf(), message };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(fail(format!("the folder '{}' does not exist", dir.display())));
    }
    if path.is_dir() {
        return Err(fail("is a folder".into()));
    }
    let probe = dir.join(format!(".neumann-probe-{}", std::process::id()));
    std::fs::File::create(&probe).map_err(|e| fail(format!("cannot create files in '{}': {e}", dir.display())))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

fn clean(c: Rgb) -> Rgb {
    Rgb::new(
        if c.x.is_finite() { c.x } else { 0.0 },
        if c.y.is_finite() { c.y } else { 0.0 },
        if c.z.is_finite() { c.z } else { 0.0 },
    )
}

/// An EXR (channels of `info.component`, float32 by default; lossless compression; the actual
/// `spp` in the header) of R, G, B, (A) and then `channels` (the file lists them sorted by
/// name, as OpenEXR requires).
fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Rgb],
    alpha: Option<&[f32]>,
    channels: &[Channel],
    info: &ImageInfo,
) -> Result<(), String> {
    use exr::prelude::*;
    let finite = |v: f32| if v.is_finite() { v } else { 0.0 };
    let colors = info.colors;
    let mut list: Vec<AnyChannel<FlatSamples>> = colors
        .names()
        .iter()
        .enumerate()
        .map(|(k, name)| {
            AnyChannel::new(*name, info.component.samples(pixels.iter().map(|&p| finite(colors.channel(clean(p), k)))))
        })
        .collect();
    if let Some(a) = alpha {
        list.push(AnyChannel::new("A", info.component.samples(a.iter().map(|&v| finite(v).clamp(0.0, 1.0)))));
    }
    for (name, values) in channels {
        let text = Text::new_or_none(name.as_str()).ok_or_else(|| format!("channel name '{name}' is not ASCII"))?;
        // neumann's own per-pixel sample count stays float32 (a count, not a colour to clamp).
        let component = if name == "spp" { ComponentFormat::Float32 } else { info.component };
        list.push(AnyChannel::new(text, component.samples(values.iter().map(|&v| finite(v)))));
    }
    let mut attributes = LayerAttributes::named("");
    attributes.software_name = Some(Text::from("neumann"));
    let layer = Layer::new(
        (width as usize, height as usize),
        attributes,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list.into_iter().collect()),
    );
    let mut image = Image::from_layer(layer);
    image.attributes.other.insert(Text::from("spp"), exr::meta::attribute::AttributeValue::I32(info.spp as i32));
    image.write().to_file(path).map_err(|e| e.to_string())
}

fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Rgb],
    alpha: Option<&[f32]>,
    info: &ImageInfo,
) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    let grey = info.colors == ColorChannels::Luminance;
    enc.set_color(match (grey, alpha.is_some()) {
        (false, false) => png::ColorType::Rgb,
        (false, true) => png::ColorType::Rgba,
        (true, false) => png::ColorType::Grayscale,
        (true, true) => png::ColorType::GrayscaleAlpha,
    });
    enc.set_depth(png::BitDepth::Eight);
    enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let scale = 2f32.powf(info.exposure);
    let encode = |v: f32| (srgb_encode(v.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8;
    let data: Vec<u8> = pixels
        .iter()
        .enumerate()
        .flat_map(|(i, &c)| {
            let c = clean(c) * scale;
            let colour = if grey { vec![encode(luminance(c))] } else { [c.x, c.y, c.z].map(encode).to_vec() };
            let a = alpha.map(|a| (a[i].clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
            colour.into_iter().chain(a)
        })
        .collect();
    let mut writer = enc.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(&data).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

/// Radiance RGBE, run-length encoded (the `image` crate's encoder): linear R, G, B, or the
/// luminance in all three for `pixel_format` `luminance`; negative and non-finite values as 0.
fn write_rgbe(path: &Path, width: u32, height: u32, pixels: &[Rgb], colors: ColorChannels) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    let positive = |v: f32| if v.is_finite() { v.max(0.0) } else { 0.0 };
    let data: Vec<image::Rgb<f32>> = pixels
        .iter()
        .map(|&p| {
            let c = clean(p);
            let c = if colors == ColorChannels::Luminance { Rgb::splat(luminance(c)) } else { c };
            image::Rgb([positive(c.x), positive(c.y), positive(c.z)])
        })
        .collect();
    let mut out = std::io::BufWriter::new(file);
    image::codecs::hdr::HdrEncoder::new(&mut out)
        .encode(&data, width as usize, height as usize)
        .map_err(|e| e.to_string())?;
    std::io::Write::flush(&mut out).map_err(|e| e.to_string())
}

fn write_pfm(path: &Path, width: u32, height: u32, pixels: &[Rgb], colors: ColorChannels) -> Result<(), String> {
    // PFM: header "PF\nW H\n-1.0\n" (negative scale = little endian; "Pf": one grey channel),
    // rows bottom to top.
    let grey = colors == ColorChannels::Luminance;
    let mut out = format!("{}\n{width} {height}\n-1.0\n", if grey { "Pf" } else { "PF" }).into_bytes();
    for y in (0..height).rev() {
        for x in 0..width {
            let c = clean(pixels[(y * width + x) as usize]);
            if grey {
                out.extend_from_slice(&luminance(c).to_le_bytes());
                continue;
            }
            for v in [c.x, c.y, c.z] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, out).map_err(|e| e.to_string())
}

/// Reads a PFM file written by [`write_image`] (or any little/big-endian colour PFM) back as
/// width, height and pixels (row-major from the top-left).
pub fn read_pfm(path: &Path) -> Result<(u32, u32, Vec<Rgb>), String> {
    let data = std::fs::read(path).map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
    let bad = |what: &str| format!("'{}' is not a colour PFM file: {what}", path.display());
    let mut fields = Vec::new();
    let mut pos = 0;
    while fields.len() < 4 {
        while pos < data.len() && data[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < data.len() && !data[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err(bad("truncated header"));
        }
        fields.push(String::from_utf8_lossy(&data[start..pos]).to_string());
    }
    pos += 1; // the single whitespace after the scale
    if fields[0] != "PF" {
        return Err(bad("missing 'PF' magic"));
    }
    let w: u32 = fields[1].parse().map_err(|_| bad("bad width"))?;
    let h: u32 = fields[2].parse().map_err(|_| bad("bad height"))?;
    let scale: f32 = fields[3].parse().map_err(|_| bad("bad scale"))?;
    let n = (w as usize) * (h as usize);
    if data.len() < pos + n * 12 {
        return Err(bad("truncated pixel data"));
    }
    let rd = |i: usize| {
        let b = [data[pos + 4 * i], data[pos + 4 * i + 1], data[pos + 4 * i + 2], data[pos + 4 * i + 3]];
        if scale < 0.0 {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut pixels = vec![Rgb::ZERO; n];
    for y in 0..h as usize {
        for x in 0..w as usize {
            let k = (y * w as usize + x) * 3;
            pixels[(h as usize - 1 - y) * w as usize + x] = Rgb::new(rd(k), rd(k + 1), rd(k + 2));
        }
    }
    Ok((w, h, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RGBA output: PNG gets an 8-bit alpha channel, EXR an A channel; PFM refuses alpha.
    #[test]
    fn alpha_channel_is_written() {
        let dir = std::env::temp_dir().join(format!("neumann-alpha-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let px = vec![Rgb::new(0.2, 0.4, 0.6); 2];
        let alpha = [1.0f32, 0.25];
        let info = ImageInfo::default();
        write_image_alpha(&dir.join("a.png"), 2, 1, &px, Some(&alpha), &info).unwrap();
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(dir.join("a.png")).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let frame = reader.next_frame(&mut buf).unwrap();
        assert_eq!(frame.color_type, png::ColorType::Rgba);
        assert_eq!((buf[3], buf[7]), (255, 64));
        write_image_alpha(&dir.join("a.exr"), 2, 1, &px, Some(&alpha), &info).unwrap();
        let image = exr::prelude::read_first_rgba_layer_from_file(
            dir.join("a.exr"),
            |res, _| vec![[0.0f32; 4]; res.width() * res.height()],
            |buf: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| buf[pos.x()] = [r, g, b, a],
        )
        .unwrap();
        let pixels = &image.layer_data.channel_data.pixels;
        assert_eq!(pixels[1], [0.2, 0.4, 0.6, 0.25]);
        assert!(write_image_alpha(&dir.join("a.pfm"), 2, 1, &px, Some(&alpha), &info).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }

    /// AOV channels travel in one EXR beside R, G, B (A), by name; PNG refuses them.
    #[test]
    fn aov_channels_are_written_by_name() {
        let dir = std::env::temp_dir().join(format!("neumann-aov-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let px = vec![Rgb::new(0.2, 0.4, 0.6), Rgb::new(f32::NAN, 1.0, 2.0)];
        let channels: Vec<Channel> =
            vec![("dd.T".into(), vec![3.0, 4.0]), ("m2__arg_0.X".into(), vec![0.5, f32::INFINITY])];
        let info = ImageInfo::default();
        write_image_layers(&dir.join("a.exr"), 2, 1, &px, Some(&[1.0, 0.5]), &channels, &info).unwrap();
        let image = exr::prelude::read_all_flat_layers_from_file(dir.join("a.exr")).unwrap();
        let layer = &image.layer_data[0];
        let get = |name: &str| -> Vec<f32> {
            let c = layer.channel_data.list.iter().find(|c| c.name.eq(name)).unwrap();
            c.sample_data.values_as_f32().collect()
        };
        assert_eq!(layer.channel_data.list.len(), 6);
        assert_eq!(get("R"), [0.2, 0.0], "non-finite values are written as 0");
        assert_eq!(get("A"), [1.0, 0.5]);
        assert_eq!(get("dd.T"), [3.0, 4.0]);
        assert_eq!(get("m2__arg_0.X"), [0.5, 0.0]);
        let e = write_image_layers(&dir.join("a.png"), 2, 1, &px, None, &channels, &info).unwrap_err();
        assert!(e.to_string().contains("only OpenEXR"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Mitsuba's component formats: every channel of the EXR in float16 (huge values clamped to
    /// the largest half, not infinite as Mitsuba writes them) or in uint32 (clamped to [0, 1],
    /// scaled to 2³² − 1 and rounded: Mitsuba 3.9.1 writes 0.2835 as 1217623168, its float32
    /// product, and 1 as 4294967040); neumann's `spp` count channel stays float32.
    #[test]
    fn component_formats() {
        use exr::prelude::{f16, FlatSamples};
        let dir = std::env::temp_dir().join(format!("neumann-component-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let px = vec![Rgb::new(0.2835, -1.0, 1e6), Rgb::new(1.0, 0.5, f32::NAN)];
        let channels: Vec<Channel> = vec![("spp".into(), vec![3.0, 70000.0]), ("d.T".into(), vec![2.5, 0.25])];
        let samples = |component: ComponentFormat| {
            let info = ImageInfo { component, ..Default::default() };
            write_image_layers(&dir.join("c.exr"), 2, 1, &px, Some(&[1.0, 0.5]), &channels, &info).unwrap();
            let image = exr::prelude::read_all_flat_layers_from_file(dir.join("c.exr")).unwrap();
            let mut list: Vec<(String, FlatSamples)> = image.layer_data[0]
                .channel_data
                .list
                .iter()
                .map(|c| (c.name.to_string(), c.sample_data.clone()))
                .collect();
            list.sort_by(|a, b| a.0.cmp(&b.0));
            list
        };
        let half = samples(ComponentFormat::Float16);
        let h = |v: f32| f16::from_f32(v);
        let want_half = [
            ("A", vec![h(1.0), h(0.5)]),
            ("B", vec![f16::MAX, h(0.0)]),
            ("G", vec![h(-1.0), h(0.5)]),
            ("R", vec![h(0.2835), h(1.0)]),
            ("d.T", vec![h(2.5), h(0.25)]),
        ];
        for (name, values) in want_half {
            let got = &half.iter().find(|c| c.0 == name).unwrap().1;
            assert!(matches!(got, FlatSamples::F16(v) if *v == values), "{name}: {got:?}");
        }
        let spp = &half.iter().find(|c| c.0 == "spp").unwrap().1;
        assert!(matches!(spp, FlatSamples::F32(v) if *v == [3.0, 70000.0]), "{spp:?}");
        let ints = samples(ComponentFormat::UInt32);
        let want_u32 = [
            ("A", vec![4294967295, 2147483648]),
            ("B", vec![4294967295, 0]),
            ("G", vec![0, 2147483648]),
            ("R", vec![1217623168, 4294967295]),
            ("d.T", vec![4294967295, 1073741824]),
        ];
        for (name, values) in want_u32 {
            let got = &ints.iter().find(|c| c.0 == name).unwrap().1;
            assert!(matches!(got, FlatSamples::U32(v) if *v == values), "{name}: {got:?}");
        }
        assert_eq!("float16".parse::<ComponentFormat>(), Ok(ComponentFormat::Float16));
        assert!("half".parse::<ComponentFormat>().is_err());
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Mitsuba's pixel formats: `luminance` writes one channel Y (EXR, PFM "Pf") or grey (PNG),
    /// `xyz` the channels X, Y, Z (EXR only), both from the linear sRGB the film holds.
    #[test]
    fn luminance_and_xyz_channels() {
        let dir = std::env::temp_dir().join(format!("neumann-colors-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let px = vec![Rgb::new(1.0, 0.0, 0.0), Rgb::new(0.2, 0.4, 0.6)];
        let read = |name: &str| {
            let image = exr::prelude::read_all_flat_layers_from_file(dir.join(name)).unwrap();
            let layer = &image.layer_data[0];
            let mut v: Vec<(String, Vec<f32>)> = layer
                .channel_data
                .list
                .iter()
                .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
                .collect();
            v.sort_by(|a, b| a.0.cmp(&b.0));
            v
        };
        let luma = ImageInfo { colors: ColorChannels::Luminance, ..Default::default() };
        write_image_alpha(&dir.join("y.exr"), 2, 1, &px, Some(&[1.0, 0.5]), &luma).unwrap();
        let y = [0.212671, luminance(px[1])];
        assert_eq!(read("y.exr"), [("A".to_string(), vec![1.0, 0.5]), ("Y".to_string(), y.to_vec())]);
        write_image(&dir.join("y.pfm"), 2, 1, &px, &luma).unwrap();
        let pfm = std::fs::read(dir.join("y.pfm")).unwrap();
        assert!(pfm.starts_with(b"Pf\n2 1\n-1.0\n") && pfm.len() == 12 + 8, "{} bytes", pfm.len());
        write_image(&dir.join("y.png"), 2, 1, &px, &luma).unwrap();
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(dir.join("y.png")).unwrap()));
        assert_eq!(decoder.read_info().unwrap().info().color_type, png::ColorType::Grayscale);
        let xyz = ImageInfo { colors: ColorChannels::Xyz, ..Default::default() };
        write_image(&dir.join("xyz.exr"), 2, 1, &px, &xyz).unwrap();
        let channels = read("xyz.exr");
        let names: Vec<&str> = channels.iter().map(|c| c.0.as_str()).collect();
        assert_eq!(names, ["X", "Y", "Z"]);
        assert_eq!(channels[0].1[0], 0.412453);
        assert_eq!(channels[1].1, y);
        for name in ["xyz.png", "xyz.pfm", "xyz.hdr"] {
            let e = write_image(&dir.join(name), 2, 1, &px, &xyz).unwrap_err();
            assert!(e.to_string().contains("only OpenEXR holds the X, Y, Z"), "{e}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn formats_by_extension_and_round_trips() {
        assert_eq!(Format::from_path(Path::new("a.EXR")).unwrap(), Format::Exr);
        let jpg = Format::from_path(Path::new("a.jpg")).unwrap_err();
        assert!(matches!(&jpg, WriteError::UnknownFormat { extension: Some(e), .. } if e == "jpg"));
        assert!(jpg.to_string().contains("'.jpg': use .exr, .png, .pfm or .hdr"), "{jpg}");
        assert_eq!(Format::from_path(Path::new("a.rgbe")).unwrap(), Format::Hdr);
        let none = Format::from_path(Path::new("noext")).unwrap_err();
        assert!(none.to_string().contains("extension (none)"), "{none}");
        let pfm_alpha = write_image_alpha(Path::new("x.pfm"), 1, 1, &[Rgb::ONE], Some(&[1.0]), &ImageInfo::default());
        assert!(matches!(pfm_alpha, Err(WriteError::Unsupported { .. })));
        let dir = std::env::temp_dir().join(format!("neumann-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let px: Vec<Rgb> = (0..6).map(|i| Rgb::new(i as f32, 0.5, f32::NAN)).collect();
        let info = ImageInfo { spp: 7, exposure: 0.0, ..Default::default() };
        for name in ["t.exr", "t.png", "t.pfm"] {
            write_image(&dir.join(name), 3, 2, &px, &info).unwrap();
            assert!(std::fs::metadata(dir.join(name)).unwrap().len() > 20);
        }
        // Radiance RGBE: the colours to 8-bit mantissas of the pixel's shared exponent (within
        // 1/128 of its largest channel), NaN and negatives as 0,
        // the luminance in all three channels for pixel_format luminance; no alpha.
        let rgbe = [Rgb::new(0.25, 3.0, f32::NAN), Rgb::new(-1.0, 1000.0, 0.01), Rgb::new(1.0, 0.5, 0.2)];
        write_image(&dir.join("t.hdr"), 3, 1, &rgbe, &info).unwrap();
        let back = image::open(dir.join("t.hdr")).unwrap().to_rgb32f();
        let want = [[0.25, 3.0, 0.0], [0.0, 1000.0, 0.01], [1.0, 0.5, 0.2]];
        for (p, w) in back.pixels().zip(want) {
            let largest = w.iter().fold(0.0f32, |m, &c| m.max(c));
            assert!((0..3).all(|k| (p[k] - w[k]).abs() <= largest / 128.0), "{:?} vs {w:?}", p.0);
        }
        let luma = ImageInfo { colors: ColorChannels::Luminance, ..Default::default() };
        write_image(&dir.join("y.hdr"), 3, 1, &rgbe, &luma).unwrap();
        let grey = image::open(dir.join("y.hdr")).unwrap().to_rgb32f();
        let y = luminance(rgbe[2]);
        assert!(
            grey.pixels().nth(2).unwrap().0.iter().all(|&c| (c - y).abs() < 0.01 * y),
            "{:?}",
            grey.pixels().nth(2)
        );
        let hdr_alpha = write_image_alpha(&dir.join("a.hdr"), 1, 1, &[Rgb::ONE], Some(&[1.0]), &ImageInfo::default());
        assert!(matches!(hdr_alpha, Err(WriteError::Unsupported { .. })));
        let (w, h, back) = read_pfm(&dir.join("t.pfm")).unwrap();
        assert_eq!((w, h), (3, 2));
        assert_eq!(back[4], Rgb::new(4.0, 0.5, 0.0), "NaN written as 0, rows in order");
        // The EXR header carries the sample count.
        let meta = exr::meta::MetaData::read_from_file(dir.join("t.exr"), false).unwrap();
        let key = exr::meta::attribute::Text::from("spp");
        let h = &meta.headers[0];
        let spp = h.shared_attributes.other.get(&key).or_else(|| h.own_attributes.other.get(&key)).cloned();
        assert!(matches!(spp, Some(exr::meta::attribute::AttributeValue::I32(7))), "{spp:?}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
