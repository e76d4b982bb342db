//! A render split over machines: each part's film as an OpenEXR file that says which render and
//! which samples and pixels it holds, and the merge of parts back into the whole render.
//!
//! A part holds the sample indices `[first, end)` of every pixel of a window of the image (all
//! of it, or a tile). Its EXR is a viewable image (R, G, B, A and AOVs: the part's own estimate)
//! plus the per-pixel sums a merge needs: `weight` (`Σ w`, the filter weights of the samples; the
//! sample count with the box filter), `weight2` (`Σ w²`), `moment2.R/G/B` (the second moment
//! `Σ w L² / Σ w`, for the variance) and `spp` (samples taken in the pixel). The header records the
//! render (a fingerprint of the scene and settings, in words too, the seed and the samples per
//! pixel of the whole render), the samples held, the window and the image it is a tile of; the
//! EXR's data window is the tile and its display window the image, so a viewer places tiles.
//!
//! Merging weighs each part by its weights: `R = Σₚ Wₚ Rₚ / Σₚ Wₚ`, and the same for the second
//! moment, alpha and AOVs. Values travel as f32, so a merge of the parts of a split equals the
//! single render with the same seed within float rounding, not bit for bit: each channel within
//! a few f32 rounding units (`merge_of_a_split_equals_the_single_render` checks 2⁻²⁰ relative).

use super::output::{write_atomically, WriteError};
use super::{Acc, Film};
use std::fmt;
use std::path::{Path, PathBuf};

/// Header attribute naming the part format's version.
const VERSION_KEY: &str = "neumannPart";
/// Per-pixel channels a part holds beside the image and its AOVs.
const SUM_CHANNELS: [&str; 6] = ["weight", "weight2", "moment2.R", "moment2.G", "moment2.B", "spp"];
/// The most pixels a part file may hold (as for images neumann reads).
const MAX_PIXELS: u64 = 1 << 28;

/// What a part says about the render it belongs to and what of it it holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartInfo {
    /// A hash of the scene and of the settings every part must share.
    pub fingerprint: u64,
    /// The scene, for messages.
    pub scene: String,
    /// The settings the fingerprint covers, in words (for messages).
    pub settings: String,
    /// The sampling seed.
    pub seed: u64,
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// The sample indices `[first, end)` every pixel of this part holds.
    pub samples: (u32, u32),
    /// This part's pixels `[x, y, width, height]` in the camera's film.
    pub window: [u32; 4],
    /// The image the parts assemble into (the whole film or its crop window).
    pub image: [u32; 4],
    /// `(I, N)` for part `I` of `N` (`--part I/N`), if the part was made so.
    pub part_of: Option<(u32, u32)>,
}

impl PartInfo {
    /// Samples `[first, end)` of part `index` (1-based) of `count` parts of an `spp`-sample
    /// render: `[⌊(I−1)·S/N⌋, ⌊I·S/N⌋)`, so the parts are disjoint, cover `[0, S)` and differ in
    /// size by at most one sample.
    pub fn split(spp: u32, index: u32, count: u32) -> (u32, u32) {
        let at = |i: u32| (u64::from(spp) * u64::from(i) / u64::from(count.max(1))) as u32;
        (at(index - 1), at(index))
    }
}

/// A part read back: what it says and its film (the sums of its window).
#[derive(Clone, Debug)]
pub struct Part {
    /// The file it came from.
    pub path: PathBuf,
    /// What it holds.
    pub info: PartInfo,
    /// Its film, `window`-sized.
    pub film: Film,
    /// Whether it has an alpha channel.
    pub alpha: bool,
    /// Non-finite samples its render dropped.
    pub dropped: u64,
}

/// A part file that could not be read, or parts that do not merge.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    /// The file is not a readable part.
    #[error("{}: {message}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Two parts of different renders.
    #[error("{} and {} are parts of different renders: {what}", first.display(), other.display())]
    Mismatch {
        /// The first part.
        first: PathBuf,
        /// The part that differs from it.
        other: PathBuf,
        /// What differs.
        what: String,
    },
    /// Two parts hold some of the same samples of the same pixels.
    #[error("{} and {} overlap: {what}", first.display(), other.display())]
    Overlap {
        /// One part.
        first: PathBuf,
        /// The other.
        other: PathBuf,
        /// Which samples or pixels both hold.
        what: String,
    },
    /// Samples or pixels no part holds.
    #[error("the parts do not make the whole render; missing: {} (merge what exists with --allow-partial)", missing.join("; "))]
    Missing {
        /// What is missing, one entry per range of samples or rectangle of pixels.
        missing: Vec<String>,
    },
    /// No parts were given.
    #[error("no parts to merge")]
    Empty,
}

