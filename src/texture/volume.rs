//! Volume textures: values over 3D space that parametrise heterogeneous media, blended phase
//! functions and Mitsuba's `volume` surface texture (Mitsuba's `<volume>` plugins `gridvolume`
//! and `constvolume`).
//!
//! Both live in the unit cube `[0, 1]³` of their local space, placed in the world by `to_world`.
//! Their world bounding box is Mitsuba 3.9.1's: the axis-aligned box of the images of the unit
//! cube's eight corners (under a rotation, larger than the rotated cube; there the values are
//! the wrap mode's, as Mitsuba looks them up). A medium built on a volume exists only inside
//! that box.
//!
//! `gridvolume` reads a `.vol` grid ([`crate::image::GridVolume`]; its stated bounding box is
//! ignored unless `use_grid_bbox` is set) and interpolates it as Dr.Jit's 3D textures do: texel
//! `i` is centred at `(i + ½) / res`; `trilinear` blends the eight texels around `p·res − ½`,
//! `nearest` takes texel `⌊p·res⌋`; indices outside the grid wrap by `wrap_mode` (`clamp`,
//! `repeat`, `mirror`).
//!
//! neumann's `nanovdb` reads a float grid of a NanoVDB file ([`crate::image::nanovdb`]) in the
//! volume's own space (where the grid's index-to-world map puts it: no unit cube), trilinearly
//! between voxel centres as NanoVDB samples, times a colour (pbrt-v4's `nanovdb` medium);
//! `blackbody` ([`super::blackbody`]) turns another volume's temperatures into radiance.

use crate::image::nanovdb::NanoGrid;
use crate::image::{GridVolume, VolumeSource};
use crate::math::spectrum::SpectrumKind;
use crate::math::{Bounds3, Rgb, Transform, Vec3};
use crate::props::{Obj, Result, SceneError, Value};
use std::sync::Arc;

/// How a grid is read between its texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridFilter {
    /// The nearest texel.
    Nearest,
    /// Trilinear interpolation of the eight nearest texels.
    Trilinear,
}

/// What indices outside the grid read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridWrap {
    /// The nearest edge texel.
    Clamp,
    /// The grid tiled.
    Repeat,
    /// The grid mirrored at its faces.
    Mirror,
    /// Zero outside the grid's texels (pbrt-v4's grids: the half texel along each face fades
    /// toward zero under trilinear filtering).
    Zero,
}

impl GridWrap {
    /// Index `i` mapped into `0..n` (`None`: outside, reading zero).
    #[inline]
    fn apply(self, i: i64, n: usize) -> Option<usize> {
        let n = n as i64;
        Some(match self {
            GridWrap::Zero if !(0..n).contains(&i) => return None,
            GridWrap::Zero => i,
            GridWrap::Clamp => i.clamp(0, n - 1),
            GridWrap::Repeat => i.rem_euclid(n),
            GridWrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m >= n {
                    2 * n - 1 - m
                } else {
                    m
                }
            }
        } as usize)
    }
}

/// A grid of one or three channels read as colours (one channel: grey), or of six read as
/// the six numbers of an SGGX matrix ([`Volume6`]).
#[derive(Clone, Debug)]
pub struct Grid {
    data: Arc<GridVolume>,
    filter: GridFilter,
    wrap: GridWrap,
}

impl Grid {
    /// The `N` channels of the texel at integer coordinates `i` (zero where outside the grid);
    /// the grid has `N` channels.
    #[inline]
    fn texel<const N: usize>(&self, i: [Option<usize>; 3]) -> [f32; N] {
        let [Some(x), Some(y), Some(z)] = i else { return [0.0; N] };
        let g = &*self.data;
        let k = ((z * g.res[1] + y) * g.res[0] + x) * g.channels;
        std::array::from_fn(|c| g.data[k + c])
    }

