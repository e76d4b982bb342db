//! PCG32 random number generator (O'Neill 2014, "PCG: A Family of Simple Fast Space-Efficient
//! Statistically Good Algorithms for Random Number Generation"), XSH-RR output on a 64-bit LCG.
//!
//! Each generator has a *sequence* (stream) selector, so one seed yields 2⁶³ independent
//! streams: the renderer gives every pixel its own stream and jumps within it with
//! [`Pcg32::advance`] to the (sample index, dimension) it needs, in O(log n). That is what makes
//! every sampler deterministic in (seed, pixel, sample index, dimension) whatever the thread
//! schedule.

const MULT: u64 = 0x5851_f42d_4c95_7f2d;
const DEFAULT_STATE: u64 = 0x853c_49e6_748f_ea9b;
const DEFAULT_STREAM: u64 = 0xda3e_39cb_94b9_5bdb;

/// A PCG32 generator: 64-bit state, 32-bit output, period 2⁶⁴ per stream.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Default for Pcg32 {
    fn default() -> Self {
        Pcg32 { state: DEFAULT_STATE, inc: DEFAULT_STREAM }
    }
}

impl Pcg32 {
    /// Generator for `seed` on stream `stream` (any value; streams are independent).
    pub fn new(seed: u64, stream: u64) -> Pcg32 {
        let mut r = Pcg32 { state: 0, inc: 0 };
        r.set_sequence(stream, seed);
        r
    }

    /// Restarts the generator at the beginning of `stream` for `seed`.
    pub fn set_sequence(&mut self, stream: u64, seed: u64) {
        self.state = 0;
        self.inc = (stream << 1) | 1;
        self.next_u32();
        self.state = self.state.wrapping_add(seed);
        self.next_u32();
    }

    /// Next uniformly distributed 32-bit integer.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = lcg_step(old, self.inc);
        xsh_rr(old)
    }

    /// Next uniform `f32` in `[0, 1)`: the top 24 bits of [`Pcg32::next_u32`] times 2⁻²⁴, so
    /// every value is exact and 1 is never returned.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        unit_f32(self.next_u32())
    }

    /// Next uniform `f64` in `[0, 1)` (53 random bits).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        (hi | lo) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }

    /// Uniform integer in `[0, bound)` without modulo bias (Lemire's method); `bound > 0`.
    pub fn next_bounded(&mut self, bound: u32) -> u32 {
        assert!(bound > 0, "next_bounded needs a positive bound");
        let threshold = bound.wrapping_neg() % bound;
        loop {
            let m = self.next_u32() as u64 * bound as u64;
            if (m as u32) >= threshold {
                return (m >> 32) as u32;
            }
        }
    }

    /// Skips `delta` outputs in O(log delta) (Brown, "Random Number Generation with Arbitrary
    /// Strides", 1994). Negative strides wrap around the period.
    pub fn advance(&mut self, delta: i64) {
        self.jump(&Stride::new(delta));
    }

    /// Skips the outputs of a precomputed [`Stride`] in O(1).
    #[inline]
    pub fn jump(&mut self, s: &Stride) {
        self.state = s.mult.wrapping_mul(self.state).wrapping_add(s.plus.wrapping_mul(self.inc));
    }
}

/// The LCG's step from state `old` on the stream of increment `inc`.
#[inline(always)]
fn lcg_step(old: u64, inc: u64) -> u64 {
    old.wrapping_mul(MULT).wrapping_add(inc)
}

/// PCG32's output for the state `old` (XSH-RR: xorshift high, random rotation).
#[inline(always)]
fn xsh_rr(old: u64) -> u32 {
    let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
    xorshifted.rotate_right((old >> 59) as u32)
}

/// An output's top 24 bits as a uniform `f32` in `[0, 1)` (exact; never 1).
#[inline(always)]
fn unit_f32(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// `W` PCG32 generators side by side (the path tracer's lanes, [`crate::math::lanes`]): each
/// lane steps exactly as its [`Pcg32`] would, in vector instructions (the 64-bit LCG step and
/// the XSH-RR output lane by lane in loops of fixed length, which the lanes' kernels inline and
/// vectorize), so that lane `k` draws the bits its generator draws.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Pcg32Lanes<const W: usize> {
    state: [u64; W],
    inc: [u64; W],
}

impl<const W: usize> Pcg32Lanes<W> {
    /// Lanes holding `rngs[k]` (lanes past `rngs.len()` hold the default generator).
    #[inline(always)]
    pub(crate) fn gather<'a>(rngs: impl Iterator<Item = &'a Pcg32>) -> Self {
        let mut lanes = Pcg32Lanes { state: [DEFAULT_STATE; W], inc: [DEFAULT_STREAM; W] };
        for (k, r) in rngs.take(W).enumerate() {
            (lanes.state[k], lanes.inc[k]) = (r.state, r.inc);
        }
        lanes
    }

    /// Writes lane `k`'s generator back into `rngs[k]`.
    #[inline(always)]
    pub(crate) fn scatter<'a>(&self, rngs: impl Iterator<Item = &'a mut Pcg32>) {
        for (k, r) in rngs.take(W).enumerate() {
            (r.state, r.inc) = (self.state[k], self.inc[k]);
        }
    }

    /// [`Pcg32::next_f32`] in the lanes whose `mask[k]` is nonzero (the others' generators do
    /// not move; their value is that of a step not taken, to be ignored).
    #[inline(always)]
    pub(crate) fn next_f32(&mut self, mask: &[u32; W]) -> [f32; W] {
        let mut out = [0.0f32; W];
        for k in 0..W {
            let old = self.state[k];
            // All ones where the lane steps: the blend of new and old state.
            let keep = (mask[k] as i32 as i64 as u64) ^ u64::MAX;
            self.state[k] = (lcg_step(old, self.inc[k]) & !keep) | (old & keep);
            out[k] = unit_f32(xsh_rr(old));
        }
        out
    }
}