/// The merge of parts: the image's film and, when every pixel holds the same samples `[a, b)`,
/// the part that the merge itself is (which can be merged again).
#[derive(Debug)]
pub struct Merged {
    /// The image's film (`image`-sized).
    pub film: Film,
    /// Whether the parts have an alpha channel.
    pub alpha: bool,
    /// The merge as a part, if it is one.
    pub info: Option<PartInfo>,
    /// What is missing (empty for a complete merge).
    pub missing: Vec<String>,
    /// Where the image lies in the camera's film.
    pub image: [u32; 4],
}

/// Text for an EXR header attribute: ASCII, other characters escaped.
fn ascii(s: &str) -> String {
    s.chars().map(|c| if c.is_ascii() && c != '\0' { c.to_string() } else { c.escape_unicode().to_string() }).collect()
}

fn rect_text(r: [u32; 4]) -> String {
    format!("{} {} {} {}", r[0], r[1], r[2], r[3])
}

fn describe_rect(r: [u32; 4]) -> String {
    format!("pixels x {}–{}, y {}–{}", r[0], r[0] + r[2], r[1], r[1] + r[3])
}

impl Film {
    /// The per-pixel channels of this film as a part: R, G, B, (A), its AOVs, then the sums
    /// (see the module documentation).
    fn part_channels(&self, alpha: bool) -> Vec<(String, Vec<f32>)> {
        let mean = |f: &dyn Fn(&Acc) -> f64| -> Vec<f32> {
            self.px.acc.iter().map(|a| if a.w() > 0.0 { (f(a) / a.w()) as f32 } else { 0.0 }).collect()
        };
        let mut out = Vec::new();
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            out.push((name.to_string(), mean(&|a| a.sum[c])));
        }
        if alpha {
            out.push(("A".into(), mean(&|a| a.alpha)));
        }
        out.extend(self.aov_channels());
        out.push(("weight".into(), self.px.acc.iter().map(|a| a.w() as f32).collect()));
        out.push(("weight2".into(), self.px.acc.iter().map(|a| a.w2() as f32).collect()));
        for (c, name) in ["moment2.R", "moment2.G", "moment2.B"].iter().enumerate() {
            out.push((name.to_string(), mean(&|a| a.wl2[c])));
        }
        out.push(("spp".into(), self.sample_counts()));
        out
    }

    /// Adds a part's film (of `window`'s size) into this film at `window`'s place relative to
    /// `origin` (this film's position in the camera's film).
    fn add_part(&mut self, part: &Film, window: [u32; 4], origin: [u32; 2]) {
        let (dx, dy) = (window[0] - origin[0], window[1] - origin[1]);
        for y in 0..window[3] {
            for x in 0..window[2] {
                let i = ((dy + y) * self.width + dx + x) as usize;
                self.px.add_from(i, &part.px, (y * window[2] + x) as usize);
            }
        }
        self.px.dropped += part.px.dropped;
    }
}

/// Writes `film` (the window's sums) as a part file at `path` (OpenEXR).
pub fn write_part(path: &Path, film: &Film, info: &PartInfo, alpha: bool) -> Result<(), WriteError> {
    use exr::meta::attribute::AttributeValue;
    use exr::prelude::*;
    let fail = |message: String| WriteError::Write { path: path.to_path_buf(), message };
    if super::output::Format::from_path(path)? != super::output::Format::Exr {
        return Err(WriteError::Unsupported {
            path: path.to_path_buf(),
            message: "a part of a split render is written as OpenEXR: name it .exr".into(),
        });
    }
    let [x, y, w, h] = info.window;
    assert_eq!((film.width, film.height), (w, h), "the film is the part's window");
    let finite = |v: f32| if v.is_finite() { v } else { 0.0 };
    let mut channels = Vec::new();
    for (name, values) in film.part_channels(alpha) {
        if channels.iter().any(|c: &AnyChannel<FlatSamples>| c.name.eq(name.as_str())) {
            return Err(fail(format!("two channels are named '{name}' (an AOV takes the name of a part's channel)")));
        }
        let text = Text::new_or_none(name.as_str()).ok_or_else(|| fail(format!("channel name '{name}' is not ASCII")))?;
        channels.push(AnyChannel::new(text, FlatSamples::F32(values.into_iter().map(finite).collect())));
    }
    let mut attributes = LayerAttributes::named("");
    attributes.software_name = Some(Text::from("neumann"));
    attributes.layer_position = Vec2(x as i32, y as i32);
    let layer =
        Layer::new((w as usize, h as usize), attributes, Encoding::FAST_LOSSLESS, AnyChannels::sort(channels.into_iter().collect()));
    let mut image = Image::from_layer(layer);
    let [ix, iy, iw, ih] = info.image;
    image.attributes.display_window =
        IntegerBounds::new(Vec2(ix as i32, iy as i32), Vec2(iw as usize, ih as usize));
    let mut put = |key: &str, value: String| {
        image.attributes.other.insert(Text::from(key), AttributeValue::Text(Text::from(ascii(&value).as_str())));
    };
    put(VERSION_KEY, "1".into());
    put("neumannFingerprint", format!("{:016x}", info.fingerprint));
    put("neumannScene", info.scene.clone());
    put("neumannSettings", info.settings.clone());
    put("neumannSeed", info.seed.to_string());
    put("neumannSpp", info.spp.to_string());
    put("neumannSamples", format!("{} {}", info.samples.0, info.samples.1));
    put("neumannWindow", rect_text(info.window));
    put("neumannImage", rect_text(info.image));
    put("neumannDropped", film.dropped().to_string());
    if let Some((i, n)) = info.part_of {
        put("neumannPartOf", format!("{i}/{n}"));
    }
    image.attributes.other.insert(Text::from("spp"), AttributeValue::I32((info.samples.1 - info.samples.0) as i32));
    write_atomically(path, |tmp| image.write().to_file(tmp).map_err(|e| e.to_string())).map_err(fail)
}

