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