    /// The `N` channels at local point `p` (unit cube); the grid has `N` channels.
    #[inline]
    fn lookup<const N: usize>(&self, p: Vec3) -> [f32; N] {
        let res = self.data.res;
        let w = self.wrap;
        match self.filter {
            GridFilter::Nearest => {
                let i = [0, 1, 2].map(|a| w.apply(crate::math::floor(p[a] * res[a] as f32) as i64, res[a]));
                self.texel(i)
            }
            GridFilter::Trilinear => {
                let x = [0, 1, 2].map(|a| p[a] * res[a] as f32 - 0.5);
                let i0 = x.map(crate::math::floor);
                let f = [0, 1, 2].map(|a| x[a] - i0[a]);
                let lo = [0, 1, 2].map(|a| w.apply(i0[a] as i64, res[a]));
                let hi = [0, 1, 2].map(|a| w.apply((i0[a] as i64).saturating_add(1), res[a]));
                let mut v = [0.0; N];
                for corner in 0..8 {
                    let pick = |a: usize| corner >> a & 1 == 1;
                    let weight = (0..3).map(|a| if pick(a) { f[a] } else { 1.0 - f[a] }).product::<f32>();
                    if weight != 0.0 {
                        let i = [0, 1, 2].map(|a| if pick(a) { hi[a] } else { lo[a] });
                        let t = self.texel::<N>(i);
                        for c in 0..N {
                            v[c] += t[c] * weight;
                        }
                    }
                }
                v
            }
        }
    }

    /// The value at local point `p` (unit cube) as a colour (one channel: grey).
    #[inline]
    fn eval(&self, p: Vec3) -> Rgb {
        if self.data.channels == 1 {
            Rgb::splat(self.lookup::<1>(p)[0])
        } else {
            Rgb::from(self.lookup::<3>(p))
        }
    }
}

/// Where a volume's values come from.
#[derive(Clone, Debug)]
pub enum VolumeData {
    /// Mitsuba's `constvolume`: one value everywhere.
    Constant(Rgb),
    /// Mitsuba's `gridvolume`.
    Grid(Grid),
    /// neumann's `pbrt_cloud`: pbrt-v4's procedural cloud density (in [0, 1]) times a colour,
    /// looked up in the cloud's own space (not a unit cube: its box is given).
    Cloud(super::cloud::CloudDensity, Rgb),
    /// neumann's `nanovdb`: a NanoVDB float grid times a colour, looked up at the point's
    /// coordinates in the volume's own space (which the grid's map relates to its voxels).
    Nano(Arc<NanoGrid>, Rgb),
    /// neumann's `blackbody`: black-body radiance at the temperatures of another volume.
    Blackbody(Box<super::blackbody::Blackbody>),
}

/// A volume texture: values over its box in the world.
#[derive(Clone, Debug)]
pub struct Volume {
    data: VolumeData,
    /// World to the data's own space: a grid's unit cube, a cloud's or a NanoVDB grid's world
    /// space (the identity for a black body, whose volumes place themselves).
    to_local: Transform,
    /// Where the volume is (the transformed unit cube's box; module docs).
    bounds: Bounds3,
    /// The largest value of any channel anywhere (≥ every interpolated value).
    max: f32,
}

impl Volume {
    /// A volume of constant value `value` over the unit cube under `to_world`.
    pub fn constant(value: Rgb, to_world: Transform) -> Volume {
        Volume::with_data(VolumeData::Constant(value), to_world, value.max_element())
    }

    fn with_data(data: VolumeData, to_world: Transform, max: f32) -> Volume {
        let bounds = to_world.apply_bounds(&Bounds3::new(Vec3::ZERO, Vec3::ONE));
        Volume { data, to_local: to_world.inverse(), bounds, max }
    }

    /// pbrt-v4's cloud density times `value` over the box `bounds` of its own space, placed
    /// in the world by `to_world` (the density is looked up at the point's coordinates in that
    /// space).
    pub fn cloud(cloud: super::cloud::CloudDensity, value: Rgb, bounds: Bounds3, to_world: Transform) -> Volume {
        Volume {
            data: VolumeData::Cloud(cloud, value),
            to_local: to_world.inverse(),
            bounds: to_world.apply_bounds(&bounds),
            max: value.max_element(),
        }
    }

    /// A NanoVDB grid times `value` in the space that `to_world` places in the world (the grid's
    /// own map takes its voxels there); it exists in its active voxels' box.
    pub fn nanovdb(grid: Arc<NanoGrid>, value: Rgb, to_world: Transform) -> Volume {
        let (lo, hi) = grid.range();
        let max = value.to_array().iter().map(|&c| (c * lo).max(c * hi)).fold(0.0f32, f32::max);
        let bounds = to_world.apply_bounds(&nano_bounds(&grid));
        Volume { data: VolumeData::Nano(grid, value), to_local: to_world.inverse(), bounds, max }
    }