/// Checks that every tile of a single-part, single-level tiled OpenEXR file says it belongs to
/// level (0, 0), as the exr crate's reader assumes without checking.
fn tiles_at_level_zero(bytes: &[u8], chunks: usize) -> Result<(), String> {
    let bad = || "a corrupt OpenEXR file (its tile table does not match its header)".to_string();
    let mut pos = 8;
    // Header attributes: name\0 type\0 size value, up to an empty name.
    loop {
        let name_end = bytes.get(pos..).and_then(|b| b.iter().position(|&c| c == 0)).ok_or_else(bad)? + pos;
        if name_end == pos {
            pos += 1;
            break;
        }
        let type_end = bytes.get(name_end + 1..).and_then(|b| b.iter().position(|&c| c == 0)).ok_or_else(bad)? + name_end + 1;
        let size = bytes.get(type_end + 1..type_end + 5).ok_or_else(bad)?;
        let size = i32::from_le_bytes(size.try_into().expect("4 bytes"));
        pos = type_end + 5 + usize::try_from(size).map_err(|_| bad())?;
    }
    for c in 0..chunks {
        let at = pos + 8 * c;
        let offset = u64::from_le_bytes(bytes.get(at..at + 8).ok_or_else(bad)?.try_into().expect("8 bytes"));
        let offset = usize::try_from(offset).map_err(|_| bad())?;
        let levels = bytes.get(offset.saturating_add(8)..offset.saturating_add(16)).ok_or_else(bad)?;
        if levels.iter().any(|&b| b != 0) {
            return Err(bad());
        }
    }
    Ok(())
}

