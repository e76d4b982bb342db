//! Special functions: the error function and its inverse (single precision), used by the
//! Beckmann microfacet distribution, an exponential without the C library's slow path for
//! underflow, and an exponential of several lanes at once (SIMD) for batches such as a
//! reconstruction filter's weights.

/// The error function `erf(x) = 2/√π ∫₀ˣ e^(-t²) dt`, from the Chebyshev-fitted complementary
/// error function of Numerical Recipes (relative error < 1.2·10⁻⁷): the polynomial and the
/// final `1 − erfc` in `f64` (near zero `erfc` is close to 1), its exponential in `f32` (an
/// `f64` exponential costs more and adds nothing at this precision).
/// Absolute error below 1.5·10⁻⁷ (tested against the Taylor series; 1.1·10⁻⁷ measured).
pub fn erf(x: f32) -> f32 {
    let z = (x as f64).abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98 + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let erfc = t * exp(poly as f32) as f64;
    let r = 1.0 - erfc;
    (if x >= 0.0 { r } else { -r }) as f32
}

/// Below this, `eˣ` in single precision is +0: glibc's `expf` threshold `-0x1.9fe368p6`
/// (`e^x` under half the least subnormal, rounded to zero).
const EXP_UNDERFLOW: f32 = f32::from_bits(0xc2cf_f1b4);

/// `eˣ` as [`f32::exp`] computes it, returning +0 directly where the result underflows: the C
/// library's `expf` takes an error path there (it sets `errno`), which costs as much as many
/// ordinary calls. Microfacet distributions, Smith masking and `erf` take exponentials of large
/// negative arguments all the time (smooth surfaces: `e^(-1/α²…)`).
#[inline]
pub fn exp(x: f32) -> f32 {
    if x < EXP_UNDERFLOW {
        0.0
    } else {
        x.exp()
    }
}

/// `eˣ` lane by lane for arguments in (-87, 88) (where `eˣ` and the `2ⁿ` below are normal
/// floats; the caller guarantees it; [`exp4`] for four lanes in one SIMD register): Cephes'
/// `expf`, `eˣ = 2ⁿ eʳ` with `n = round(x / ln 2)`, `r = x − n ln 2` in two exact parts and a
/// degree-7 polynomial for `eʳ` on `|r| ≤ ln 2 / 2`; within 1 ulp of the correctly rounded value. Branch-free and without calls: in SIMD lanes
/// several exponentials cost about what one call of the C library's costs (a single one, on a
/// chain of dependent operations, is faster through [`exp`]: the library's table-driven `expf`
/// has the shorter latency).
#[inline(always)]
pub fn exp_lanes<const N: usize>(x: [f32; N]) -> [f32; N] {
    let mut out = [0.0f32; N];
    for k in 0..N {
        let shifted = x[k] * std::f32::consts::LOG2_E + EXP_SHIFT;
        let n = shifted - EXP_SHIFT;
        let r = x[k] - n * LN2_HI - n * LN2_LO;
        let mut p = EXP_POLY[0];
        for c in &EXP_POLY[1..] {
            p = p * r + c;
        }
        let e_r = p * (r * r) + r + 1.0;
        // 2ⁿ from the exponent bits: n is the low bits of `shifted`.
        let two_n = f32::from_bits((shifted.to_bits().wrapping_sub(EXP_SHIFT.to_bits()).wrapping_add(127)) << 23);
        out[k] = e_r * two_n;
    }
    out
}

