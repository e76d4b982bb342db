//! Sparse float grids as NanoVDB stores them (file format major version 32, the layout of
//! OpenVDB 8.1 onward and of pbrt-v4-scenes' `.nvdb` files): a root table of tiles, each a value
//! or an upper node of 32³ entries; an upper entry is a value or a lower node of 16³; a lower
//! entry is a value or a leaf of 8³ voxels. An entry's children are byte offsets from the node
//! that holds them. [`NanoGrid`] keeps the grid's bytes as the file holds them (decompressed),
//! checks every child link once when built, and then reads voxels through the tree.
//!
//! Index space: voxel `(i, j, k)` sits at integer coordinates; the grid's affine map takes index
//! to world coordinates (its "world" is the space of whoever places the grid: pbrt-v4's medium
//! space). [`NanoGrid::sample`] interpolates as NanoVDB's `SampleFromVoxels<…, 1, false>` (the
//! eight voxels around `⌊x⌋`, trilinear weights `x − ⌊x⌋`), which pbrt-v4's `nanovdb` medium
//! uses. Reading the file (segments, codecs, grid names) is `load::nanovdb`'s job.

use std::collections::HashMap;

/// `"NanoVDB0"`, little-endian: the first eight bytes of a grid (and of a file segment).
pub const MAGIC: u64 = 0x3042_4456_6f6e_614e;
/// The format's major version this reader knows (its layout is fixed within a major version).
pub const MAJOR_VERSION: u32 = 32;

const GRID_DATA: usize = 672;
const TREE_DATA: usize = 64;
const ROOT_HEADER: usize = 64;
const ROOT_TILE: usize = 32;
/// Header of an internal node of 2^(3·log2dim) entries: box (24 B), flags (8 B), value and child
/// masks, minimum, maximum, average, deviation (4 B each), padded to 32 bytes.
const fn internal_header(log2dim: u32) -> usize {
    let mask = (1usize << (3 * log2dim)) / 8;
    (24 + 8 + 2 * mask + 16 + 31) & !31
}
const UPPER_HEADER: usize = internal_header(5);
const LOWER_HEADER: usize = internal_header(4);
const UPPER_BYTES: usize = UPPER_HEADER + 8 * 32 * 32 * 32;
const LOWER_BYTES: usize = LOWER_HEADER + 8 * 16 * 16 * 16;
/// A float leaf: origin (12 B), box extent (3 B), flags (1 B), value mask (64 B), statistics
/// (16 B), then 512 values, x slowest.
const LEAF_VALUES: usize = 96;
const LEAF_BYTES: usize = LEAF_VALUES + 4 * 512;

/// What a lookup reached: a constant value (a tile, or the background), or a leaf (its byte
/// offset).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Node {
    Value(f32),
    Leaf(usize),
}

/// A root tile: its key (the coordinates' top 20 bits), and its upper node or value.
#[derive(Clone, Copy, Debug)]
struct RootTile {
    key: u64,
    node: Result<usize, f32>,
}

/// One NanoVDB grid of 32-bit floats (`GridType::Float`).
#[derive(Clone, Debug)]
pub struct NanoGrid {
    name: String,
    /// NanoVDB's grid class (0 unknown, 1 level set, 2 fog volume, …).
    class: u32,
    bytes: Vec<u8>,
    /// Root tiles by key.
    tiles: Vec<RootTile>,
    background: f32,
    /// Index to world: `world = m · ijk + t`; world to index: `inv · (world − t)` (the map's
    /// single-precision half, which pbrt-v4's `worldToIndexF` reads).
    m: [f32; 9],
    inv: [f32; 9],
    t: [f32; 3],
    index_bbox: [[i32; 3]; 2],
    world_bbox: [[f64; 3]; 2],
    /// Byte offset of the first leaf (leaves lie contiguously after it).
    first_leaf: usize,
    /// The largest of each leaf's 512 values (active or not), by leaf number.
    leaf_max: Vec<f32>,
    /// The largest value in each upper and lower node (its tiles and children), by byte offset.
    node_max: HashMap<usize, f32>,
    min: f32,
    max: f32,
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    b.get(o..o + 4).map_or(0, |s| u32::from_le_bytes(s.try_into().expect("4 bytes")))
}
fn u64_at(b: &[u8], o: usize) -> u64 {
    b.get(o..o + 8).map_or(0, |s| u64::from_le_bytes(s.try_into().expect("8 bytes")))
}
fn f32_at(b: &[u8], o: usize) -> f32 {
    f32::from_bits(u32_at(b, o))
}
fn f64_at(b: &[u8], o: usize) -> f64 {
    f64::from_bits(u64_at(b, o))
}
fn i32_at(b: &[u8], o: usize) -> i32 {
    u32_at(b, o) as i32
}
fn bit(b: &[u8], mask: usize, n: usize) -> bool {
    u64_at(b, mask + 8 * (n >> 6)) >> (n & 63) & 1 == 1
}