    /// Black-body radiance ([`super::blackbody::Blackbody`]; its volumes place themselves in
    /// the world).
    pub fn blackbody(b: super::blackbody::Blackbody) -> Volume {
        let (bounds, max) = (b.bounds(), b.max());
        Volume { data: VolumeData::Blackbody(Box::new(b)), to_local: Transform::IDENTITY, bounds, max }
    }

    /// A grid volume (one or three channels) over the unit cube under `to_world`; `None` for
    /// another channel count.
    pub fn grid(data: Arc<GridVolume>, filter: GridFilter, wrap: GridWrap, to_world: Transform) -> Option<Volume> {
        if data.channels != 1 && data.channels != 3 {
            return None;
        }
        let max = data.data.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        Some(Volume::with_data(VolumeData::Grid(Grid { data, filter, wrap }), to_world, max))
    }

    /// The value at world point `p` (the data's value at the nearest point of the domain
    /// when `p` is outside the box, by the wrap mode; callers stay inside [`Volume::bounds`]).
    #[inline]
    pub fn eval(&self, p: Vec3) -> Rgb {
        match &self.data {
            VolumeData::Constant(v) => *v,
            VolumeData::Grid(g) => g.eval(self.to_local.apply_point(p)),
            VolumeData::Cloud(c, v) => *v * c.at(self.to_local.apply_point(p)),
            VolumeData::Nano(g, v) => *v * g.sample(g.world_to_index(self.to_local.apply_point(p).to_array())),
            VolumeData::Blackbody(b) => b.eval(p),
        }
    }

    /// The world box the volume occupies.
    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// The largest value of any channel (an upper bound of [`Volume::eval`]).
    pub fn max(&self) -> f32 {
        self.max
    }

    /// An upper bound of every channel of [`Volume::eval`] over the world box `region`: for a
    /// grid, the largest texel that nearest or trilinear lookups anywhere in it read (the
    /// region mapped to the unit cube, its texel range widened by one for the trilinear
    /// footprint, indices wrapped as lookups wrap them; zero for texels a `zero` wrap leaves
    /// out); [`Volume::max`] for a constant or a cloud, and where the region maps to more than
    /// twice the grid's extent (a degenerate transform).
    pub fn max_in(&self, region: &Bounds3) -> f32 {
        if let VolumeData::Nano(g, v) = &self.data {
            // The voxels trilinear lookups in the region read: its index box, widened by one.
            let local = self.to_local.apply_bounds(region);
            let mut index = Bounds3::EMPTY;
            for i in 0..8 {
                let x = Vec3::from(g.world_to_index(local.corner(i).to_array()));
                if !(x.abs().max_element() < 1.0e9 && x.is_finite()) {
                    return self.max;
                }
                index = index.union_point(x);
            }
            let lo = index.min.to_array().map(|c| crate::math::floor(c) as i32 - 1);
            let hi = index.max.to_array().map(|c| crate::math::floor(c) as i32 + 1);
            let m = g.max_in(lo, hi);
            return v.to_array().iter().map(|&c| c * m).fold(0.0f32, f32::max).min(self.max);
        }
        let VolumeData::Grid(g) = &self.data else { return self.max };
        let local = self.to_local.apply_bounds(region);
        let res = g.data.res;
        let mut range = [(0i64, 0i64); 3];
        for a in 0..3 {
            let n = res[a] as f32;
            let lo = crate::math::floor(local.min[a] * n - 0.5);
            let hi = crate::math::floor(local.max[a] * n - 0.5) + 1.0;
            if !(lo.is_finite() && hi.is_finite()) || hi - lo > 2.0 * n + 2.0 {
                return self.max;
            }
            range[a] = (lo as i64, hi as i64);
        }
        // A grid has one channel or three; texels a `zero` wrap leaves out read zero.
        let texel_max = |i: [Option<usize>; 3]| match g.data.channels {
            1 => g.texel::<1>(i)[0],
            _ => g.texel::<3>(i).into_iter().fold(f32::NEG_INFINITY, f32::max),
        };
        let mut max = f32::NEG_INFINITY;
        for z in range[2].0..=range[2].1 {
            let z = g.wrap.apply(z, res[2]);
            for y in range[1].0..=range[1].1 {
                let y = g.wrap.apply(y, res[1]);
                for x in range[0].0..=range[0].1 {
                    max = max.max(texel_max([g.wrap.apply(x, res[0]), y, z]));
                }
            }
        }
        max
    }