/// [`exp_lanes`] of four lanes in one SSE register on x86-64 (the same operations in the same
/// order: the same bits), elsewhere `exp_lanes` itself. The compiler does not vectorize
/// `exp_lanes`' exponent-bit arithmetic by itself.
#[inline]
pub fn exp4(x: [f32; 4]) -> [f32; 4] {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of every x86-64 CPU (the target's baseline), and the unaligned load
    // and store access the sixteen bytes of a four-f32 array.
    unsafe {
        use std::arch::x86_64::*;
        let mut out = [0.0f32; 4];
        _mm_storeu_ps(out.as_mut_ptr(), exp4_sse(_mm_loadu_ps(x.as_ptr())));
        out
    }
    #[cfg(not(target_arch = "x86_64"))]
    exp_lanes(x)
}

/// [`exp4`] on a register, for callers that keep their lanes in one.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub fn exp4_sse(x: std::arch::x86_64::__m128) -> std::arch::x86_64::__m128 {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of every x86-64 CPU (the target's baseline).
    unsafe {
        let v = |c: f32| _mm_set1_ps(c);
        let shifted = _mm_add_ps(_mm_mul_ps(x, v(std::f32::consts::LOG2_E)), v(EXP_SHIFT));
        let n = _mm_sub_ps(shifted, v(EXP_SHIFT));
        let r = _mm_sub_ps(_mm_sub_ps(x, _mm_mul_ps(n, v(LN2_HI))), _mm_mul_ps(n, v(LN2_LO)));
        let mut p = v(EXP_POLY[0]);
        for c in &EXP_POLY[1..] {
            p = _mm_add_ps(_mm_mul_ps(p, r), v(*c));
        }
        let e_r = _mm_add_ps(_mm_add_ps(_mm_mul_ps(p, _mm_mul_ps(r, r)), r), v(1.0));
        let bits = _mm_sub_epi32(_mm_castps_si128(shifted), _mm_set1_epi32(EXP_SHIFT.to_bits() as i32));
        let two_n = _mm_castsi128_ps(_mm_slli_epi32::<23>(_mm_add_epi32(bits, _mm_set1_epi32(127))));
        _mm_mul_ps(e_r, two_n)
    }
}

/// Round to nearest by adding and subtracting 1.5·2²³ (exact for |x| < 2²²).
const EXP_SHIFT: f32 = 12_582_912.0;
/// ln 2 = LN2_HI + LN2_LO, LN2_HI of 9 significant bits: n · LN2_HI and x − n · LN2_HI are exact.
const LN2_HI: f32 = 0.693_359_4;
const LN2_LO: f32 = -2.121_944_4e-4;
/// Cephes' `expf` polynomial: `eʳ ≈ 1 + r + r² P(r)`, coefficients of P from the highest degree.
const EXP_POLY: [f32; 6] = [1.987_569_1e-4, 1.398_199_9e-3, 8.333_452e-3, 4.166_579_6e-2, 0.166_666_65, 0.5];