/// A jump of a fixed number of outputs, valid on every stream: skipping `delta` steps of the LCG
/// `s ← MULT·s + inc` is the affine map `s ← mult·s + plus·inc`, whose coefficients do not
/// depend on the stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stride {
    mult: u64,
    plus: u64,
}

impl Stride {
    /// The jump over `delta` outputs (negative: backwards around the period), by binary
    /// exponentiation of the affine map.
    pub const fn new(delta: i64) -> Stride {
        let mut delta = delta as u64;
        let (mut cur_mult, mut cur_plus) = (MULT, 1u64);
        let (mut acc_mult, mut acc_plus) = (1u64, 0u64);
        while delta > 0 {
            if delta & 1 != 0 {
                acc_mult = acc_mult.wrapping_mul(cur_mult);
                acc_plus = acc_plus.wrapping_mul(cur_mult).wrapping_add(cur_plus);
            }
            cur_plus = cur_mult.wrapping_add(1).wrapping_mul(cur_plus);
            cur_mult = cur_mult.wrapping_mul(cur_mult);
            delta >>= 1;
        }
        Stride { mult: acc_mult, plus: acc_plus }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_1d, Chi2Config};

    #[test]
    fn reference_output_of_the_pcg32_demo() {
        // The first outputs of pcg32 seeded with (42, 54) as printed by O'Neill's pcg32-demo.
        let mut r = Pcg32::new(42, 54);
        let expected = [0xa15c02b7u32, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e];
        for e in expected {
            assert_eq!(r.next_u32(), e);
        }
    }

    /// Lanes step as their generators do, bit for bit, and only where their mask is set.
    #[test]
    fn lanes_draw_what_each_generator_draws() {
        let mut rngs: Vec<Pcg32> = (0..5).map(|k| Pcg32::new(17 + k, 3 * k + 1)).collect();
        let mut lanes = Pcg32Lanes::<8>::gather(rngs.iter());
        let mut reference = rngs.clone();
        for step in 0..40u32 {
            let mask: [u32; 8] = std::array::from_fn(|k| if !(k as u32 + step).is_multiple_of(3) { u32::MAX } else { 0 });
            let got = lanes.next_f32(&mask);
            for (k, r) in reference.iter_mut().enumerate() {
                if mask[k] != 0 {
                    assert_eq!(got[k].to_bits(), r.next_f32().to_bits(), "lane {k}, step {step}");
                }
            }
        }
        lanes.scatter(rngs.iter_mut());
        assert_eq!(rngs, reference);
    }

    #[test]
    fn advance_matches_stepping_and_rewinds() {
        let mut a = Pcg32::new(5, 9);
        let mut b = a.clone();
        for _ in 0..1000 {
            a.next_u32();
        }
        b.advance(1000);
        assert_eq!(a, b);
        b.advance(-1000);
        assert_eq!(b, Pcg32::new(5, 9));
        // A precomputed stride is the same jump on any stream.
        let s = Stride::new(1 << 16);
        for stream in [0u64, 3, 1 << 40] {
            let (mut a, mut b) = (Pcg32::new(8, stream), Pcg32::new(8, stream));
            a.advance(1 << 16);
            b.jump(&s);
            b.jump(&s);
            a.advance(1 << 16);
            assert_eq!(a, b);
        }
    }

    #[test]
    fn streams_differ() {
        let mut a = Pcg32::new(1, 0);
        let mut b = Pcg32::new(1, 1);
        let same = (0..64).filter(|_| a.next_u32() == b.next_u32()).count();
        assert!(same < 2);
    }

    #[test]
    fn floats_are_uniform_in_unit_interval() {
        let mut r = Pcg32::new(2024, 3);
        let mut lo: f64 = 1.0;
        let out = chi2_1d(
            (0.0, 1.0),
            64,
            1_000_000,
            |_| {
                let x = r.next_f32();
                lo = lo.min(x as f64);
                assert!((0.0..1.0).contains(&x));
                Some(x as f64)
            },
            |_| 1.0,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        let mut r = Pcg32::new(2024, 4);
        let f64s = chi2_1d((0.0, 1.0), 64, 1_000_000, |_| Some(r.next_f64()), |_| 1.0, &Chi2Config::default());
        assert!(f64s.passed(), "{f64s}");
    }

    #[test]
    fn bounded_integers_are_unbiased() {
        let mut r = Pcg32::new(77, 0);
        let bound = 7u32;
        let mut counts = vec![0f64; bound as usize];
        let n = 700_000;
        for _ in 0..n {
            counts[r.next_bounded(bound) as usize] += 1.0;
        }
        let expected = vec![n as f64 / bound as f64; bound as usize];
        let out = crate::testkit::pearson(&counts, &expected, &Chi2Config::default());
        assert!(out.passed(), "{out}");
    }
}