    /// The resolution of a grid volume's data (`None` for a constant or a cloud).
    pub fn grid_resolution(&self) -> Option<[usize; 3]> {
        match &self.data {
            VolumeData::Grid(g) => Some(g.data.res),
            VolumeData::Nano(g, _) => {
                let b = g.index_bbox();
                Some(std::array::from_fn(|a| (b[1][a] as i64 - b[0][a] as i64 + 1).clamp(1, 1 << 20) as usize))
            }
            _ => None,
        }
    }

    /// The average value over the volume's box (of its grid values; a one-channel grid's in
    /// all three channels).
    pub fn mean(&self) -> Rgb {
        match &self.data {
            VolumeData::Constant(v) => *v,
            VolumeData::Cloud(..) | VolumeData::Nano(..) | VolumeData::Blackbody(_) => {
                // The average over a 16³ lattice of the box's points.
                let (lo, hi) = (self.bounds.min, self.bounds.max);
                let n = 16;
                let mut sum = Rgb::ZERO;
                for k in 0..n * n * n {
                    let f = Vec3::new((k % n) as f32, (k / n % n) as f32, (k / (n * n)) as f32) + Vec3::splat(0.5);
                    sum += self.eval(lo + (hi - lo) * f / n as f32);
                }
                sum / (n * n * n) as f32
            }
            VolumeData::Grid(g) => {
                let (ch, data) = (g.data.channels, &g.data.data);
                let n = (data.len() / ch.max(1)).max(1) as f64;
                let sum = |c: usize| data.iter().skip(c).step_by(ch.max(1)).map(|&x| x as f64).sum::<f64>() / n;
                if ch == 3 {
                    Rgb::new(sum(0) as f32, sum(1) as f32, sum(2) as f32)
                } else {
                    Rgb::splat(sum(0) as f32)
                }
            }
        }
    }

    /// Whether its three channels are equal everywhere (a one-channel grid, or equal values).
    pub fn is_grey(&self) -> bool {
        let grey = |c: Rgb| c.x == c.y && c.y == c.z;
        match &self.data {
            VolumeData::Constant(v) | VolumeData::Cloud(_, v) | VolumeData::Nano(_, v) => grey(*v),
            VolumeData::Blackbody(_) => false,
            VolumeData::Grid(g) => {
                g.data.channels == 1 || g.data.data.chunks_exact(3).all(|t| t[0] == t[1] && t[1] == t[2])
            }
        }
    }

    /// The smallest value of any channel anywhere.
    pub fn min(&self) -> f32 {
        match &self.data {
            VolumeData::Constant(v) => v.min_element(),
            VolumeData::Grid(g) => g.data.data.iter().copied().fold(f32::INFINITY, f32::min),
            VolumeData::Cloud(_, v) => v.min_element().min(0.0),
            VolumeData::Nano(g, v) => {
                let (lo, hi) = g.range();
                v.to_array().iter().map(|&c| (c * lo).min(c * hi)).fold(f32::INFINITY, f32::min)
            }
            VolumeData::Blackbody(b) => b.min(),
        }
    }

    /// Whether every value is finite.
    pub fn is_finite(&self) -> bool {
        match &self.data {
            VolumeData::Constant(v) => v.is_finite(),
            VolumeData::Grid(g) => g.data.data.iter().all(|v| v.is_finite()),
            VolumeData::Cloud(c, v) => {
                v.is_finite() && [c.density, c.wispiness, c.frequency].iter().all(|x| x.is_finite())
            }
            // The grid's values are checked finite when read.
            VolumeData::Nano(_, v) => v.is_finite(),
            VolumeData::Blackbody(b) => b.is_finite(),
        }
    }

    /// Whether the volume is the same everywhere in its box.
    pub fn is_constant(&self) -> bool {
        matches!(self.data, VolumeData::Constant(_))
    }
}

