//! NanoVDB files (`.nvdb`, format major version 32): one or more segments, each a 16-byte
//! header (the magic `"NanoVDB0"`, the version, the number of grids, the codec: none, ZIP or
//! Blosc), then per grid its 176-byte metadata and name, then the grids' buffers in order, each
//! as stored (`fileSize` bytes: raw, or a byte count and a zlib stream). The grids are
//! [`crate::image::nanovdb::NanoGrid`]s.

use super::LoadError;
use crate::image::nanovdb::{NanoGrid, MAGIC, MAJOR_VERSION};
use std::io::Read;
use std::path::Path;

const SEGMENT_HEADER: usize = 16;
const META_DATA: usize = 176;

/// One grid's metadata in a file.
#[derive(Clone, Debug)]
struct GridEntry {
    name: String,
    /// Bytes in memory (decompressed).
    grid_size: u64,
    /// Bytes in the file.
    file_size: u64,
    codec: u16,
    /// Where its stored bytes start.
    offset: usize,
}

/// The names of the grids in the NanoVDB file `bytes`, with where each is stored.
fn entries(bytes: &[u8]) -> Result<Vec<GridEntry>, String> {
    let u16_at = |o: usize| u16::from_le_bytes(bytes[o..o + 2].try_into().expect("2 bytes"));
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
    let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().expect("8 bytes"));
    let mut out = Vec::new();
    let mut at = 0usize;
    while at < bytes.len() {
        if bytes.len() - at < SEGMENT_HEADER {
            return Err(format!("the file ends inside a segment header at byte {at}"));
        }
        if u64_at(at) != MAGIC {
            return Err(if at == 0 {
                "not a NanoVDB file (it does not start with \"NanoVDB0\")".into()
            } else {
                format!("no NanoVDB segment header at byte {at}")
            });
        }
        let version = u32_at(at + 8);
        if version >> 21 != MAJOR_VERSION {
            return Err(format!(
                "NanoVDB format version {}.{}.{}: neumann reads version {MAJOR_VERSION} (OpenVDB 8.1 onward)",
                version >> 21,
                version >> 10 & 2047,
                version & 1023
            ));
        }
        let count = u16_at(at + 12) as usize;
        let codec = u16_at(at + 14);
        at += SEGMENT_HEADER;
        let mut segment = Vec::with_capacity(count);
        for _ in 0..count {
            if bytes.len() - at < META_DATA {
                return Err(format!("the file ends inside a grid's metadata at byte {at}"));
            }
            let (grid_size, file_size) = (u64_at(at), u64_at(at + 8));
            let name_size = u32_at(at + 136) as usize;
            at += META_DATA;
            if bytes.len() - at < name_size {
                return Err(format!("the file ends inside a grid's name at byte {at}"));
            }
            let name = &bytes[at..at + name_size];
            let name = String::from_utf8_lossy(name.split(|&c| c == 0).next().unwrap_or(&[])).into_owned();
            at += name_size;
            segment.push(GridEntry { name, grid_size, file_size, codec, offset: 0 });
        }
        for e in &mut segment {
            e.offset = at;
            let size = usize::try_from(e.file_size).ok().filter(|&s| s <= bytes.len() - at);
            let Some(size) = size else {
                return Err(format!(
                    "grid \"{}\" ({} bytes stored) runs past the end of the file",
                    e.name, e.file_size
                ));
            };
            at += size;
        }
        out.extend(segment);
    }
    Ok(out)
}

/// The bytes of grid `e` of the file `bytes`, decompressed.
fn grid_bytes(bytes: &[u8], e: &GridEntry) -> Result<Vec<u8>, String> {
    let stored = &bytes[e.offset..e.offset + e.file_size as usize];
    let size = usize::try_from(e.grid_size)
        .ok()
        .filter(|&s| s as u64 <= super::limits::MAX_FILE_BYTES)
        .ok_or_else(|| format!("grid \"{}\" of {} bytes is too large", e.name, e.grid_size))?;
    match e.codec {
        0 if stored.len() == size => Ok(stored.to_vec()),
        0 => Err(format!("grid \"{}\" stores {} bytes for a grid of {size}", e.name, stored.len())),
        1 => {
            // ZIP: the compressed byte count, then a zlib stream of the grid.
            if stored.len() < 8 {
                return Err(format!("grid \"{}\": its ZIP block is truncated", e.name));
            }
            let n = u64::from_le_bytes(stored[..8].try_into().expect("8 bytes"));
            let body = usize::try_from(n).ok().and_then(|n| stored.get(8..8 + n));
            let body = body.ok_or_else(|| format!("grid \"{}\": its ZIP block overruns the grid", e.name))?;
            // zlib expands at most ~1032:1: a size the metadata overstate is not allocated.
            let mut out = Vec::with_capacity(size.min(body.len().saturating_mul(1032)));
            flate2::read::ZlibDecoder::new(body)
                .take(size as u64 + 1)
                .read_to_end(&mut out)
                .map_err(|err| format!("grid \"{}\": its ZIP data do not decompress ({err})", e.name))?;
            if out.len() != size {
                return Err(format!("grid \"{}\" decompresses to {} bytes, its metadata say {size}", e.name, out.len()));
            }
            Ok(out)
        }
        2 => Err(format!(
            "grid \"{}\" is compressed with Blosc, which neumann does not read (rewrite it with nanovdb_convert's ZIP or no codec)",
            e.name
        )),
        c => Err(format!("grid \"{}\": unknown codec {c}", e.name)),
    }
}

