//! Images in memory: linear RGB pixels, rows from the top, and grid volumes (values on a 3D
//! lattice: SDF grids, grid media). Textures, environment maps and shapes sample them; decoding
//! files into them is the job of `load::image` and `load::volume`, which sit above the
//! renderer's layers.

pub mod nanovdb;

use crate::math::Rgb;
use crate::props::{Obj, Result};
use std::sync::Arc;

/// A linear RGB image, rows from the top.
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row-major from the top-left.
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// Pixel at column `x`, row `y` (clamped to the image).
    #[inline]
    pub fn get(&self, x: i64, y: i64) -> Rgb {
        let x = x.clamp(0, self.width as i64 - 1) as usize;
        let y = y.clamp(0, self.height as i64 - 1) as usize;
        self.pixels[y * self.width as usize + x]
    }
}
/// A grid of values on a 3D lattice (Mitsuba's `.vol` grid volumes).
#[derive(Clone, Debug, PartialEq)]
pub struct GridVolume {
    /// Resolution along x, y and z (each ≥ 1).
    pub res: [usize; 3],
    /// Values per grid point.
    pub channels: usize,
    /// The bounding box the file states (min, max); Mitsuba's shapes ignore it.
    pub bbox: [[f32; 3]; 2],
    /// `res[0]·res[1]·res[2]·channels` values: index `((z·res[1] + y)·res[0] + x)·channels + c`.
    pub data: Vec<f32>,
}

/// Where plugins get their grid volumes: the loader resolves the file that the string parameter
/// `name` of `o` names (relative to the scene file), reads it (Mitsuba's `.vol` format) and shares
/// it between the plugins that name the same file.
pub trait VolumeSource {
    /// The grid volume named by parameter `name` of `o`; errors are located at the parameter.
    fn grid_volume(&mut self, o: &Obj, name: &str) -> Result<Arc<GridVolume>>;

    /// The float grid named `grid` of the NanoVDB file that the string parameter `name` of `o`
    /// names (`None` if the file has no grid of that name); errors are located at the parameter.
    fn nanovdb_grid(&mut self, o: &Obj, name: &str, grid: &str) -> Result<Option<Arc<nanovdb::NanoGrid>>>;

    /// Reports a warning (a complete line, `warning: FILE:LINE:COL: …`).
    fn warn(&mut self, line: String);
}

/// Where plugins get their images: the loader resolves the file that the string parameter
/// `name` of `o` names (relative to the scene file), decodes it (linear RGB; sRGB-decoded unless
/// `raw`) and shares it between the plugins that name the same file.
pub trait ImageSource {
    /// The image named by parameter `name` of `o`; errors are located at the parameter.
    fn image(&mut self, o: &Obj, name: &str, raw: bool) -> Result<Arc<Image>>;

    /// The image named by parameter `name` of `o` read as pbrt-v4 reads a float image texture
    /// (grey: the alpha where an RGBA image's is not all 1, else the mean of the colour), its
    /// 8- and 16-bit values decoded as sRGB, linear (`raw`) or by the power `gamma`.
    fn pbrt_scalar_image(&mut self, o: &Obj, name: &str, raw: bool, gamma: Option<f32>) -> Result<Arc<Image>>;
}

/// Checks that every chunk of the OpenEXR file at `path` declares no more data than the file
/// holds after the chunk's start. The decoder allocates a chunk's declared size (up to the
/// header's largest block, which a wide image makes gigabytes) before reading it, so a few bytes
/// claiming a huge chunk would otherwise take that memory. Reads the headers and offset tables
/// as the decoder does, then each chunk's size field at its offset.
pub fn exr_chunks_fit(path: &std::path::Path) -> std::result::Result<(), String> {
    use exr::meta::{header::Header, BlockDescription, MetaData, Requirements};
    use std::io::{Read, Seek, SeekFrom};
    let bad = |e: exr::error::Error| format!("not a readable OpenEXR file: {e}");
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read the file: {e}"))?;
    let len = file.metadata().map_err(|e| format!("cannot read the file: {e}"))?.len();
    // Headers through a buffered reader of the file, chunks by seeks on the file itself (a
    // `&File` reads and seeks; the seeks start from absolute offsets, wherever the buffer left it).
    let mut read = exr::io::PeekRead::new(std::io::BufReader::new(&file));
    exr::meta::magic_number::validate_exr(&mut read).map_err(bad)?;
    let requirements = Requirements::read(&mut read).map_err(bad)?;
    let headers = Header::read_all(&mut read, &requirements, false).map_err(bad)?;
    let tables = MetaData::read_offset_tables(&mut read, &headers).map_err(bad)?;
    drop(read);
    let mut file = &file;
    for (header, table) in headers.iter().zip(&tables) {
        // Before the data: the part number (multi-part files), the block's coordinates (a
        // scan line's y, or a tile's four coordinates), then its byte count(s).
        let part = if requirements.is_multilayer() { 4 } else { 0 };
        let coordinates = match header.blocks {
            BlockDescription::Tiles(_) => 16,
            BlockDescription::ScanLines => 4,
        };
        for &offset in table {
            let start = offset.checked_add(part + coordinates).filter(|&p| p <= len);
            let Some(start) = start else {
                return Err(format!("a chunk's offset {offset} lies beyond the file's {len} bytes"));
            };
            // Deep data: the sizes of the packed offset table and sample data (u64 each);
            // flat: the compressed pixels' size (i32).
            let mut field = [0u8; 16];
            let field = &mut field[..if header.deep { 16 } else { 4 }];
            file.seek(SeekFrom::Start(start))
                .and_then(|_| file.read_exact(field))
                .map_err(|_| format!("a chunk at offset {offset} is cut short by the end of the file"))?;
            let (declared, after) = if header.deep {
                let a = u64::from_le_bytes(field[..8].try_into().expect("8 bytes"));
                let b = u64::from_le_bytes(field[8..].try_into().expect("8 bytes"));
                (a.saturating_add(b), start + 24)
            } else {
                let size = i32::from_le_bytes(field.try_into().expect("4 bytes"));
                if size < 0 {
                    return Err(format!("a chunk at offset {offset} declares a negative size ({size} bytes)"));
                }
                (size as u64, start + 4)
            };
            let left = len.saturating_sub(after);
            if declared > left {
                return Err(format!(
                    "a chunk at offset {offset} declares {declared} bytes, more than the {left} the file holds after it"
                ));
            }
        }
    }
    Ok(())
}