/// An error unless NanoVDB grid `g` is a fog volume or unclassified (as pbrt-v4 requires of a
/// medium's grids: a level set's values are distances, not densities).
fn fog_volume(o: &Obj, g: &NanoGrid) -> Result<()> {
    match g.unfit_class() {
        None => Ok(()),
        Some(c) => Err(o.error_at(
            "filename",
            format!("grid \"{}\" is a {c}: a volume reads fog volumes (or unclassified grids)", g.name()),
        )),
    }
}

/// The box of a NanoVDB grid's active voxel centres in its world space.
fn nano_bounds(grid: &NanoGrid) -> Bounds3 {
    let [lo, hi] = grid.world_bbox();
    let v = |c: [f64; 3]| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
    Bounds3::new(v(lo), v(hi))
}

/// A volume parameter `name` of a medium, as Mitsuba's `props.volume`: a nested `<volume>`
/// (`gridvolume` or `constvolume`), or a `<float>`, `<rgb>` or `<spectrum>` (a `constvolume`
/// over the unit cube), or `default` (likewise) when absent. `kind` says how spectra reduce to
/// RGB.
pub fn volume_param(
    o: &Obj,
    name: &str,
    default: f32,
    kind: SpectrumKind,
    files: &mut dyn VolumeSource,
) -> Result<Volume> {
    match o.get(name).map(|p| &p.value) {
        Some(Value::Object(v)) if v.tag == "volume" => {
            v.built.set(true);
            Volume::from_props(v, kind, files)
        }
        Some(Value::Object(_)) => {
            Err(o.error_at(name, format!("'{name}' takes a <volume>, <float>, <rgb> or <spectrum>")))
        }
        _ => Ok(Volume::constant(constant_param(o, name, default, kind)?, Transform::IDENTITY)),
    }
}

/// A constant medium coefficient `name` (`default` when absent): a `<float>`, a `<spectrum>`
/// (reduced to RGB as `kind`) or an `<rgb>`, which Mitsuba reads as a reflectance, so it must
/// lie in [0, 1] whatever the parameter (larger extinctions take `scale`, a float, or a
/// `constvolume`).
pub fn constant_param(o: &Obj, name: &str, default: f32, kind: SpectrumKind) -> Result<Rgb> {
    let kind =
        if matches!(o.get(name).map(|p| &p.value), Some(Value::Rgb(_))) { SpectrumKind::Reflectance } else { kind };
    o.rgb(name, Rgb::splat(default), kind)
}

