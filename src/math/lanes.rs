//! Paths in SIMD lanes: `W` values of one quantity side by side, one per path.
//!
//! [`Fw`] holds `W` single-precision lanes as an array and applies every operation lane by lane
//! in loops of fixed length. Inlined (`#[inline(always)]`) into a function compiled for AVX-512,
//! AVX2 or plain SSE2 (`#[target_feature]`, chosen at run time as the BVH's traversal is), the
//! loops become that instruction set's vector instructions, so one generic kernel serves every
//! width: 16 lanes in AVX-512's registers, two registers of 8 for AVX2, four of 4 for SSE2.
//!
//! **Bit for bit the scalar code's arithmetic.** Each lane performs exactly the IEEE operations
//! the scalar function it mirrors performs, in the same order (Rust never contracts `a * b + c`
//! into a fused multiply-add, nor reassociates; vector `add`, `mul`, `div`, `sqrt`, `min`, `max`
//! round as their scalar forms do). A kernel written in lanes therefore gives the same bits as
//! the scalar path it replaces, and its tests compare bits, not statistics. Where the scalar code
//! branches, the lane code evaluates both sides and selects ([`Fw::select`]), which is the same
//! value in each lane.
//!
//! Masks ([`Mw`]) are all-ones or all-zeros per lane (as SIMD comparisons produce them), so that
//! selecting is a bitwise blend and testing any lane one movemask.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// `W` lanes of `f32`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Fw<const W: usize>(pub [f32; W]);

/// A lane mask: `u32::MAX` in the lanes that are set, 0 elsewhere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, align(64))]
pub struct Mw<const W: usize>(pub [u32; W]);

/// `[f(0), …, f(W − 1)]` by a plain loop. `std::array::from_fn` and `<[T; N]>::map` call a
/// helper that is not inlined into the caller, so in a `#[target_feature]` kernel they would run
/// as calls compiled without its instruction set; these loops inline and vectorize.
#[inline(always)]
fn lanewise<T: Copy + Default, const W: usize>(f: impl Fn(usize) -> T) -> [T; W] {
    let mut out = [T::default(); W];
    for (k, o) in out.iter_mut().enumerate() {
        *o = f(k);
    }
    out
}

impl<const W: usize> Fw<W> {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(x: f32) -> Self {
        Fw([x; W])
    }

    /// Lane `k` is `f(k)` (a gather, when `f` reads memory).
    #[inline(always)]
    pub fn from_fn(f: impl Fn(usize) -> f32) -> Self {
        Fw(lanewise(f))
    }