/// The inverse error function on (-1, 1) clamped to ±(1 − 10⁻⁷): Giles' single-precision
/// polynomial fit ("Approximating the erfinv function", 2010; Mitsuba's `dr::erfinv`), one
/// logarithm and a polynomial. The exact erf of the result lies within 10⁻⁷ of x (measured
/// 0.86·10⁻⁷ over erf's range up to erf(3)). A Newton step on [`erf`] does not improve it: it
/// measured 1.12·10⁻⁷, [`erf`]'s own error, at the price of an `erf` and an exponential.
#[inline]
pub fn erfinv(x: f32) -> f32 {
    let x = x.clamp(-1.0 + 1e-7, 1.0 - 1e-7);
    let mut w = -((1.0 - x) * (1.0 + x)).ln();
    let p = if w < 5.0 {
        w -= 2.5;
        let mut p = 2.810_226_4e-8f32;
        for c in [
            3.432_739_4e-7,
            -3.523_387_7e-6,
            -4.391_506_5e-6,
            2.185_808_7e-4,
            -1.253_725e-3,
            -4.177_681_6e-3,
            0.246_640_73,
            1.501_409_4,
        ] {
            p = c + p * w;
        }
        p
    } else {
        w = w.sqrt() - 3.0;
        let mut p = -2.002_142_6e-4f32;
        for c in [
            1.009_505_6e-4,
            1.349_343_2e-3,
            -3.673_428_4e-3,
            5.739_507_7e-3,
            -7.622_461_3e-3,
            9.438_870_5e-3,
            1.001_674,
            2.832_976_8,
        ] {
            p = c + p * w;
        }
        p
    };
    p * x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `exp` is `f32::exp`, bit for bit, on a sweep of the whole range (through the underflow
    /// threshold, with the special values).
    #[test]
    fn exp_is_the_library_exp() {
        let mut x = -200.0f32;
        let mut underflowed = 0;
        while x < 100.0 {
            assert_eq!(exp(x).to_bits(), x.exp().to_bits(), "{x}");
            underflowed += usize::from(exp(x) == 0.0);
            x += 1e-3;
        }
        assert!(underflowed > 90_000, "{underflowed} zeros");
        for bits in EXP_UNDERFLOW.to_bits() - 1000..EXP_UNDERFLOW.to_bits() + 1000 {
            let x = f32::from_bits(bits);
            assert_eq!(exp(x).to_bits(), x.exp().to_bits(), "{x}");
        }
        for x in [f32::NEG_INFINITY, f32::INFINITY, f32::MIN, f32::MAX, -0.0, 0.0] {
            assert_eq!(exp(x).to_bits(), x.exp().to_bits(), "{x}");
        }
        assert!(exp(f32::NAN).is_nan());
    }

    /// Every float of (-87, 88) at a stride of 97 bits (some 22 million), within 1 ulp of the
    /// correctly rounded `f64` exponential.
    #[test]
    fn exp_lanes_within_an_ulp() {
        let mut worst = 0i64;
        let mut count = 0usize;
        let mut batch = [0.0f32; 8];
        let mut filled = 0;
        let mut check = |batch: &[f32; 8]| {
            let halves = [exp4(batch[..4].try_into().unwrap()), exp4(batch[4..].try_into().unwrap())];
            assert_eq!(halves.concat(), exp_lanes(*batch), "{batch:?}");
            for (x, got) in batch.iter().zip(exp_lanes(*batch)) {
                let want = (*x as f64).exp() as f32;
                worst = worst.max((got.to_bits() as i64 - want.to_bits() as i64).abs());
            }
        };
        for bits in (0..0x7f80_0000u32).step_by(97) {
            for x in [f32::from_bits(bits), -f32::from_bits(bits)] {
                if x > -87.0 && x < 88.0 {
                    batch[filled] = x;
                    filled += 1;
                    count += 1;
                    if filled == 8 {
                        check(&batch);
                        filled = 0;
                    }
                }
            }
        }
        check(&batch);
        assert!(count > 20_000_000, "{count}");
        assert!(worst <= 1, "{worst} ulps");
        assert_eq!(exp_lanes([0.0, -0.0, 1.0]), [1.0, 1.0, std::f32::consts::E]);
    }

    #[test]
    fn erf_reference_values() {
        // erf(0.5), erf(1), erf(2) to 10 digits.
        for (x, e) in [
            (0.0f32, 0.0f64),
            (0.5, 0.520_499_877_8),
            (1.0, 0.842_700_792_9),
            (2.0, 0.995_322_265_0),
            (-1.0, -0.842_700_792_9),
        ] {
            assert!((erf(x) as f64 - e).abs() < 3e-7, "erf({x})");
        }
    }

    /// erf by its Taylor series in `f64` (accurate to about 10⁻⁹ for |x| ≤ 4).
    fn erf_series(x: f64) -> f64 {
        let (mut term, mut sum) = (x, x);
        for n in 1..200 {
            term *= -x * x / n as f64;
            sum += term / (2 * n + 1) as f64;
        }
        sum * 2.0 / std::f64::consts::PI.sqrt()
    }

    /// Over a dense grid of (-4, 4): erf within 1.5·10⁻⁷ of the series (measured 1.1·10⁻⁷), and
    /// erfinv inverts the series' erf to within 10⁻⁷ (about one ulp of the values near ±1 it
    /// inverts; measured 0.86·10⁻⁷, where the fit with a Newton step on `erf` measured
    /// 1.12·10⁻⁷).
    #[test]
    fn erf_and_erfinv_against_the_series() {
        let (mut worst_erf, mut worst_inv) = (0.0f64, 0.0f64);
        for i in -4000..=4000 {
            let x = i as f64 / 1000.0;
            worst_erf = worst_erf.max((erf(x as f32) as f64 - erf_series(x)).abs());
            if x.abs() < 3.0 {
                let e = erf_series(x) as f32;
                if e.abs() < 1.0 {
                    worst_inv = worst_inv.max((erf_series(erfinv(e) as f64) - e as f64).abs());
                }
            }
        }
        assert!(worst_erf < 1.5e-7, "erf: {worst_erf:e}");
        assert!(worst_inv < 1e-7, "erfinv: {worst_inv:e}");
    }

    #[test]
    fn erfinv_inverts_erf() {
        for i in -99..=99 {
            let x = i as f32 / 100.0;
            let y = erfinv(x);
            assert!((erf(y) - x).abs() < 2e-6, "x = {x}: erf(erfinv) = {}", erf(y));
        }
        assert!(erfinv(0.999_999).is_finite());
    }
}