/// The float grid named `grid` of the NanoVDB file bytes `bytes` (`None` if it has no grid of
/// that name).
pub fn parse_nanovdb(bytes: &[u8], grid: &str) -> Result<Option<NanoGrid>, String> {
    let all = entries(bytes)?;
    let Some(e) = all.iter().find(|e| e.name == grid) else { return Ok(None) };
    NanoGrid::from_bytes(grid_bytes(bytes, e)?).map(Some)
}

/// The names of the grids of the NanoVDB file bytes `bytes`, in file order.
pub fn grid_names(bytes: &[u8]) -> Result<Vec<String>, String> {
    Ok(entries(bytes)?.into_iter().map(|e| e.name).collect())
}

/// Reads the float grid named `grid` of the NanoVDB file at `path` (`None`: no such grid).
pub fn load_nanovdb(path: &Path, grid: &str) -> Result<Option<NanoGrid>, LoadError> {
    let bytes = super::limits::read_bounded(path, super::limits::MAX_FILE_BYTES)?;
    parse_nanovdb(&bytes, grid).map_err(|m| LoadError::format(path, m))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blob() -> Vec<u8> {
        std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/nanovdb/blob.nvdb")).expect("test file")
    }

    /// The reference lines of `blob_ref.txt`: world point, density, temperature.
    fn reference() -> (Vec<String>, Vec<[f32; 5]>) {
        let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/nanovdb/blob_ref.txt"))
            .expect("reference file");
        let comments = text.lines().filter(|l| l.starts_with('#')).map(str::to_string).collect();
        let rows = text
            .lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| {
                let v: Vec<f32> = l.split_whitespace().map(|x| x.parse().expect("number")).collect();
                [v[0], v[1], v[2], v[3], v[4]]
            })
            .collect();
        (comments, rows)
    }

    /// The same file with its grids stored without compression (the codec NONE path).
    fn uncompressed(bytes: &[u8]) -> Vec<u8> {
        let all = entries(bytes).unwrap();
        let mut out = bytes[..SEGMENT_HEADER].to_vec();
        out[14..16].copy_from_slice(&0u16.to_le_bytes());
        let mut at = SEGMENT_HEADER;
        let mut grids = Vec::new();
        for e in &all {
            let g = grid_bytes(bytes, e).unwrap();
            let mut meta = bytes[at..e.offset.min(at + META_DATA + 256)].to_vec();
            let name_size = u32::from_le_bytes(meta[136..140].try_into().unwrap()) as usize;
            meta.truncate(META_DATA + name_size);
            meta[8..16].copy_from_slice(&(g.len() as u64).to_le_bytes());
            meta[168..170].copy_from_slice(&0u16.to_le_bytes());
            at += META_DATA + name_size;
            out.extend(meta);
            grids.push(g);
        }
        for g in grids {
            out.extend(g);
        }
        out
    }

    #[test]
    fn reads_the_grids_nanovdb_wrote() {
        let bytes = blob();
        assert_eq!(grid_names(&bytes).unwrap(), ["density", "temperature"]);
        let (comments, rows) = reference();
        for data in [bytes.clone(), uncompressed(&bytes)] {
            let d = parse_nanovdb(&data, "density").unwrap().unwrap();
            let t = parse_nanovdb(&data, "temperature").unwrap().unwrap();
            assert!(parse_nanovdb(&data, "velocity").unwrap().is_none());
            // The boxes NanoVDB reported.
            for (g, line) in [(&d, &comments[1]), (&t, &comments[2])] {
                let w: Vec<&str> = line.split_whitespace().collect();
                let ints: Vec<i32> = w[3..9].iter().map(|x| x.parse().unwrap()).collect();
                let bb = g.index_bbox();
                assert_eq!([bb[0], bb[1]].concat(), ints, "{line}");
                let world: Vec<f64> = w[10..16].iter().map(|x| x.parse().unwrap()).collect();
                let wb = g.world_bbox();
                for (a, b) in [wb[0], wb[1]].concat().iter().zip(&world) {
                    assert!((a - b).abs() < 1e-6, "{line}");
                }
            }
            // NanoVDB's own trilinear lookups at 600 world points (125 inside the density).
            let mut inside = 0;
            for r in &rows {
                let p = [r[0], r[1], r[2]];
                for (g, want) in [(&d, r[3]), (&t, r[4])] {
                    let got = g.sample(g.world_to_index(p));
                    assert!((got - want).abs() <= 1e-5 * (1.0 + want.abs()), "{} at {p:?}: {got} vs {want}", g.name());
                }
                inside += (r[3] > 0.0) as u32;
            }
            assert!(inside > 100, "{inside}");
        }
    }

    /// Three voxels NanoVDB wrote at (1, 2, 3), (2, 2, 3), (1, 3, 4), voxel size ½: their values,
    /// the background elsewhere, the map, and interpolation between them.
    #[test]
    fn reads_single_voxels() {
        let bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/nanovdb/voxels.nvdb")).unwrap();
        let g = parse_nanovdb(&uncompressed(&bytes), "density").unwrap().unwrap();
        assert_eq!(g.unfit_class(), None);
        assert_eq!(g.index_bbox(), [[1, 2, 3], [2, 3, 4]]);
        assert_eq!(g.range(), (0.0, 2.0));
        assert_eq!((g.value([1, 2, 3]), g.value([2, 2, 3]), g.value([1, 3, 4])), (0.5, 1.5, 2.0));
        for ijk in [[0, 2, 3], [1, 2, 4], [-1, -2, -3], [1 << 20, 2, 3], [i32::MIN, i32::MAX, 0]] {
            assert_eq!(g.value(ijk), 0.0, "{ijk:?}");
        }
        assert_eq!(g.world_to_index([0.5, 1.0, 1.5]), [1.0, 2.0, 3.0]);
        assert_eq!(g.index_to_world([2.0, 2.0, 3.0]), [1.0, 1.0, 1.5]);
        assert_eq!(g.sample([1.25, 2.0, 3.0]), 0.75);
        assert_eq!(g.sample([1.0, 2.5, 3.5]), 0.25 * (0.5 + 2.0));
        assert_eq!(g.sample([1.5, 2.5, 3.5]), (0.5 + 1.5 + 2.0) / 8.0);
        // The leaf's corner: the stencil crosses into the next leaf (empty).
        assert_eq!(g.sample([7.5, 2.0, 3.0]), 0.0);
        assert_eq!(g.sample([f32::NAN, 0.0, 0.0]), 0.0);
        assert_eq!(g.max_in([0, 0, 0], [1, 1, 1]), 2.0, "the 8³ block holds all three");
        assert_eq!(g.max_in([8, 0, 0], [9, 1, 1]), 0.0);
        let mut level_set = uncompressed(&bytes);
        let at = entries(&level_set).unwrap()[0].offset + 632;
        level_set[at] = 1;
        let g = parse_nanovdb(&level_set, "density").unwrap().unwrap();
        assert_eq!(g.unfit_class().as_deref(), Some("level set"));
    }

    #[test]
    fn max_in_bounds_every_voxel_of_a_box() {
        let d = parse_nanovdb(&blob(), "density").unwrap().unwrap();
        let (lo, hi) = d.range();
        assert_eq!(lo, 0.0);
        let bb = d.index_bbox();
        let mut true_max = 0.0f32;
        for i in bb[0][0]..=bb[1][0] {
            for j in bb[0][1]..=bb[1][1] {
                for k in bb[0][2]..=bb[1][2] {
                    true_max = true_max.max(d.value([i, j, k]));
                }
            }
        }
        assert_eq!(true_max, hi);
        // Boxes of every size around the ball: the bound holds and is that of the 8³ blocks.
        let mut rng = crate::sampling::Pcg32::new(3, 1);
        for _ in 0..300 {
            let c: [i32; 3] = std::array::from_fn(|_| (rng.next_f32() * 40.0) as i32 - 20);
            let r: [i32; 3] = std::array::from_fn(|_| (rng.next_f32() * 9.0) as i32);
            let (a, b) = (std::array::from_fn(|k| c[k] - r[k]), std::array::from_fn(|k| c[k] + r[k]));
            let bound = d.max_in(a, b);
            let mut m = 0.0f32;
            let mut block_m = 0.0f32;
            for i in a[0]..=b[0] {
                for j in a[1]..=b[1] {
                    for k in a[2]..=b[2] {
                        m = m.max(d.value([i, j, k]));
                    }
                }
            }
            for i in (a[0] >> 3) * 8..(b[0] >> 3) * 8 + 8 {
                for j in (a[1] >> 3) * 8..(b[1] >> 3) * 8 + 8 {
                    for k in (a[2] >> 3) * 8..(b[2] >> 3) * 8 + 8 {
                        block_m = block_m.max(d.value([i, j, k]));
                    }
                }
            }
            assert!(bound >= m, "{a:?}–{b:?}: {bound} < {m}");
            assert_eq!(bound, block_m, "{a:?}–{b:?}");
        }
        // Boxes holding whole nodes (read by their maxima), a lower node's 128³ exactly, the
        // whole index space, and nothing but background.
        let block_max = |a: [i32; 3], b: [i32; 3]| {
            let mut m = f32::NEG_INFINITY;
            for i in (a[0] >> 3)..=(b[0] >> 3) {
                for j in (a[1] >> 3)..=(b[1] >> 3) {
                    for k in (a[2] >> 3)..=(b[2] >> 3) {
                        for v in 0..512 {
                            m = m.max(d.value([i * 8 + (v >> 6), j * 8 + (v >> 3 & 7), k * 8 + (v & 7)]));
                        }
                    }
                }
            }
            m
        };
        for (a, b) in [([0, 0, 0], [127, 127, 127]), ([-128, -128, -128], [-1, -1, -1]), ([-200, -3, -7], [5, 300, 4])]
        {
            assert_eq!(d.max_in(a, b), block_max(a, b), "{a:?}–{b:?}");
        }
        assert_eq!(d.max_in([i32::MIN / 2; 3], [i32::MAX / 2; 3]), hi);
        assert_eq!(d.max_in([1 << 20; 3], [(1 << 20) + 100; 3]), 0.0, "background only");
        assert_eq!(d.max_in([5000, -20, -20], [9000, 20, 20]), 0.0);
    }

    #[test]
    fn bad_files_are_errors() {
        let bytes = blob();
        let err = |b: &[u8]| parse_nanovdb(b, "density").unwrap_err();
        assert!(err(b"hello world, not a grid").contains("not a NanoVDB file"));
        assert!(err(&bytes[..100]).contains("ends inside"), "{}", err(&bytes[..100]));
        assert!(err(&bytes[..bytes.len() - 10]).contains("runs past the end"));
        let mut v = bytes.clone();
        v[8..12].copy_from_slice(&(29u32 << 21).to_le_bytes());
        assert!(err(&v).contains("version 29.0.0"), "{}", err(&v));
        let mut v = bytes.clone();
        v[14] = 2;
        assert!(err(&v).contains("Blosc"));
        // Metadata overstating a grid's size (3 GiB): an error, nothing that size allocated.
        let mut v = bytes.clone();
        v[SEGMENT_HEADER..SEGMENT_HEADER + 8].copy_from_slice(&(3u64 << 30).to_le_bytes());
        assert!(err(&v).contains("decompresses to"), "{}", err(&v));
        // A corrupted ZIP stream.
        let mut v = bytes.clone();
        let e = &entries(&bytes).unwrap()[0];
        for k in 0..64 {
            v[e.offset + 40 + k] ^= 0x5a;
        }
        assert!(err(&v).contains("ZIP"), "{}", err(&v));
        // Corrupt child offsets and grid types in an uncompressed copy: errors, never panics.
        let raw = uncompressed(&bytes);
        let e = &entries(&raw).unwrap()[0];
        let mut v = raw.clone();
        v[e.offset + 636] = 6;
        assert!(err(&v).contains("Vec3f"), "{}", err(&v));
        let mut rng = crate::sampling::Pcg32::new(11, 5);
        for _ in 0..200 {
            let mut v = raw.clone();
            for _ in 0..8 {
                let k = e.offset + (rng.next_f32() * e.grid_size as f32) as usize % e.grid_size as usize;
                v[k] = (rng.next_f32() * 256.0) as u8;
            }
            if let Ok(Some(g)) = parse_nanovdb(&v, "density") {
                for _ in 0..50 {
                    let x = std::array::from_fn(|_| rng.next_f32() * 60.0 - 30.0);
                    assert!(g.sample(x).is_finite());
                }
                let bb = g.index_bbox();
                let _ = g.max_in(bb[0], bb[1]);
            }
        }
    }
}