    /// `f` applied to each lane.
    #[inline(always)]
    pub fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Fw(lanewise(|k| f(self.0[k])))
    }

    /// `f` applied to each pair of lanes.
    #[inline(always)]
    pub fn zip(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
        Fw(lanewise(|k| f(self.0[k], o.0[k])))
    }

    /// The mask of lanes where `f(self, o)` holds.
    #[inline(always)]
    fn compare(self, o: Self, f: impl Fn(f32, f32) -> bool) -> Mw<W> {
        Mw(lanewise(|k| if f(self.0[k], o.0[k]) { u32::MAX } else { 0 }))
    }

    /// Lane `k`.
    #[inline(always)]
    pub fn lane(self, k: usize) -> f32 {
        self.0[k]
    }

    /// Square roots.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        self.map(f32::sqrt)
    }

    /// Absolute values.
    #[inline(always)]
    pub fn abs(self) -> Self {
        self.map(f32::abs)
    }

    /// Lane-wise minimum, as `f32::min` (the other operand where one is NaN).
    #[inline(always)]
    pub fn min(self, o: Self) -> Self {
        self.zip(o, f32::min)
    }

    /// Lane-wise maximum, as `f32::max`.
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        self.zip(o, f32::max)
    }

    /// `|self|` with the sign of `sign`, as `f32::copysign`.
    #[inline(always)]
    pub fn copysign(self, sign: Self) -> Self {
        self.zip(sign, f32::copysign)
    }

    /// Lane-wise clamp to `[lo, hi]`, as `f32::clamp` (NaN stays NaN).
    #[inline(always)]
    pub fn clamp(self, lo: f32, hi: f32) -> Self {
        self.map(|x| x.clamp(lo, hi))
    }

    /// `a` in the lanes of `m`, `b` elsewhere.
    #[inline(always)]
    pub fn select(m: Mw<W>, a: Self, b: Self) -> Self {
        // By the mask's sign bit (all of it set or clear): one blend instruction.
        Fw(lanewise(|k| if (m.0[k] as i32) < 0 { a.0[k] } else { b.0[k] }))
    }

    /// Lanes where `self < o`.
    #[inline(always)]
    pub fn lt(self, o: Self) -> Mw<W> {
        self.compare(o, |a, b| a < b)
    }

    /// Lanes where `self ≤ o`.
    #[inline(always)]
    pub fn le(self, o: Self) -> Mw<W> {
        self.compare(o, |a, b| a <= b)
    }

    /// Lanes where `self > o`.
    #[inline(always)]
    pub fn gt(self, o: Self) -> Mw<W> {
        self.compare(o, |a, b| a > b)
    }

    /// Lanes where `self ≥ o`.
    #[inline(always)]
    pub fn ge(self, o: Self) -> Mw<W> {
        self.compare(o, |a, b| a >= b)
    }

    /// Lanes where `self == o` (false where either is NaN).
    #[inline(always)]
    pub fn eq(self, o: Self) -> Mw<W> {
        self.compare(o, |a, b| a == b)
    }

    /// Lanes where `self != o` (true where either is NaN).
    #[inline(always)]
    pub fn ne(self, o: Self) -> Mw<W> {
        self.compare(o, |a, b| a != b)
    }

    /// Lanes that are neither infinite nor NaN.
    #[inline(always)]
    pub fn is_finite(self) -> Mw<W> {
        Mw(lanewise(|k| if self.0[k].is_finite() { u32::MAX } else { 0 }))
    }

    /// Truncation toward zero, as `f32::trunc` (one vector instruction; an `as i32` cast, which
    /// saturates, is a scalar conversion per lane).
    #[inline(always)]
    pub fn trunc(self) -> Self {
        self.map(f32::trunc)
    }

    /// `round(x)` as [`crate::math::round`] (half away from zero), bit for bit, written without
    /// its branches and its `as i32` cast: `trunc` gives the same integer part wherever the
    /// scalar function computes one (|x| < 2²³), and its early returns are selects.
    #[inline(always)]
    pub fn round(self) -> Self {
        let t = self.trunc();
        let d = self - t;
        let r = Fw::select(d.ge(Fw::splat(0.5)), t + 1.0, Fw::select(d.le(Fw::splat(-0.5)), t - 1.0, t)).copysign(self);
        let keep = self.abs().ge(Fw::splat(8_388_608.0)) | self.eq(Fw::splat(0.0));
        let nan = self.ne(self);
        Fw::select(nan, self + self, Fw::select(keep, self, r))
    }
}

impl<const W: usize> Mw<W> {
    /// No lane set.
    pub const NONE: Self = Mw([0; W]);
    /// Every lane set.
    pub const ALL: Self = Mw([u32::MAX; W]);

    /// The mask of lanes `k` where `f(k)`.
    #[inline(always)]
    pub fn from_fn(f: impl Fn(usize) -> bool) -> Self {
        Mw(lanewise(|k| if f(k) { u32::MAX } else { 0 }))
    }

    /// Whether lane `k` is set.
    #[inline(always)]
    pub fn test(self, k: usize) -> bool {
        self.0[k] != 0
    }

