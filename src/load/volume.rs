//! Mitsuba's binary grid volumes (`.vol`), the data of `sdfgrid` shapes (and of grid media).
//! Layout (little-endian): the bytes `V`, `O`, `L` and the version 3; the encoding (i32: 1 =
//! float32, the only one Mitsuba 3 reads); the resolution x, y, z (i32 each); the channel count
//! (i32); the bounding box (6 × f32: min x, y, z, max x, y, z); then x·y·z·channels float32
//! values, x varying fastest, then y, then z, the channels of a point together.

use super::LoadError;
pub use crate::image::GridVolume;
use std::path::Path;

const HEADER_BYTES: usize = 48;

/// Reads the grid volume at `path`.
pub fn load_grid_volume(path: &Path) -> Result<GridVolume, LoadError> {
    let bytes = super::limits::read_bounded(path, super::limits::MAX_FILE_BYTES)?;
    parse_grid_volume(&bytes).map_err(|m| LoadError::format(path, m))
}

/// Parses the bytes of a `.vol` file.
pub fn parse_grid_volume(bytes: &[u8]) -> Result<GridVolume, String> {
    if bytes.len() < HEADER_BYTES {
        return Err(format!("a grid volume has a {HEADER_BYTES}-byte header, the file has {} bytes", bytes.len()));
    }
    if &bytes[..3] != b"VOL" {
        return Err("not a Mitsuba grid volume (the file does not start with \"VOL\")".into());
    }
    if bytes[3] != 3 {
        return Err(format!("grid volume version {} (only version 3 exists)", bytes[3]));
    }
    let i32_at = |k: usize| i32::from_le_bytes(bytes[4 + 4 * k..8 + 4 * k].try_into().expect("4 bytes"));
    let f32_at = |k: usize| f32::from_le_bytes(bytes[24 + 4 * k..28 + 4 * k].try_into().expect("4 bytes"));
    let encoding = i32_at(0);
    if encoding != 1 {
        return Err(format!("grid volume encoding {encoding} (Mitsuba 3 reads only 1, float32)"));
    }
    let dim = |k: usize, what: &str| -> Result<usize, String> {
        let v = i32_at(k);
        usize::try_from(v).ok().filter(|&v| v >= 1).ok_or_else(|| format!("the {what} must be ≥ 1, got {v}"))
    };
    let res = [dim(1, "x resolution")?, dim(2, "y resolution")?, dim(3, "z resolution")?];
    let channels = dim(4, "channel count")?;
    let count = res
        .iter()
        .chain(&[channels])
        .try_fold(1usize, |a, &b| a.checked_mul(b))
        .filter(|&n| n.checked_mul(4).is_some())
        .ok_or("the grid is too large")?;
    let expected = HEADER_BYTES + 4 * count;
    if bytes.len() != expected {
        return Err(format!(
            "a {}×{}×{} grid of {channels} channel(s) has {expected} bytes, the file has {}",
            res[0],
            res[1],
            res[2],
            bytes.len()
        ));
    }
    let bbox = [[f32_at(0), f32_at(1), f32_at(2)], [f32_at(3), f32_at(4), f32_at(5)]];
    let data = bytes[HEADER_BYTES..].chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes"))).collect();
    Ok(GridVolume { res, channels, bbox, data })
}

/// The bytes of a `.vol` file holding `volume` (for tests and tools).
pub fn grid_volume_bytes(volume: &GridVolume) -> Vec<u8> {
    let mut out = b"VOL\x03".to_vec();
    for v in [1, volume.res[0] as i32, volume.res[1] as i32, volume.res[2] as i32, volume.channels as i32] {
        out.extend(v.to_le_bytes());
    }
    for v in volume.bbox.iter().flatten().chain(&volume.data) {
        out.extend(v.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_hostile_input() {
        let v = GridVolume {
            res: [3, 2, 2],
            channels: 1,
            bbox: [[0.0; 3], [1.0; 3]],
            data: (0..12).map(|i| i as f32 * 0.5 - 2.0).collect(),
        };
        let bytes = grid_volume_bytes(&v);
        assert_eq!(parse_grid_volume(&bytes).unwrap(), v);
        // Truncated, wrong magic, version, encoding, sizes: errors, never panics or huge
        // allocations.
        for n in 0..bytes.len() {
            assert!(parse_grid_volume(&bytes[..n]).is_err(), "{n} bytes");
        }
        let mut bad = bytes.clone();
        bad[0] = b'X';
        assert!(parse_grid_volume(&bad).unwrap_err().contains("VOL"));
        let mut bad = bytes.clone();
        bad[4] = 2;
        assert!(parse_grid_volume(&bad).unwrap_err().contains("encoding 2"));
        let mut bad = bytes.clone();
        bad[8..12].copy_from_slice(&i32::MAX.to_le_bytes());
        bad[12..16].copy_from_slice(&i32::MAX.to_le_bytes());
        bad[16..20].copy_from_slice(&i32::MAX.to_le_bytes());
        assert!(parse_grid_volume(&bad).is_err());
        let mut bad = bytes;
        bad[8..12].copy_from_slice(&0i32.to_le_bytes());
        assert!(parse_grid_volume(&bad).unwrap_err().contains("≥ 1"));
    }
}
