//! Images in memory: linear RGB pixels, rows from the top. Textures and environment maps sample
//! them; decoding files into them is the job of `load::image`, which sits above the
//! renderer's layers.

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
/// Where plugins get their images: the loader resolves the file that the string parameter
/// `name` of `o` names (relative to the scene file), decodes it (linear RGB; sRGB-decoded unless
/// `raw`) and shares it between the plugins that name the same file.
pub trait ImageSource {
    /// The image named by parameter `name` of `o`; errors are located at the parameter.
    fn image(&mut self, o: &Obj, name: &str, raw: bool) -> Result<Arc<Image>>;
}