    /// Whether any lane is set.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.0.iter().fold(0, |a, &m| a | m) != 0
    }

    /// Whether every lane is set.
    #[inline(always)]
    pub fn all(self) -> bool {
        self.0.iter().fold(u32::MAX, |a, &m| a & m) != 0
    }

    /// Bit `k` set where lane `k` is (at most 64 lanes).
    #[inline(always)]
    pub fn bits(self) -> u64 {
        // By the lanes' sign bits, four at a time by SSE's movemask (every x86-64 CPU has it).
        #[cfg(target_arch = "x86_64")]
        if W.is_multiple_of(4) {
            use std::arch::x86_64::{_mm_castsi128_ps, _mm_loadu_si128, _mm_movemask_ps};
            let mut b = 0u64;
            for q in 0..W / 4 {
                // SAFETY: lanes 4q .. 4q + 3 exist (W is a multiple of 4); an unaligned load.
                let m = unsafe { _mm_movemask_ps(_mm_castsi128_ps(_mm_loadu_si128(self.0.as_ptr().add(4 * q).cast()))) };
                b |= (m as u64) << (4 * q);
            }
            return b;
        }
        let mut b = 0u64;
        for k in 0..W {
            b |= u64::from((self.0[k] as i32) < 0) << k;
        }
        b
    }
}

macro_rules! lane_ops {
    ($($trait:ident $method:ident $op:tt),*) => {$(
        impl<const W: usize> $trait for Fw<W> {
            type Output = Fw<W>;
            #[inline(always)]
            fn $method(self, o: Fw<W>) -> Fw<W> {
                Fw(lanewise(|k| self.0[k] $op o.0[k]))
            }
        }
        impl<const W: usize> $trait<f32> for Fw<W> {
            type Output = Fw<W>;
            #[inline(always)]
            fn $method(self, o: f32) -> Fw<W> {
                Fw(lanewise(|k| self.0[k] $op o))
            }
        }
        impl<const W: usize> $trait<Fw<W>> for f32 {
            type Output = Fw<W>;
            #[inline(always)]
            fn $method(self, o: Fw<W>) -> Fw<W> {
                Fw(lanewise(|k| self $op o.0[k]))
            }
        }
    )*};
}

lane_ops!(Add add +, Sub sub -, Mul mul *, Div div /);

impl<const W: usize> Neg for Fw<W> {
    type Output = Fw<W>;
    #[inline(always)]
    fn neg(self) -> Fw<W> {
        self.map(|x| -x)
    }
}

impl<const W: usize> BitAnd for Mw<W> {
    type Output = Mw<W>;
    #[inline(always)]
    fn bitand(self, o: Mw<W>) -> Mw<W> {
        Mw(lanewise(|k| self.0[k] & o.0[k]))
    }
}

impl<const W: usize> BitOr for Mw<W> {
    type Output = Mw<W>;
    #[inline(always)]
    fn bitor(self, o: Mw<W>) -> Mw<W> {
        Mw(lanewise(|k| self.0[k] | o.0[k]))
    }
}

impl<const W: usize> Not for Mw<W> {
    type Output = Mw<W>;
    #[inline(always)]
    fn not(self) -> Mw<W> {
        Mw(lanewise(|k| !self.0[k]))
    }
}

/// The set lanes of `m`, lowest first (a loop over them branches once per set lane, where
/// testing each lane in turn mispredicts on the unpredictable ones).
#[inline(always)]
pub fn ones<const W: usize>(m: Mw<W>) -> impl Iterator<Item = usize> {
    let mut bits = m.bits();
    std::iter::from_fn(move || {
        (bits != 0).then(|| {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            k
        })
    })
}

/// `W` three-component vectors (points, directions, normals or RGB), one per lane, as three
/// [`Fw`]: the lane form of [`crate::math::Vec3`], its operations in glam's order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3w<const W: usize> {
    /// x (or red) of each lane.
    pub x: Fw<W>,
    /// y (or green).
    pub y: Fw<W>,
    /// z (or blue).
    pub z: Fw<W>,
}

impl<const W: usize> V3w<W> {
    /// Every lane `v`.
    #[inline(always)]
    pub fn splat(v: crate::math::Vec3) -> Self {
        V3w { x: Fw::splat(v.x), y: Fw::splat(v.y), z: Fw::splat(v.z) }
    }

    /// From components.
    #[inline(always)]
    pub fn new(x: Fw<W>, y: Fw<W>, z: Fw<W>) -> Self {
        V3w { x, y, z }
    }

