//! Files that a scene format decoded itself — glTF's meshes in binary buffers and its embedded
//! or referenced images — found by name by the shape and texture plugins, as files on disk are:
//! the `mesh` shape's `filename` and a bitmap's `filename` name them.

use crate::geometry::TriangleMesh;
use crate::image::Image;
use crate::math::color::srgb_decode;
use crate::math::Rgb;
use std::collections::HashMap;

/// A decoded 8- or 16-bit image's values as stored, in [0, 1] (not yet sRGB-decoded), with
/// alpha (1 where the file has none).
#[derive(Clone, Debug)]
pub struct EncodedImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA, row-major from the top-left.
    pub rgba: Vec<[f32; 4]>,
    /// Whether the colour is linear already (an image a scene format made from its own
    /// values), never sRGB-decoded; else it is as an 8- or 16-bit file stores it.
    pub linear: bool,
}

/// One channel of an [`EncodedImage`], or its colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    /// Red, green and blue (sRGB-decoded unless read raw).
    Rgb,
    /// One channel as a grey image (always raw: data such as roughness or opacity).
    Single(usize),
}

impl EncodedImage {
    /// The linear image of `channel`: the colour sRGB-decoded unless `raw`; a single channel as
    /// grey, as stored.
    pub fn image(&self, channel: Channel, raw: bool) -> Image {
        let pixels = self
            .rgba
            .iter()
            .map(|p| match channel {
                Channel::Rgb if raw || self.linear => Rgb::new(p[0], p[1], p[2]),
                Channel::Rgb => Rgb::new(srgb_decode(p[0]), srgb_decode(p[1]), srgb_decode(p[2])),
                Channel::Single(c) => Rgb::splat(p[c.min(3)]),
            })
            .collect();
        Image { width: self.width, height: self.height, pixels }
    }
}

/// The decoded files of one scene, by name.
#[derive(Debug, Default)]
pub struct MemoryFiles {
    /// Meshes (the `mesh` shape's `filename`).
    pub meshes: HashMap<String, TriangleMesh>,
    /// Images (a bitmap's `filename`: the name, or `name#r`, `#g`, `#b`, `#a` for one channel).
    pub images: HashMap<String, EncodedImage>,
    /// Grid volumes (a `gridvolume`'s `filename`: pbrt-v4's grid media, written inline).
    pub volumes: HashMap<String, std::sync::Arc<crate::image::GridVolume>>,
    /// Curves (the `curve` shape's `filename`: pbrt-v4's curves).
    pub curves: HashMap<String, crate::geometry::CurveSet>,
}

impl MemoryFiles {
    /// The image that the bitmap file name `name` (with its optional channel suffix) names.
    pub fn image(&self, name: &str, raw: bool) -> Option<Image> {
        let (base, channel) = match name.rsplit_once('#') {
            Some((base, c)) => (base, Channel::Single(["r", "g", "b", "a"].iter().position(|x| *x == c)?)),
            None => (name, Channel::Rgb),
        };
        Some(self.images.get(base)?.image(channel, raw))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_and_decoding() {
        let mut files = MemoryFiles::default();
        files.images.insert(
            "img".into(),
            EncodedImage { width: 1, height: 1, rgba: vec![[0.5, 0.25, 1.0, 0.75]], linear: false },
        );
        let rgb = files.image("img", false).unwrap().pixels[0];
        assert!((rgb.x - srgb_decode(0.5)).abs() < 1e-7 && rgb.z == 1.0);
        assert_eq!(files.image("img", true).unwrap().pixels[0], Rgb::new(0.5, 0.25, 1.0));
        assert_eq!(files.image("img#a", false).unwrap().pixels[0], Rgb::splat(0.75));
        assert_eq!(files.image("img#g", false).unwrap().pixels[0], Rgb::splat(0.25));
        assert!(files.image("img#x", false).is_none() && files.image("other", false).is_none());
    }
}