impl Volume {
    /// Mitsuba's volume plugins:
    /// - `constvolume`: `value` (1; a float, rgb or spectrum), `to_world`;
    /// - `gridvolume`: `filename` (a `.vol` file of 1 or 3 channels), `filter_type`
    ///   (`trilinear`, or `nearest`), `wrap_mode` (`clamp`, `repeat` or `mirror`; neumann's
    ///   `zero`: nothing outside the texels, as pbrt-v4's grids), `to_world`,
    ///   `use_grid_bbox` (false: the file's bounding box is ignored; true: it places the grid
    ///   before `to_world`), `max_value` (an upper bound of the values; neumann takes the larger
    ///   of it and the data's maximum, so that tracking stays unbiased), `raw` and `accel` (no
    ///   effect in RGB rendering).
    ///
    /// and neumann's:
    /// - `nanovdb`: `filename` (a NanoVDB file), `grid` (the name of a float grid in it,
    ///   `density`), `value` (1: a colour it multiplies), `to_world` (where the grid's world
    ///   space goes: the grid's own map places its voxels there); the volume's box is that of the
    ///   grid's active voxels;
    ///   `required` (true; false: a file without the grid gives a volume of zero, as pbrt-v4's
    ///   optional temperature grid);
    /// - `blackbody`: black-body radiance ([`super::blackbody`]) at the temperatures of the
    ///   volume `temperature` (required: a nested `<volume>` or a number), `temperature_offset`
    ///   (0), `temperature_scale` (1), times `scale` (1) and the volume `weight` (none).
    pub fn from_props(o: &Obj, kind: SpectrumKind, files: &mut dyn VolumeSource) -> Result<Volume> {
        o.check_children(&[])?;
        let to_world = o.transform("to_world")?;
        match o.ty.as_str() {
            "constvolume" => Ok(Volume::constant(o.rgb("value", Rgb::ONE, kind)?, to_world)),
            "pbrt_cloud" => {
                let d = super::cloud::CloudDensity::default();
                let cloud = super::cloud::CloudDensity {
                    density: o.float("density", d.density)?,
                    wispiness: o.float("wispiness", d.wispiness)?,
                    frequency: o.float("frequency", d.frequency)?,
                };
                let (p0, p1) = (o.point_opt("p0")?.unwrap_or(Vec3::ZERO), o.point_opt("p1")?.unwrap_or(Vec3::ONE));
                if !(p1.cmpgt(p0).all() && (p1 - p0).is_finite()) {
                    return Err(o.error_at("p1", format!("the cloud's box p0 {p0} – p1 {p1} is empty")));
                }
                let v = Volume::cloud(cloud, o.rgb("value", Rgb::ONE, kind)?, Bounds3::new(p0, p1), to_world);
                if !v.is_finite() {
                    return Err(o.error("the cloud's parameters must be finite"));
                }
                Ok(v)
            }
            "gridvolume" => {
                let (data, filter, wrap, to_world) = grid_from_props(o, files)?;
                let channels = data.channels;
                let mut v = Volume::grid(data, filter, wrap, to_world).ok_or_else(|| {
                    o.error_at(
                        "filename",
                        format!(
                            "a medium reads grids of 1 or 3 channels, this one has {channels} (6-channel grids \
                             parametrise SGGX phase functions: their 'S')"
                        ),
                    )
                })?;
                if let Some(m) = o.float_opt("max_value")? {
                    v.max = v.max.max(m);
                }
                Ok(v)
            }
            "nanovdb" => {
                let grid = o.string_opt("grid")?.unwrap_or_else(|| "density".into());
                let value = o.rgb("value", Rgb::ONE, kind)?;
                let required = o.bool("required", true)?;
                match files.nanovdb_grid(o, "filename", &grid)? {
                    Some(g) => {
                        fog_volume(o, &g)?;
                        Ok(Volume::nanovdb(g, value, to_world))
                    }
                    None if !required => Ok(Volume::constant(Rgb::ZERO, to_world)),
                    None => Err(o.error_at(
                        "filename",
                        format!("the file has no grid named \"{grid}\" (see the \"grid\" parameter)"),
                    )),
                }
            }
            "blackbody" => {
                if o.get("temperature").is_none() {
                    return Err(o.error("a blackbody volume needs its 'temperature' (a <volume> or a number)"));
                }
                let temperature = volume_param(o, "temperature", 0.0, SpectrumKind::Unbounded, files)?;
                if !temperature.is_grey() || !temperature.is_finite() {
                    return Err(o.error_at("temperature", "'temperature' must be one finite value per point (grey)"));
                }
                let weight = match o.get("weight") {
                    None => None,
                    Some(_) => {
                        let w = volume_param(o, "weight", 1.0, SpectrumKind::Unbounded, files)?;
                        check_range(o, "weight", &w, 0.0, f32::INFINITY)?;
                        Some(w)
                    }
                };
                let (offset, t_scale, scale) =
                    (o.float("temperature_offset", 0.0)?, o.float("temperature_scale", 1.0)?, o.float("scale", 1.0)?);
                for (name, v) in [("temperature_offset", offset), ("temperature_scale", t_scale), ("scale", scale)] {
                    if !v.is_finite() {
                        return Err(o.error_at(name, format!("{name} must be finite, got {v}")));
                    }
                }
                if scale < 0.0 {
                    return Err(o.error_at("scale", format!("scale must be ≥ 0, got {scale}")));
                }
                Ok(Volume::blackbody(super::blackbody::Blackbody::new(temperature, weight, offset, t_scale, scale)))
            }
            _ => Err(o.unknown_plugin(&["gridvolume", "constvolume", "pbrt_cloud", "nanovdb", "blackbody"])),
        }
    }
}

/// A grid volume of six channels (Mitsuba's `gridvolume` read by `eval_6`): the parameters
/// `[S_xx, S_yy, S_zz, S_xy, S_xz, S_yz]` of an SGGX phase function over space, read as
/// [`Volume`] reads grids (the unit cube under `to_world`, the same filters and wrap modes).
#[derive(Clone, Debug)]
pub struct Volume6 {
    grid: Grid,
    /// World to the unit cube of the grid.
    to_local: Transform,
}