/// Reads a part written by [`write_part`].
pub fn read_part(path: &Path) -> Result<Part, PartError> {
    use exr::meta::attribute::AttributeValue;
    let fail = |message: String| PartError::Read { path: path.to_path_buf(), message };
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| fail(format!("not a readable OpenEXR file: {e}")))?;
    let header = meta.headers.first().ok_or_else(|| fail("an OpenEXR file without a layer".into()))?;
    // neumann writes one flat single-resolution layer; other layouts (mip or rip levels, deep
    // data, several layers) are no parts, and the exr crate's reader trips over inconsistent
    // level indices in them (found by fuzzing).
    let single_level = match &header.blocks {
        exr::meta::BlockDescription::ScanLines => true,
        exr::meta::BlockDescription::Tiles(t) => matches!(t.level_mode, exr::meta::attribute::LevelMode::Singular),
    };
    if meta.headers.len() != 1 || header.deep || !single_level {
        return Err(fail("not a part of a split render (a multi-resolution, multi-layer or deep OpenEXR file)".into()));
    }
    if matches!(header.blocks, exr::meta::BlockDescription::Tiles(_)) {
        let mut bytes = Vec::new();
        use std::io::Read;
        std::fs::File::open(path)
            .and_then(|f| f.take(16 << 30).read_to_end(&mut bytes))
            .map_err(|e| fail(format!("cannot read: {e}")))?;
        tiles_at_level_zero(&bytes, header.chunk_count).map_err(fail)?;
    }
    let size = header.layer_size;
    if size.width() as u64 * size.height() as u64 > MAX_PIXELS {
        return Err(fail(format!("{}×{} pixels, more than the limit of {MAX_PIXELS}", size.width(), size.height())));
    }
    let text = |key: &str| -> Result<String, PartError> {
        let key_text = exr::prelude::Text::from(key);
        match header.shared_attributes.other.get(&key_text).or_else(|| header.own_attributes.other.get(&key_text)) {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            Some(_) => Err(fail(format!("the header attribute {key} is not text"))),
            None if key == VERSION_KEY => Err(fail(
                "not a part of a split render (no neumannPart header attribute: write parts with neumann render --part or --pixel-bounds)".into(),
            )),
            None => Err(fail(format!("the header lacks the attribute {key}"))),
        }
    };
    let numbers = |key: &str, count: usize| -> Result<Vec<u64>, PartError> {
        let t = text(key)?;
        let v: Vec<u64> = t.split_whitespace().map(str::parse).collect::<Result<_, _>>().map_err(|_| fail(format!("{key} '{t}' is not {count} whole numbers")))?;
        if v.len() != count || v.iter().any(|&n| n > u64::from(u32::MAX) && count != 1) {
            return Err(fail(format!("{key} '{t}' is not {count} whole numbers")));
        }
        Ok(v)
    };
    let version = text(VERSION_KEY)?;
    if version != "1" {
        return Err(fail(format!("a part of format version {version}; this neumann reads version 1")));
    }
    let rect = |key: &str| -> Result<[u32; 4], PartError> {
        let v = numbers(key, 4)?;
        let r = [v[0] as u32, v[1] as u32, v[2] as u32, v[3] as u32];
        if r[2] == 0 || r[3] == 0 || r[0].checked_add(r[2]).is_none() || r[1].checked_add(r[3]).is_none() {
            return Err(fail(format!("{key} '{}' is not a rectangle of pixels", rect_text(r))));
        }
        Ok(r)
    };
    let fingerprint = u64::from_str_radix(&text("neumannFingerprint")?, 16).map_err(|_| fail("neumannFingerprint is not hexadecimal".into()))?;
    let samples = numbers("neumannSamples", 2)?;
    let spp = numbers("neumannSpp", 1)?[0];
    let part_of = match text("neumannPartOf") {
        Ok(t) => {
            let bad = || fail(format!("neumannPartOf '{t}' is not I/N"));
            let (i, n) = t.split_once('/').ok_or_else(bad)?;
            Some((i.parse().map_err(|_| bad())?, n.parse().map_err(|_| bad())?))
        }
        Err(_) => None,
    };
    let info = PartInfo {
        fingerprint,
        scene: text("neumannScene")?,
        settings: text("neumannSettings")?,
        seed: numbers("neumannSeed", 1)?[0],
        spp: u32::try_from(spp).map_err(|_| fail("neumannSpp is too large".into()))?,
        samples: (samples[0] as u32, samples[1] as u32),
        window: rect("neumannWindow")?,
        image: rect("neumannImage")?,
        part_of,
    };
    let dropped = numbers("neumannDropped", 1)?[0];
    let [wx, wy, w, h] = info.window;
    let [ix, iy, iw, ih] = info.image;
    if info.samples.0 >= info.samples.1 || info.samples.1 > info.spp {
        return Err(fail(format!("holds samples {}–{} of a {}-sample render", info.samples.0, info.samples.1, info.spp)));
    }
    if (size.width(), size.height()) != (w as usize, h as usize)
        || wx < ix
        || wy < iy
        || u64::from(wx) + u64::from(w) > u64::from(ix) + u64::from(iw)
        || u64::from(wy) + u64::from(h) > u64::from(iy) + u64::from(ih)
    {
        return Err(fail(format!(
            "its window ({}) is not its {}×{} pixels inside its image ({})",
            describe_rect(info.window),
            size.width(),
            size.height(),
            describe_rect(info.image)
        )));
    }
    crate::image::exr_chunks_fit(path).map_err(&fail)?;
    let image = exr::prelude::read_all_flat_layers_from_file(path).map_err(|e| fail(format!("not a readable OpenEXR file: {e}")))?;
    let layer = image.layer_data.first().ok_or_else(|| fail("an OpenEXR file without a layer".into()))?;
    let channel = |name: &str| -> Option<Vec<f32>> {
        layer.channel_data.list.iter().find(|c| c.name.eq(name)).map(|c| c.sample_data.values_as_f32().collect())
    };
    let pixels = w as usize * h as usize;
    let need = |name: &str| {
        let values = channel(name).ok_or_else(|| fail(format!("the channel '{name}' is missing")))?;
        if values.len() != pixels {
            return Err(fail(format!("the channel '{name}' holds {} values for {pixels} pixels (subsampled?)", values.len())));
        }
        Ok(values)
    };
    let reserved = |name: &str| ["R", "G", "B", "A"].contains(&name) || SUM_CHANNELS.contains(&name);
    let aov_names: Vec<String> =
        layer.channel_data.list.iter().map(|c| c.name.to_string()).filter(|n| !reserved(n)).collect();
    let alpha = if channel("A").is_some() { Some(need("A")?) } else { None };
    let rgb = [need("R")?, need("G")?, need("B")?];
    let [weight, weight2, m_r, m_g, m_b, count] = SUM_CHANNELS.map(need);
    let (weight, weight2, m2, count) = (weight?, weight2?, [m_r?, m_g?, m_b?], count?);
    let aovs: Vec<Vec<f32>> = aov_names.iter().map(|n| need(n)).collect::<Result<_, _>>()?;
    let mut film = Film::new(w, h).with_aovs(order_aovs(&aov_names));
    let order: Vec<usize> = film.aov_names.iter().map(|n| aov_names.iter().position(|m| m == n).expect("same names")).collect();
    let finite = |v: f32| -> Result<f64, PartError> {
        if v.is_finite() {
            Ok(f64::from(v))
        } else {
            Err(fail("a pixel holds a value that is not finite".into()))
        }
    };
    for i in 0..pixels {
        let wt = finite(weight[i])?;
        if wt < 0.0 || !(count[i] >= 0.0 && count[i] <= u32::MAX as f32) {
            return Err(fail(format!("pixel {i} has a negative weight or sample count")));
        }
        let a = &mut film.px.acc[i];
        for c in 0..3 {
            a.sum[c] = finite(rgb[c][i])? * wt;
            a.wl2[c] = finite(m2[c][i])? * wt;
        }
        a.sum[3] = wt;
        a.wl2[3] = finite(weight2[i])?;
        a.alpha = match &alpha {
            Some(v) => finite(v[i])? * wt,
            None => 0.0,
        };
        film.px.count[i] = count[i] as u32;
        for (k, &j) in order.iter().enumerate() {
            film.px.aovs[i * order.len() + k] = finite(aovs[j][i])? * wt;
        }
    }
    film.px.dropped = dropped;
    Ok(Part { path: path.to_path_buf(), info, film, alpha: alpha.is_some(), dropped })
}