    /// Lane `k` is `f(k)`.
    #[inline(always)]
    pub fn from_fn(f: impl Fn(usize) -> crate::math::Vec3) -> Self {
        let mut v = V3w { x: Fw::splat(0.0), y: Fw::splat(0.0), z: Fw::splat(0.0) };
        for k in 0..W {
            let p = f(k);
            (v.x.0[k], v.y.0[k], v.z.0[k]) = (p.x, p.y, p.z);
        }
        v
    }

    /// Lane `k` as a vector.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> crate::math::Vec3 {
        crate::math::Vec3::new(self.x.0[k], self.y.0[k], self.z.0[k])
    }

    /// Dot products, `(x x' + y y') + z z'` as glam's.
    #[inline(always)]
    pub fn dot(self, o: Self) -> Fw<W> {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross products, as glam's.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3w { x: self.y * o.z - o.y * self.z, y: self.z * o.x - o.z * self.x, z: self.x * o.y - o.x * self.y }
    }

    /// Squared lengths.
    #[inline(always)]
    pub fn length_squared(self) -> Fw<W> {
        self.dot(self)
    }

    /// Lengths.
    #[inline(always)]
    pub fn length(self) -> Fw<W> {
        self.dot(self).sqrt()
    }

    /// Unit vectors, as glam's `normalize`: `self × (1 / length)`.
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self * (1.0 / self.length())
    }

    /// Absolute values of the components.
    #[inline(always)]
    pub fn abs(self) -> Self {
        V3w { x: self.x.abs(), y: self.y.abs(), z: self.z.abs() }
    }

    /// Each component times `s`.
    #[inline(always)]
    pub fn scale(self, s: Fw<W>) -> Self {
        V3w { x: self.x * s, y: self.y * s, z: self.z * s }
    }

    /// `a` in the lanes of `m`, `b` elsewhere.
    #[inline(always)]
    pub fn select(m: Mw<W>, a: Self, b: Self) -> Self {
        V3w { x: Fw::select(m, a.x, b.x), y: Fw::select(m, a.y, b.y), z: Fw::select(m, a.z, b.z) }
    }

    /// The largest component of each lane, as glam's `max_element`: `max(x, max(y, z))` with
    /// `max(a, b) = if a > b { a } else { b }` (which passes a NaN in `b` on).
    #[inline(always)]
    pub fn max_element(self) -> Fw<W> {
        let max = |a: Fw<W>, b: Fw<W>| Fw::select(a.gt(b), a, b);
        max(self.x, max(self.y, self.z))
    }
}

macro_rules! v3_ops {
    ($($trait:ident $method:ident $op:tt),*) => {$(
        impl<const W: usize> $trait for V3w<W> {
            type Output = V3w<W>;
            #[inline(always)]
            fn $method(self, o: V3w<W>) -> V3w<W> {
                V3w { x: self.x $op o.x, y: self.y $op o.y, z: self.z $op o.z }
            }
        }
        impl<const W: usize> $trait<Fw<W>> for V3w<W> {
            type Output = V3w<W>;
            #[inline(always)]
            fn $method(self, o: Fw<W>) -> V3w<W> {
                V3w { x: self.x $op o, y: self.y $op o, z: self.z $op o }
            }
        }
    )*};
}

v3_ops!(Add add +, Sub sub -, Mul mul *, Div div /);

impl<const W: usize> Neg for V3w<W> {
    type Output = V3w<W>;
    #[inline(always)]
    fn neg(self) -> V3w<W> {
        V3w { x: -self.x, y: -self.y, z: -self.z }
    }
}

/// The frame `(s, t, n)` of each lane ([`crate::math::Frame`] in lanes).
#[derive(Clone, Copy)]
pub struct FrameW<const W: usize> {
    /// First tangent.
    pub s: V3w<W>,
    /// Second tangent.
    pub t: V3w<W>,
    /// Normal.
    pub n: V3w<W>,
}

impl<const W: usize> FrameW<W> {
    /// [`crate::math::Frame::from_z`] in lanes.
    #[inline(always)]
    pub fn from_z(n: V3w<W>) -> Self {
        let sign = Fw::splat(1.0).copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = V3w::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = V3w::new(b, sign + n.y * n.y * a, -n.y);
        FrameW { s, t, n }
    }