/// The root key of voxel `ijk` (each coordinate's bits above the upper node's 4096³).
fn root_key(ijk: [i32; 3]) -> u64 {
    let top = |c: i32| (c as u32 >> 12) as u64;
    top(ijk[2]) | top(ijk[1]) << 21 | top(ijk[0]) << 42
}
/// The origin (smallest voxel) of the root cell of key `key`.
fn key_origin(key: u64) -> [i32; 3] {
    let c = |shift: u32| (((key >> shift) & 0x1f_ffff) << 12) as u32 as i32;
    [c(42), c(21), c(0)]
}
fn upper_entry(ijk: [i32; 3]) -> usize {
    let e = |c: i32| ((c & 4095) >> 7) as usize;
    e(ijk[0]) << 10 | e(ijk[1]) << 5 | e(ijk[2])
}
fn lower_entry(ijk: [i32; 3]) -> usize {
    let e = |c: i32| ((c & 127) >> 3) as usize;
    e(ijk[0]) << 8 | e(ijk[1]) << 4 | e(ijk[2])
}
fn leaf_entry(ijk: [i32; 3]) -> usize {
    let e = |c: i32| (c & 7) as usize;
    e(ijk[0]) << 6 | e(ijk[1]) << 3 | e(ijk[2])
}

impl NanoGrid {
    /// A grid from its bytes (a NanoVDB `GridData` and what follows it), checked: the magic
    /// number, major version 32, a float grid, and every node of the tree inside the buffer where
    /// its parent says. Errors say what is wrong.
    pub fn from_bytes(bytes: Vec<u8>) -> Result<NanoGrid, String> {
        let b = &bytes[..];
        if b.len() < GRID_DATA + TREE_DATA + ROOT_HEADER {
            return Err(format!("a NanoVDB grid of {} bytes is too short for its headers", b.len()));
        }
        if u64_at(b, 0) != MAGIC {
            return Err("not a NanoVDB grid (its magic number is not \"NanoVDB0\")".into());
        }
        let version = u32_at(b, 16);
        let major = version >> 21;
        if major != MAJOR_VERSION {
            return Err(format!(
                "NanoVDB format version {}.{}.{}: neumann reads version {MAJOR_VERSION} (OpenVDB 8.1 onward; \
                 convert older files with that version's nanovdb_convert)",
                major,
                version >> 10 & 2047,
                version & 1023
            ));
        }
        let nul = b[40..296].iter().position(|&c| c == 0).unwrap_or(256);
        let name = String::from_utf8_lossy(&b[40..40 + nul]).into_owned();
        let grid_type = u32_at(b, 636);
        if grid_type != 1 {
            const TYPES: [&str; 10] =
                ["Unknown", "Float", "Double", "Int16", "Int32", "Int64", "Vec3f", "Vec3d", "Mask", "Half"];
            let ty = TYPES.get(grid_type as usize).map_or_else(|| format!("type {grid_type}"), |t| t.to_string());
            return Err(format!("grid \"{name}\" holds {ty} values: neumann reads grids of 32-bit floats"));
        }
        let class = u32_at(b, 632);
        let read9 = |o: usize| std::array::from_fn(|k| f32_at(b, o + 4 * k));
        let (m, inv) = (read9(296), read9(332));
        let t = std::array::from_fn(|k| f32_at(b, 368 + 4 * k));
        let world_bbox = [0, 1].map(|c| std::array::from_fn(|k| f64_at(b, 560 + 24 * c + 8 * k)));
        if !(m.iter().chain(&inv).chain(&t).all(|x| x.is_finite())) {
            return Err(format!("grid \"{name}\" has a non-finite index-to-world map"));
        }
        let tree = GRID_DATA;
        let offset = |k: usize| usize::try_from(u64_at(b, tree + 8 * k)).ok().and_then(|o| o.checked_add(tree));
        let (Some(first_leaf), Some(root)) = (offset(0), offset(3)) else {
            return Err(format!("grid \"{name}\": node offsets outside the grid"));
        };
        let leaf_count = u32_at(b, tree + 32) as usize;
        let fits = |at: usize, len: usize| at.checked_add(len).is_some_and(|end| end <= b.len());
        if !fits(root, ROOT_HEADER) {
            return Err(format!("grid \"{name}\": its root node lies outside the grid"));
        }
        let index_bbox = [0, 1].map(|c| std::array::from_fn(|k| i32_at(b, root + 12 * c + 4 * k)));
        let table = u32_at(b, root + 24) as usize;
        let background = f32_at(b, root + 28);
        if !fits(root + ROOT_HEADER, table.saturating_mul(ROOT_TILE)) {
            return Err(format!("grid \"{name}\": its root table of {table} tiles overruns the grid"));
        }
        let bad = |what: &str| format!("grid \"{name}\": a {what} lies outside the grid or off its alignment");
        let child = |parent: usize, at: usize, len: usize| -> Option<usize> {
            let c = u64_at(b, at) as i64;
            let abs = (parent as i64).checked_add(c)?;
            let abs = usize::try_from(abs).ok()?;
            (abs % 32 == 0 && fits(abs, len)).then_some(abs)
        };
        // Leaves lie in one array from `first_leaf`; its length is bounded by the buffer.
        if first_leaf > b.len() || leaf_count > (b.len() - first_leaf) / LEAF_BYTES {
            return Err(format!("grid \"{name}\": its {leaf_count} leaves overrun the grid"));
        }
        let mut tiles = Vec::with_capacity(table);
        let (mut min, mut max) = (background, background);
        let mut leaf_max = vec![f32::NEG_INFINITY; leaf_count];
        // Each node is checked once however many parents name it (its largest value kept):
        // the work stays bounded by the buffer's size.
        let mut node_max: HashMap<usize, f32> = HashMap::new();
        let mut finite = background.is_finite();
        let mut extend = |v: f32, m: &mut f32| {
            min = min.min(v);
            max = max.max(v);
            *m = m.max(v);
            v.is_finite()
        };
        for n in 0..table {
            let at = root + ROOT_HEADER + n * ROOT_TILE;
            let key = u64_at(b, at);
            if u64_at(b, at + 8) == 0 {
                let v = f32_at(b, at + 20);
                let mut unused = f32::NEG_INFINITY;
                finite &= extend(v, &mut unused);
                tiles.push(RootTile { key, node: Err(v) });
                continue;
            }
            let upper = child(root, at + 8, UPPER_BYTES).ok_or_else(|| bad("upper node"))?;
            tiles.push(RootTile { key, node: Ok(upper) });
            if node_max.contains_key(&upper) {
                continue;
            }
            let mut upper_max = f32::NEG_INFINITY;
            for u in 0..32 * 32 * 32 {
                let entry = upper + UPPER_HEADER + 8 * u;
                if !bit(b, upper + 32 + 4096, u) {
                    finite &= extend(f32_at(b, entry), &mut upper_max);
                    continue;
                }
                let lower = child(upper, entry, LOWER_BYTES).ok_or_else(|| bad("lower node"))?;
                if let Some(&m) = node_max.get(&lower) {
                    upper_max = upper_max.max(m);
                    continue;
                }
                let mut lower_max = f32::NEG_INFINITY;
                for l in 0..16 * 16 * 16 {
                    let entry = lower + LOWER_HEADER + 8 * l;
                    if !bit(b, lower + 32 + 512, l) {
                        finite &= extend(f32_at(b, entry), &mut lower_max);
                        continue;
                    }
                    let leaf = child(lower, entry, LEAF_BYTES).ok_or_else(|| bad("leaf"))?;
                    let k = leaf.checked_sub(first_leaf).filter(|d| d % LEAF_BYTES == 0).map(|d| d / LEAF_BYTES);
                    let Some(k) = k.filter(|&k| k < leaf_count) else { return Err(bad("leaf")) };
                    if leaf_max[k] == f32::NEG_INFINITY {
                        let values = &b[leaf + LEAF_VALUES..leaf + LEAF_BYTES];
                        let mut lm = f32::NEG_INFINITY;
                        for v in values.chunks_exact(4) {
                            finite &= extend(f32::from_le_bytes(v.try_into().expect("4 bytes")), &mut lm);
                        }
                        leaf_max[k] = lm;
                    }
                    lower_max = lower_max.max(leaf_max[k]);
                }
                node_max.insert(lower, lower_max);
                upper_max = upper_max.max(lower_max);
            }
            node_max.insert(upper, upper_max);
        }
        if !finite {
            return Err(format!("grid \"{name}\" holds values that are not finite (NaN or infinite)"));
        }
        tiles.sort_by_key(|t| t.key);
        Ok(NanoGrid {
            name,
            class,
            bytes,
            tiles,
            node_max,
            background,
            m,
            inv,
            t,
            index_bbox,
            world_bbox,
            first_leaf,
            leaf_max,
            min,
            max,
        })
    }