/// AOV channel names in a stable order: an EXR lists its channels sorted by name, so the order
/// a render gave them is not recoverable; parts compare and merge them in sorted order.
fn order_aovs(names: &[String]) -> Vec<String> {
    let mut v = names.to_vec();
    v.sort();
    v
}

/// The samples `[first, end)` of `spp` that `ranges` (sorted, disjoint) leave out.
fn gaps(ranges: &[(u32, u32)], spp: u32) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    let mut at = 0;
    for &(a, b) in ranges {
        if a > at {
            out.push((at, a));
        }
        at = at.max(b);
    }
    if at < spp {
        out.push((at, spp));
    }
    out
}

fn overlaps(a: [u32; 4], b: [u32; 4]) -> bool {
    a[0] < b[0] + b[2] && b[0] < a[0] + a[2] && a[1] < b[1] + b[3] && b[1] < a[1] + a[3]
}

/// Merges `parts` (weighted by their filter weights) into their image. Refuses parts of
/// different renders and parts holding the same samples of the same pixels; samples or pixels
/// that no part holds are an error unless `allow_partial`, and are listed either way.
pub fn merge_parts(parts: &[Part], allow_partial: bool) -> Result<Merged, PartError> {
    let first = parts.first().ok_or(PartError::Empty)?;
    let base = &first.info;
    for p in &parts[1..] {
        let i = &p.info;
        let what = if i.seed != base.seed {
            Some(format!("the seeds differ ({} and {})", base.seed, i.seed))
        } else if i.spp != base.spp {
            Some(format!("the samples per pixel differ ({} and {})", base.spp, i.spp))
        } else if i.settings != base.settings {
            Some(format!("the settings differ ('{}' and '{}')", base.settings, i.settings))
        } else if i.image != base.image {
            Some(format!("the images differ ({} and {})", describe_rect(base.image), describe_rect(i.image)))
        } else if i.scene != base.scene || i.fingerprint != base.fingerprint {
            Some(format!("the scenes differ ('{}' and '{}', or the scene file or its -D parameters changed)", base.scene, i.scene))
        } else if p.film.aov_names != first.film.aov_names || p.alpha != first.alpha {
            Some("the channels (alpha, AOVs) differ".to_string())
        } else {
            None
        };
        if let Some(what) = what {
            return Err(PartError::Mismatch { first: first.path.clone(), other: p.path.clone(), what });
        }
    }
    // The image cut along every window's edges into cells that each part covers whole or not
    // at all; in each cell the parts' sample ranges must be disjoint, and together they should
    // hold [0, spp).
    let [ix, iy, iw, ih] = base.image;
    let cuts = |pos: usize, size: usize| -> Vec<u32> {
        let mut v: Vec<u32> = [base.image[pos], base.image[pos] + base.image[size]]
            .into_iter()
            .chain(parts.iter().flat_map(|p| [p.info.window[pos], p.info.window[pos] + p.info.window[size]]))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let (xs, ys) = (cuts(0, 2), cuts(1, 3));
    // Per gap of samples: the pixels that lack it and their bounding box.
    let mut lacking: Vec<((u32, u32), u64, [u32; 4])> = Vec::new();
    let mut unions = Vec::new();
    for (y0, y1) in ys.iter().zip(&ys[1..]) {
        for (x0, x1) in xs.iter().zip(&xs[1..]) {
            let cell = [*x0, *y0, x1 - x0, y1 - y0];
            let mut here: Vec<&Part> = parts.iter().filter(|p| overlaps(p.info.window, cell)).collect();
            here.sort_by_key(|p| p.info.samples);
            for pair in here.windows(2) {
                let ((_, a1), (b0, b1)) = (pair[0].info.samples, pair[1].info.samples);
                if b0 < a1 {
                    return Err(PartError::Overlap {
                        first: pair[0].path.clone(),
                        other: pair[1].path.clone(),
                        what: format!("both hold samples {b0}–{} of {}", a1.min(b1), describe_rect(cell)),
                    });
                }
            }
            let ranges: Vec<(u32, u32)> = here.iter().map(|p| p.info.samples).collect();
            for gap in gaps(&ranges, base.spp) {
                let n = u64::from(cell[2]) * u64::from(cell[3]);
                match lacking.iter_mut().find(|(g, _, _)| *g == gap) {
                    Some((_, count, bbox)) => {
                        *count += n;
                        *bbox = union_rect(*bbox, cell);
                    }
                    None => lacking.push((gap, n, cell)),
                }
            }
            let contiguous = ranges.first().map(|r| (r.0, ranges.last().map_or(r.1, |l| l.1)));
            unions.push(contiguous.filter(|&(a, b)| ranges.iter().map(|r| r.1 - r.0).sum::<u32>() == b - a));
        }
    }
    let pixels = u64::from(iw) * u64::from(ih);
    let missing: Vec<String> = lacking
        .iter()
        .map(|&((a, b), count, bbox)| {
            let which = if count == pixels {
                "every pixel".to_string()
            } else if count == u64::from(bbox[2]) * u64::from(bbox[3]) {
                describe_rect(bbox)
            } else {
                format!("{count} pixels within {}", describe_rect(bbox))
            };
            format!("samples {a}–{b} of {which}{}", named_parts(parts, (a, b)))
        })
        .collect();
    if !missing.is_empty() && !allow_partial {
        return Err(PartError::Missing { missing });
    }
    let mut film = Film::new(iw, ih).with_aovs(first.film.aov_names.clone());
    let mut order: Vec<&Part> = parts.iter().collect();
    order.sort_by_key(|p| (p.info.samples, p.info.window));
    for p in order {
        film.add_part(&p.film, p.info.window, [ix, iy]);
    }
    // The merge is itself a part when every pixel holds the same contiguous samples.
    let info = match unions.first() {
        Some(Some(u)) if unions.iter().all(|v| *v == Some(*u)) => {
            Some(PartInfo { samples: *u, window: base.image, part_of: None, ..base.clone() })
        }
        _ => None,
    };
    Ok(Merged { film, alpha: first.alpha, info, missing, image: base.image })
}

/// The bounding box of two rectangles.
fn union_rect(a: [u32; 4], b: [u32; 4]) -> [u32; 4] {
    let (x0, y0) = (a[0].min(b[0]), a[1].min(b[1]));
    let (x1, y1) = ((a[0] + a[2]).max(b[0] + b[2]), (a[1] + a[3]).max(b[1] + b[3]));
    [x0, y0, x1 - x0, y1 - y0]
}

/// ` (part I/N, …)`: the parts of an `I/N` split whose samples lie in `range`, if the parts say
/// how they were split.
fn named_parts(parts: &[Part], range: (u32, u32)) -> String {
    let Some((_, n)) = parts.iter().find_map(|p| p.info.part_of) else { return String::new() };
    let spp = parts[0].info.spp;
    let names: Vec<String> = (1..=n)
        .filter(|&i| {
            let (a, b) = PartInfo::split(spp, i, n);
            a < b && a < range.1 && range.0 < b
        })
        .map(|i| format!("{i}/{n}"))
        .collect();
    match names.len() {
        0 => String::new(),
        1 => format!(" (part {})", names[0]),
        _ => format!(" (parts {})", names.join(", ")),
    }
}

impl fmt::Display for PartInfo {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "samples {}–{} of {} spp, {}", self.samples.0, self.samples.1, self.spp, describe_rect(self.window))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::filter::Filter;
    use crate::integrator::PathIntegrator;
    use crate::math::Rgb;
    use crate::render::{render, RenderSettings};
    use crate::scene::cornell::cornell_box;
    use std::sync::atomic::AtomicBool;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("neumann-part-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn info(samples: (u32, u32), window: [u32; 4], image: [u32; 4]) -> PartInfo {
        PartInfo {
            fingerprint: 0xfeed,
            scene: "cbox".into(),
            settings: "path, gaussian".into(),
            seed: 3,
            spp: 24,
            samples,
            window,
            image,
            part_of: None,
        }
    }

    /// Splits cover `[0, S)` with disjoint ranges differing in size by at most one.
    #[test]
    fn splits_are_disjoint_and_cover_the_samples() {
        for spp in 1..40 {
            for n in 1..=spp {
                let ranges: Vec<(u32, u32)> = (1..=n).map(|i| PartInfo::split(spp, i, n)).collect();
                assert_eq!(ranges[0].0, 0);
                assert_eq!(ranges[n as usize - 1].1, spp);
                assert!(ranges.windows(2).all(|p| p[0].1 == p[1].0));
                let sizes: Vec<u32> = ranges.iter().map(|r| r.1 - r.0).collect();
                assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1 && sizes.iter().all(|&s| s > 0));
            }
        }
    }

    /// Parts of a render split both by samples and by tiles, with a Gaussian filter (whose
    /// footprint crosses tile edges), written, read back and merged, equal the single render
    /// within float rounding: every channel within 2⁻²⁰ relative (a few f32 rounding units), the
    /// same sample counts and weights, and the same variance estimate.
    #[test]
    fn merge_of_a_split_equals_the_single_render() {
        split_and_merge(false);
        // With the film's border sampled, the tiles at the image's edge sample it too.
        split_and_merge(true);
    }

    fn split_and_merge(sample_border: bool) {
        let scene = cornell_box(30, 20).unwrap();
        let integrator = PathIntegrator::default();
        let never = AtomicBool::new(false);
        let image = [0, 0, 30, 20];
        let filter = Filter::gaussian(0.5).unwrap();
        let base = RenderSettings { spp: 24, seed: 3, filter, sample_border, ..Default::default() };
        let whole = render(&scene, &integrator, &base, &never).unwrap().film;
        let d = dir(&format!("split-{sample_border}"));
        let mut paths = Vec::new();
        // Samples 0–10 of the whole image; 10–24 in three tiles (one the full width).
        let pieces = [((0, 10), image), ((10, 24), [0, 0, 13, 9]), ((10, 24), [13, 0, 17, 9]), ((10, 24), [0, 9, 30, 11])];
        for (k, (samples, window)) in pieces.into_iter().enumerate() {
            let settings = RenderSettings {
                sample_range: Some(samples),
                window: Some(window),
                tile_of: Some(image),
                threads: 1 + k % 2,
                ..base.clone()
            };
            let film = render(&scene, &integrator, &settings, &never).unwrap().film;
            assert_eq!(film.spp_range(), (samples.1 - samples.0, samples.1 - samples.0));
            let path = d.join(format!("p{k}.exr"));
            write_part(&path, &film, &info(samples, window, image), false).unwrap();
            paths.push(path);
        }
        let parts: Vec<Part> = paths.iter().map(|p| read_part(p).unwrap()).collect();
        let merged = merge_parts(&parts, false).unwrap();
        assert!(merged.missing.is_empty());
        assert_eq!(merged.info.as_ref().map(|i| (i.samples, i.window)), Some(((0, 24), image)));
        assert_eq!(merged.film.sample_counts(), whole.sample_counts());
        let close = |a: f32, b: f32| (a - b).abs() <= b.abs() * 2f32.powi(-20) + 1e-30;
        let (m, w) = (merged.film.image(), whole.image());
        let mut identical = 0;
        for (i, (a, b)) in m.iter().zip(&w).enumerate() {
            for c in 0..3 {
                assert!(close(a[c], b[c]), "pixel {i} channel {c}: merged {} single {}", a[c], b[c]);
                identical += usize::from(a[c] == b[c]);
            }
        }
        assert!(identical > m.len(), "most values are bit-identical ({identical} of {})", 3 * m.len());
        for (a, b) in merged.film.variance_of_mean().iter().zip(whole.variance_of_mean()) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= 1e-4 * b[c].abs() + 1e-12, "variance {a} vs {b}");
            }
        }
        // Tiles rendered without their neighbours' samples (a plain crop window) would differ
        // at the tile edges: the margin is what makes them assemble.
        let crop = RenderSettings { window: Some([0, 0, 13, 9]), sample_border: false, ..base.clone() };
        let cropped = render(&scene, &integrator, &crop, &never).unwrap().film.image();
        assert!((0..9).any(|y| !close(cropped[y * 13 + 12].x, w[y * 30 + 12].x)), "the filter crosses the tile edge");
        // The merge is itself a part: written and merged alone it gives the same image.
        let again = d.join("merged.exr");
        write_part(&again, &merged.film, merged.info.as_ref().unwrap(), false).unwrap();
        let twice = merge_parts(&[read_part(&again).unwrap()], false).unwrap();
        for (a, b) in twice.film.image().iter().zip(&m) {
            assert!((0..3).all(|c| close(a[c], b[c])));
        }
        std::fs::remove_dir_all(&d).ok();
    }

    /// Parts of different renders, overlapping samples and missing ones are refused with what is
    /// wrong; `allow_partial` merges what exists; files that are not parts are located errors.
    #[test]
    fn merge_refuses_mismatches_and_names_what_is_missing() {
        let d = dir("refuse");
        let image = [0, 0, 8, 6];
        let film = |w: u32, h: u32, v: f32| {
            let mut f = Film::new(w, h);
            let buf = (0..w * h).map(|_| [f64::from(v); 3]).collect::<Vec<_>>();
            f.add_pass(&buf, 0);
            f
        };
        let write = |name: &str, info: &PartInfo, v: f32| {
            let path = d.join(name);
            write_part(&path, &film(info.window[2], info.window[3], v), info, false).unwrap();
            read_part(&path).unwrap()
        };
        let split = |i: u32, n: u32| PartInfo { part_of: Some((i, n)), ..info(PartInfo::split(24, i, n), image, image) };
        let p1 = write("p1.exr", &split(1, 3), 1.0);
        let p2 = write("p2.exr", &split(2, 3), 2.0);
        let p3 = write("p3.exr", &split(3, 3), 3.0);
        assert_eq!(p2.info, split(2, 3), "the header round-trips");
        let whole = merge_parts(&[p3.clone(), p1.clone(), p2.clone()], false).unwrap();
        assert_eq!(whole.film.image()[5], Rgb::splat(2.0), "weighted by samples");
        let e = merge_parts(&[p1.clone(), p3.clone()], false).unwrap_err().to_string();
        assert!(e.contains("missing: samples 8–16 of every pixel (part 2/3)"), "{e}");
        let partial = merge_parts(&[p1.clone(), p3.clone()], true).unwrap();
        assert_eq!((partial.missing.len(), partial.info.is_none()), (1, true), "a partial merge is not a part");
        let other_seed = write("seed.exr", &PartInfo { seed: 4, ..split(2, 3) }, 2.0);
        let e = merge_parts(&[p1.clone(), other_seed], false).unwrap_err().to_string();
        assert!(e.contains("parts of different renders: the seeds differ (3 and 4)"), "{e}");
        let other_scene = write("scene.exr", &PartInfo { fingerprint: 1, ..split(2, 3) }, 2.0);
        let e = merge_parts(&[p1.clone(), other_scene], false).unwrap_err().to_string();
        assert!(e.contains("the scenes differ"), "{e}");
        let e = merge_parts(&[p1.clone(), p1.clone()], false).unwrap_err().to_string();
        assert!(e.contains("overlap: both hold samples 0–8 of pixels x 0–8, y 0–6"), "{e}");
        let tile = write("tile.exr", &info((0, 24), [0, 0, 4, 6], image), 1.0);
        let e = merge_parts(std::slice::from_ref(&tile), false).unwrap_err().to_string();
        assert!(e.contains("samples 0–24 of pixels x 4–8, y 0–6"), "{e}");
        let e = merge_parts(&[tile, p2], false).unwrap_err().to_string();
        assert!(e.contains("overlap: both hold samples 8–16 of pixels x 0–4"), "{e}");
        assert!(matches!(merge_parts(&[], false), Err(PartError::Empty)));
        // Not parts: a plain image, a truncated part, a missing file.
        let plain = d.join("plain.exr");
        super::super::output::write_image(&plain, 2, 2, &[Rgb::ONE; 4], &Default::default()).unwrap();
        let e = read_part(&plain).unwrap_err().to_string();
        assert!(e.contains("not a part of a split render"), "{e}");
        let bytes = std::fs::read(d.join("p1.exr")).unwrap();
        for n in [0, 100, bytes.len() / 2, bytes.len() - 1] {
            std::fs::write(d.join("cut.exr"), &bytes[..n]).unwrap();
            assert!(read_part(&d.join("cut.exr")).is_err(), "{n} bytes");
        }
        assert!(read_part(&d.join("none.exr")).is_err());
        assert!(write_part(&d.join("p.png"), &film(8, 6, 1.0), &split(1, 3), false).is_err(), "parts are EXR");
        std::fs::remove_dir_all(&d).ok();
    }
}