impl Volume6 {
    /// A six-channel grid over the unit cube under `to_world`; `None` for another channel
    /// count.
    pub fn grid(data: Arc<GridVolume>, filter: GridFilter, wrap: GridWrap, to_world: Transform) -> Option<Volume6> {
        (data.channels == 6).then(|| Volume6 { grid: Grid { data, filter, wrap }, to_local: to_world.inverse() })
    }

    /// The six values at world point `p`.
    #[inline]
    pub fn eval(&self, p: Vec3) -> [f32; 6] {
        self.grid.lookup::<6>(self.to_local.apply_point(p))
    }

    /// The texels, six numbers each.
    pub fn texels(&self) -> impl Iterator<Item = &[f32]> {
        self.grid.data.data.chunks_exact(6)
    }

    /// Mitsuba's `gridvolume` of six channels (what an SGGX phase function's `S` must be:
    /// Mitsuba 3.9.1's `constvolume` has no six-value form): `filename`, `filter_type`,
    /// `wrap_mode`, `to_world`, `use_grid_bbox`, `raw`, `accel` as for [`Volume::from_props`].
    pub fn from_props(o: &Obj, files: &mut dyn VolumeSource) -> Result<Volume6> {
        o.check_children(&[])?;
        if o.ty != "gridvolume" {
            return Err(
                o.error("six values per point need a gridvolume of six channels (Mitsuba's constvolume has none)")
            );
        }
        let (data, filter, wrap, to_world) = grid_from_props(o, files)?;
        let channels = data.channels;
        Volume6::grid(data, filter, wrap, to_world).ok_or_else(|| {
            o.error_at("filename", format!("an SGGX phase function reads grids of 6 channels, this one has {channels}"))
        })
    }
}

/// What a `gridvolume` reads besides `max_value`: its grid, `filter_type`, `wrap_mode` and
/// placement (`to_world`, and the file's box with `use_grid_bbox`); `raw` and `accel` are read
/// and change nothing in RGB rendering.
fn grid_from_props(
    o: &Obj,
    files: &mut dyn VolumeSource,
) -> Result<(Arc<GridVolume>, GridFilter, GridWrap, Transform)> {
    let mut to_world = o.transform("to_world")?;
    let filter = match o.choice("filter_type", &["trilinear", "nearest"])?.as_str() {
        "nearest" => GridFilter::Nearest,
        _ => GridFilter::Trilinear,
    };
    let wrap = match o.choice("wrap_mode", &["clamp", "repeat", "mirror", "zero"])?.as_str() {
        "repeat" => GridWrap::Repeat,
        "mirror" => GridWrap::Mirror,
        "zero" => GridWrap::Zero,
        _ => GridWrap::Clamp,
    };
    o.bool("raw", false)?;
    o.bool("accel", true)?;
    let data = files.grid_volume(o, "filename")?;
    if o.bool("use_grid_bbox", false)? {
        let [lo, hi] = data.bbox.map(Vec3::from);
        let box_to_world = Transform::scale(hi - lo)
            .map(|s| Transform::translate(lo) * s)
            .ok_or_else(|| o.error_at("use_grid_bbox", "the file's bounding box is empty"))?;
        to_world = to_world * box_to_world;
    }
    Ok((data, filter, wrap, to_world))
}