    /// The grid's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its class's name if it is neither a fog volume nor unclassified (pbrt-v4 reads densities
    /// and temperatures only from those): `"level set"`, …
    pub fn unfit_class(&self) -> Option<String> {
        const CLASSES: [&str; 9] = [
            "unknown",
            "level set",
            "fog volume",
            "staggered grid",
            "point index grid",
            "point data grid",
            "topology grid",
            "voxel volume",
            "index grid",
        ];
        match self.class {
            0 | 2 => None,
            c => Some(CLASSES.get(c as usize).map_or_else(|| format!("class {c}"), |s| s.to_string())),
        }
    }

    /// The box of its active voxels in index space, bounds included (NanoVDB's `indexBBox`).
    pub fn index_bbox(&self) -> [[i32; 3]; 2] {
        self.index_bbox
    }

    /// The box of its active voxels' centres in world space (NanoVDB's `worldBBox`: the map's
    /// image of the index box's corners).
    pub fn world_bbox(&self) -> [[f64; 3]; 2] {
        self.world_bbox
    }

    /// The smallest and largest value anywhere (every voxel, tile and the background).
    pub fn range(&self) -> (f32, f32) {
        (self.min, self.max)
    }

    /// World point `p` in index coordinates (NanoVDB's `worldToIndexF`).
    #[inline]
    pub fn world_to_index(&self, p: [f32; 3]) -> [f32; 3] {
        let d = [p[0] - self.t[0], p[1] - self.t[1], p[2] - self.t[2]];
        let r = |k: usize| self.inv[3 * k] * d[0] + self.inv[3 * k + 1] * d[1] + self.inv[3 * k + 2] * d[2];
        [r(0), r(1), r(2)]
    }