    /// [`crate::math::Frame::from_zx`] in lanes: Gram–Schmidt where the tangent is usable,
    /// [`FrameW::from_z`] in the other lanes.
    #[inline(always)]
    pub fn from_zx(n: V3w<W>, s: V3w<W>) -> Self {
        let s2 = s.length_squared();
        let s = s - n.scale(n.dot(s));
        let len2 = s.length_squared();
        let fallback = s2.eq(Fw::splat(0.0)) | len2.ne(len2) | len2.le(s2 * 1e-12) | !s2.is_finite();
        let s = s / len2.sqrt();
        let gram = FrameW { s, t: n.cross(s), n };
        let z = FrameW::from_z(n);
        FrameW { s: V3w::select(fallback, z.s, gram.s), t: V3w::select(fallback, z.t, gram.t), n }
    }

    /// World → local, as [`crate::math::Frame::to_local`].
    #[inline(always)]
    pub fn to_local(self, v: V3w<W>) -> V3w<W> {
        V3w::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local → world, as [`crate::math::Frame::to_world`].
    #[inline(always)]
    pub fn to_world(self, v: V3w<W>) -> V3w<W> {
        self.s.scale(v.x) + self.t.scale(v.y) + self.n.scale(v.z)
    }
}

/// [`crate::math::sin_cos_quarter`] in lanes (the same polynomial, the same bits).
#[inline(always)]
pub fn sin_cos_quarter<const W: usize>(x: Fw<W>) -> (Fw<W>, Fw<W>) {
    let x2 = x * x;
    let s = x * (1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    let c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0))));
    (s, c)
}