/// Rejects volumes with values outside `[lo, hi]` (or not finite), at parameter `name` of `o`.
pub fn check_range(o: &Obj, name: &str, v: &Volume, lo: f32, hi: f32) -> Result<()> {
    if !v.is_finite() || v.min() < lo || v.max() > hi {
        let range = if hi.is_infinite() { format!("≥ {lo}") } else { format!("in [{lo}, {hi}]") };
        let found = format!("values from {} to {}", v.min(), v.max());
        return Err(match o.get(name) {
            Some(p) => SceneError::at(&p.loc, format!("'{name}' must be {range}, the volume has {found}")),
            None => o.error(format!("'{name}' must be {range}, the volume has {found}")),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2×3×4 grid of the values 0..24 (x fastest), read as Mitsuba 3.9.1 reads it: the
    /// expected values were printed by Mitsuba's `gridvolume.eval_1` at the same points, for
    /// every filter and wrap mode.
    #[test]
    fn lookups_match_mitsuba() {
        let grid = Arc::new(GridVolume {
            res: [2, 3, 4],
            channels: 1,
            bbox: [[0.0; 3], [1.0; 3]],
            data: (0..24).map(|i| i as f32).collect(),
        });
        let points = [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(0.9, 0.95, 0.99),
            Vec3::new(1.2, -0.3, 0.5),
            Vec3::new(-0.6, 1.7, 2.2),
        ];
        let cases = [
            (GridFilter::Trilinear, GridWrap::Clamp, [4.4, 11.5, 23.0, 10.0, 22.0]),
            (GridFilter::Trilinear, GridWrap::Repeat, [4.7, 11.5, 13.02, 12.3, 5.3]),
            (GridFilter::Trilinear, GridWrap::Mirror, [4.4, 11.5, 23.0, 10.8, 3.3]),
            (GridFilter::Nearest, GridWrap::Clamp, [6.0, 15.0, 23.0, 13.0, 22.0]),
            (GridFilter::Nearest, GridWrap::Repeat, [6.0, 15.0, 23.0, 16.0, 4.0]),
            (GridFilter::Nearest, GridWrap::Mirror, [6.0, 15.0, 23.0, 13.0, 1.0]),
        ];
        for (filter, wrap, want) in cases {
            let v = Volume::grid(grid.clone(), filter, wrap, Transform::IDENTITY).unwrap();
            assert_eq!(v.max(), 23.0);
            for (p, w) in points.iter().zip(want) {
                let got = v.eval(*p);
                assert!(
                    (got.x - w).abs() < 1e-3 && got.x == got.y && got.y == got.z,
                    "{filter:?} {wrap:?} {p}: {got} vs {w}"
                );
            }
        }
    }

    /// Mitsuba 3.9.1's bounding box: that of the transformed unit cube's eight corners (its
    /// `bbox()` of a `constvolume` or `gridvolume` under rotate(z, 45°) · scale(2, 1, 1) is
    /// [-0.707107, 0, 0] to [1.41421, 2.12132, 1]), and the constant volume's unit cube.
    #[test]
    fn bounds_are_mitsubas() {
        let t = Transform::rotate(Vec3::Z, 45.0).unwrap() * Transform::scale(Vec3::new(2.0, 1.0, 1.0)).unwrap();
        let b = Volume::constant(Rgb::ONE, t).bounds();
        let s = std::f32::consts::FRAC_1_SQRT_2;
        for (got, want) in [(b.min, Vec3::new(-s, 0.0, 0.0)), (b.max, Vec3::new(2.0 * s, 3.0 * s, 1.0))] {
            assert!((got - want).abs().max_element() < 1e-5, "{got} vs {want}");
        }
        assert_eq!(Volume::constant(Rgb::ONE, Transform::IDENTITY).bounds(), Bounds3::new(Vec3::ZERO, Vec3::ONE));
    }

    /// Three-channel grids give colours; trilinear interpolation at a texel centre is the texel.
    #[test]
    fn rgb_grid_at_texel_centres() {
        let data: Vec<f32> = (0..8 * 3).map(|i| (i as f32 * 0.37).sin().abs()).collect();
        let grid = Arc::new(GridVolume { res: [2, 2, 2], channels: 3, bbox: [[0.0; 3], [1.0; 3]], data: data.clone() });
        let v = Volume::grid(grid, GridFilter::Trilinear, GridWrap::Clamp, Transform::IDENTITY).unwrap();
        for k in 0..8 {
            let (x, y, z) = (k & 1, k >> 1 & 1, k >> 2);
            let p = Vec3::new(0.25 + 0.5 * x as f32, 0.25 + 0.5 * y as f32, 0.25 + 0.5 * z as f32);
            let want = Rgb::new(data[3 * k], data[3 * k + 1], data[3 * k + 2]);
            assert!((v.eval(p) - want).abs().max_element() < 1e-6);
        }
        let six = Arc::new(GridVolume { res: [1, 1, 1], channels: 6, bbox: [[0.0; 3], [1.0; 3]], data: vec![0.0; 6] });
        assert!(Volume::grid(six, GridFilter::Nearest, GridWrap::Clamp, Transform::IDENTITY).is_none());
    }
}