    /// Index point `x` in world coordinates (NanoVDB's `indexToWorldF`).
    pub fn index_to_world(&self, x: [f32; 3]) -> [f32; 3] {
        let r = |k: usize| self.m[3 * k] * x[0] + self.m[3 * k + 1] * x[1] + self.m[3 * k + 2] * x[2] + self.t[k];
        [r(0), r(1), r(2)]
    }

    /// The node that holds voxel `ijk`: its leaf, or the value of the tile (or background) that
    /// covers it.
    #[inline]
    fn node(&self, ijk: [i32; 3]) -> Node {
        let b = &self.bytes[..];
        let key = root_key(ijk);
        let upper = match self.tiles.binary_search_by_key(&key, |t| t.key) {
            Err(_) => return Node::Value(self.background),
            Ok(n) => match self.tiles[n].node {
                Err(v) => return Node::Value(v),
                Ok(upper) => upper,
            },
        };
        let u = upper_entry(ijk);
        let entry = upper + UPPER_HEADER + 8 * u;
        if !bit(b, upper + 32 + 4096, u) {
            return Node::Value(f32_at(b, entry));
        }
        let lower = (upper as i64 + u64_at(b, entry) as i64) as usize;
        let l = lower_entry(ijk);
        let entry = lower + LOWER_HEADER + 8 * l;
        if !bit(b, lower + 32 + 512, l) {
            return Node::Value(f32_at(b, entry));
        }
        Node::Leaf((lower as i64 + u64_at(b, entry) as i64) as usize)
    }

    /// The value of voxel `ijk` (the background where nothing is stored).
    #[inline]
    pub fn value(&self, ijk: [i32; 3]) -> f32 {
        match self.node(ijk) {
            Node::Value(v) => v,
            Node::Leaf(leaf) => f32_at(&self.bytes, leaf + LEAF_VALUES + 4 * leaf_entry(ijk)),
        }
    }