/// [`crate::math::sin_cos_2pi`] in lanes for `u ∈ [0, 1]` (the same bits there; NaN gives NaN
/// as the scalar does): the quadrant's rotation by selects.
#[inline(always)]
pub fn sin_cos_2pi<const W: usize>(u: Fw<W>) -> (Fw<W>, Fw<W>) {
    let q = (u * 4.0).round();
    let (s, c) = sin_cos_quarter((u - q * 0.25) * std::f32::consts::TAU);
    // The scalar's `q as i32 & 3` for the whole numbers q ∈ [0, 4] that u ∈ [0, 1] gives, in
    // float arithmetic (exact): q − 4 ⌊q / 4⌋. Elsewhere (u outside [0, 1], NaN) the lanes may
    // pick another quadrant than the scalar code; both are then outside the function's domain.
    let quadrant = q - (q * 0.25).map(f32::floor) * 4.0;
    let (odd, high) = (quadrant.eq(Fw::splat(1.0)) | quadrant.eq(Fw::splat(3.0)), quadrant.ge(Fw::splat(2.0)));
    // Quadrants 0..3: (s, c), (c, −s), (−s, −c), (−c, s).
    let (s1, c1) = (Fw::select(odd, c, s), Fw::select(odd, -s, c));
    (Fw::select(high, -s1, s1), Fw::select(high, -c1, c1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    /// Random lanes with the awkward values mixed in: zeros of both signs, tiny and huge
    /// magnitudes, infinities and NaN.
    fn awkward<const W: usize>(rng: &mut Pcg32) -> Fw<W> {
        const SPECIAL: [f32; 8] = [0.0, -0.0, 1e-30, -3e29, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1.0];
        let mut lanes = Fw::splat(0.0);
        for x in lanes.0.iter_mut() {
            let r = rng.next_u32();
            *x = if r.is_multiple_of(5) {
                SPECIAL[(r >> 8) as usize % SPECIAL.len()]
            } else {
                (rng.next_f32() - 0.5) * 20.0
            };
        }
        lanes
    }

    fn same_bits(a: f32, b: f32) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// Every lane operation gives the scalar operation's bits, for each width the kernels use.
    #[test]
    fn lane_operations_match_scalar_bits() {
        fn check<const W: usize>(rng: &mut Pcg32) {
            for _ in 0..2000 {
                let (a, b, c) = (awkward::<W>(rng), awkward::<W>(rng), awkward::<W>(rng));
                let m = a.lt(b);
                let va = V3w::new(a, b, c);
                let vb = V3w::new(c, a, b);
                for k in 0..W {
                    let (x, y, z) = (a.0[k], b.0[k], c.0[k]);
                    let (p, q) = (crate::math::Vec3::new(x, y, z), crate::math::Vec3::new(z, x, y));
                    let pairs = [
                        ((a + b).0[k], x + y),
                        ((a - b).0[k], x - y),
                        ((a * b).0[k], x * y),
                        ((a / b).0[k], x / y),
                        ((a * 3.0 + b).0[k], x * 3.0 + y),
                        ((-a).0[k], -x),
                        (a.sqrt().0[k], x.sqrt()),
                        (a.min(b).0[k], x.min(y)),
                        (a.max(b).0[k], x.max(y)),
                        (a.copysign(b).0[k], x.copysign(y)),
                        (Fw::select(m, a, b).0[k], if x < y { x } else { y }),
                        (va.dot(vb).0[k], p.dot(q)),
                        (va.cross(vb).x.0[k], p.cross(q).x),
                        (va.cross(vb).y.0[k], p.cross(q).y),
                        (va.cross(vb).z.0[k], p.cross(q).z),
                        (va.length().0[k], p.length()),
                        (va.normalize().y.0[k], p.normalize().y),
                        (va.max_element().0[k], p.max_element()),
                        (a.round().0[k], crate::math::round(x)),
                    ];
                    for (i, (lane, scalar)) in pairs.into_iter().enumerate() {
                        assert!(
                            same_bits(lane, scalar),
                            "op {i} lane {k}: {lane:e} vs {scalar:e} ({x:e}, {y:e}, {z:e})"
                        );
                    }
                    assert_eq!(m.test(k), x < y);
                    assert_eq!(a.is_finite().test(k), x.is_finite());
                    assert_eq!(a.ne(b).test(k), x != y);
                }
                assert_eq!(m.any(), (0..W).any(|k| m.test(k)));
                assert_eq!(m.all(), (0..W).all(|k| m.test(k)));
                assert_eq!(m.bits(), (0..W).fold(0u64, |b, k| b | (u64::from(m.test(k)) << k)));
                assert_eq!((!m).bits() | m.bits(), (1u64 << W) - 1);
            }
        }
        let mut rng = Pcg32::new(11, 3);
        check::<4>(&mut rng);
        check::<8>(&mut rng);
        check::<16>(&mut rng);
    }

    /// The lane sine and cosine are the scalar ones bit for bit, quadrant edges included.
    #[test]
    fn sin_cos_match_scalar_bits() {
        let edges = [0.0f32, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0 - f32::EPSILON / 2.0, 1.0];
        let near = edges.iter().flat_map(|&e| [e, f32::from_bits(e.to_bits().saturating_sub(1)), e + 1e-7]);
        let mut us: Vec<f32> =
            (0..=4096).map(|k| k as f32 / 4096.0).chain(near).filter(|u| (0.0..=1.0).contains(u)).collect();
        us.push(f32::NAN);
        while !us.len().is_multiple_of(16) {
            us.push(0.5);
        }
        for chunk in us.chunks(16) {
            let u = Fw::<16>::from_fn(|k| chunk[k]);
            let (s, c) = sin_cos_2pi(u);
            let (sq, cq) = sin_cos_quarter(u - 0.5);
            for (k, &uk) in chunk.iter().enumerate() {
                let (es, ec) = crate::math::sin_cos_2pi(uk);
                assert!(
                    same_bits(s.0[k], es) && same_bits(c.0[k], ec),
                    "u {}: ({}, {}) vs ({es}, {ec})",
                    uk,
                    s.0[k],
                    c.0[k]
                );
                let (eq_s, eq_c) = crate::math::sin_cos_quarter(uk - 0.5);
                assert!(same_bits(sq.0[k], eq_s) && same_bits(cq.0[k], eq_c));
            }
        }
    }
}