    /// The trilinear interpolation of the voxels around index point `x` (NanoVDB's
    /// `SampleFromVoxels<…, 1, false>`); the background far outside, 0 at non-finite points.
    #[inline]
    pub fn sample(&self, x: [f32; 3]) -> f32 {
        let f = x.map(crate::math::floor);
        if !f.iter().all(|c| c.abs() < 2.0e9) {
            return if x.iter().all(|c| c.is_finite()) { self.background } else { 0.0 };
        }
        let ijk = f.map(|c| c as i32);
        let w = [x[0] - f[0], x[1] - f[1], x[2] - f[2]];
        let mut v = [[[0.0f32; 2]; 2]; 2];
        if ijk.iter().all(|&c| c & 7 != 7) {
            // The eight voxels share a node (7 times in 10 for points spread evenly).
            match self.node(ijk) {
                Node::Value(c) => return c,
                Node::Leaf(leaf) => {
                    let base = leaf + LEAF_VALUES + 4 * leaf_entry(ijk);
                    for (a, va) in v.iter_mut().enumerate() {
                        for (bb, vb) in va.iter_mut().enumerate() {
                            for (c, vc) in vb.iter_mut().enumerate() {
                                *vc = f32_at(&self.bytes, base + 4 * (a << 6 | bb << 3 | c));
                            }
                        }
                    }
                }
            }
        } else {
            for (a, va) in v.iter_mut().enumerate() {
                for (bb, vb) in va.iter_mut().enumerate() {
                    for (c, vc) in vb.iter_mut().enumerate() {
                        let at = |k: usize, d: usize| ijk[k].wrapping_add(d as i32);
                        *vc = self.value([at(0, a), at(1, bb), at(2, c)]);
                    }
                }
            }
        }
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let along_z = |a: usize, bb: usize| lerp(v[a][bb][0], v[a][bb][1], w[2]);
        let along_y = |a: usize| lerp(along_z(a, 0), along_z(a, 1), w[1]);
        lerp(along_y(0), along_y(1), w[0])
    }

    /// An upper bound of every voxel value in the index box `lo`–`hi` (bounds included): the
    /// largest value of each 8³ block the box touches (a leaf's largest voxel, or the covering
    /// tile's value), found through the tree — a node inside the box by its largest value,
    /// space no root tile covers by the background — so the work follows the nodes the box
    /// cuts, not its volume.
    pub fn max_in(&self, lo: [i32; 3], hi: [i32; 3]) -> f32 {
        if (0..3).any(|k| lo[k] > hi[k]) {
            return f32::NEG_INFINITY;
        }
        // The root cells (4096³) the box touches; any not covered by a tile reads the background.
        let cells: i64 = (0..3).map(|k| ((hi[k] >> 12) as i64 - (lo[k] >> 12) as i64) + 1).product();
        let mut max = f32::NEG_INFINITY;
        let mut covered = 0i64;
        for t in &self.tiles {
            let o = key_origin(t.key);
            if (0..3).any(|k| o[k] as i64 + 4095 < lo[k] as i64 || o[k] > hi[k]) {
                continue;
            }
            covered += 1;
            max = max.max(match t.node {
                Err(v) => v,
                Ok(upper) => self.node_max_in(upper, o, 12, lo, hi),
            });
        }
        if covered < cells {
            max = max.max(self.background);
        }
        max
    }

    /// [`NanoGrid::max_in`] within the internal node at byte offset `node` whose children are
    /// `2^child_log2` voxels wide (upper: 7, lower: 3) and whose origin is `o`; `log2` its own width.
    fn node_max_in(&self, node: usize, o: [i32; 3], log2: u32, lo: [i32; 3], hi: [i32; 3]) -> f32 {
        let width = 1i64 << log2;
        if (0..3).all(|k| lo[k] as i64 <= o[k] as i64 && o[k] as i64 + width - 1 <= hi[k] as i64) {
            return self.node_max.get(&node).copied().unwrap_or(f32::INFINITY);
        }
        let b = &self.bytes[..];
        let (dim_log2, header, child_log2) = if log2 == 12 { (5, UPPER_HEADER, 7) } else { (4, LOWER_HEADER, 3) };
        let mask = node + 32 + (1usize << (3 * dim_log2)) / 8;
        // The child cells the box touches, per axis.
        let range = |k: usize| {
            let a = ((lo[k] as i64 - o[k] as i64).max(0) >> child_log2) as usize;
            let z = ((hi[k] as i64 - o[k] as i64).min(width - 1) >> child_log2) as usize;
            a..=z
        };
        let mut max = f32::NEG_INFINITY;
        for i in range(0) {
            for j in range(1) {
                for k in range(2) {
                    let n = i << (2 * dim_log2) | j << dim_log2 | k;
                    let entry = node + header + 8 * n;
                    if !bit(b, mask, n) {
                        max = max.max(f32_at(b, entry));
                        continue;
                    }
                    let child = (node as i64 + u64_at(b, entry) as i64) as usize;
                    max = max.max(if log2 == 12 {
                        let co = [i, j, k].map(|c| (c as i32) << child_log2);
                        let co = [o[0] + co[0], o[1] + co[1], o[2] + co[2]];
                        self.node_max_in(child, co, 7, lo, hi)
                    } else {
                        self.leaf_max[(child - self.first_leaf) / LEAF_BYTES]
                    });
                }
            }
        }
        max
    }
}
