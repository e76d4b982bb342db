//! SIMD chosen at run time: the [`Avx`] token, which only exists on a CPU with AVX, and
//! [`F32x8`], eight `f32` lanes in one AVX register, which can only be made with the token.
//!
//! Code that uses [`F32x8`] is written as ordinary `#[inline(always)]` functions and runs
//! fast only where it is inlined into a function compiled for AVX (`#[target_feature(enable =
//! "avx")]`, such as the BVH's AVX traversal): there the intrinsics inline too. Elsewhere it is
//! still correct, one call per operation.
//!
//! The operations are IEEE single precision, lane by lane, as SSE's four lanes compute them
//! (`min`/`max` return the second operand when either is NaN, as `minps`/`maxps` do), so code
//! generic over [`glam::Vec4`] and [`F32x8`] gives the same bits in both.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Proof that this CPU has AVX: made only by [`Avx::detect`] (a run-time check) or by code
/// that already runs under that guarantee ([`Avx::new_unchecked`]).
#[derive(Clone, Copy, Debug)]
pub struct Avx(());

impl Avx {
    /// The token, if this CPU has AVX.
    pub fn detect() -> Option<Avx> {
        #[cfg(target_arch = "x86_64")]
        if is_x86_feature_detected!("avx") {
            return Some(Avx(()));
        }
        None
    }

    /// The token without a check.
    ///
    /// # Safety
    ///
    /// The CPU must have AVX (for instance, the caller is compiled with
    /// `#[target_feature(enable = "avx")]`, which is only called where it has).
    #[inline(always)]
    pub unsafe fn new_unchecked() -> Avx {
        Avx(())
    }
}

/// The ordered (false where either lane is NaN) comparisons of [`F32x8`], one per predicate.
#[cfg(target_arch = "x86_64")]
macro_rules! compare {
    ($($(#[$doc:meta])* $name:ident $predicate:ident;)*) => {$(
        $(#[$doc])*
        #[inline(always)]
        pub fn $name(self, o: F32x8) -> M8 {
            M8(unsafe { _mm256_cmp_ps::<$predicate>(self.0, o.0) })
        }
    )*};
}

/// Eight `f32` lanes in an AVX register.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub struct F32x8(__m256);

/// The lane mask of an [`F32x8`] comparison: all bits set in the lanes where it holds.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub struct M8(__m256);

// SAFETY (every `unsafe` block below): an `F32x8` or `M8` exists only if an `Avx` token did,
// so the CPU has AVX; loads and stores are of exactly eight floats.
#[cfg(target_arch = "x86_64")]
impl F32x8 {
    /// All lanes `x`.
    #[inline(always)]
    pub fn splat(_: Avx, x: f32) -> F32x8 {
        F32x8(unsafe { _mm256_set1_ps(x) })
    }

    /// The eight floats of `a` (lane k = `a[k]`).
    #[inline(always)]
    pub fn load(_: Avx, a: &[f32; 8]) -> F32x8 {
        F32x8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [f32; 8] {
        let mut a = [0.0; 8];
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
        a
    }

    /// Lane-wise `min(self, o)` (`o` where either is NaN).
    #[inline(always)]
    pub fn min(self, o: F32x8) -> F32x8 {
        F32x8(unsafe { _mm256_min_ps(self.0, o.0) })
    }

    /// Lane-wise `max(self, o)` (`o` where either is NaN).
    #[inline(always)]
    pub fn max(self, o: F32x8) -> F32x8 {
        F32x8(unsafe { _mm256_max_ps(self.0, o.0) })
    }

    /// Lane-wise `|self|`.
    #[inline(always)]
    pub fn abs(self) -> F32x8 {
        F32x8(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0) })
    }

    /// Lane-wise `1 / self` (a division, exact as `1.0 / x` is).
    #[inline(always)]
    pub fn recip(self) -> F32x8 {
        F32x8(unsafe { _mm256_div_ps(_mm256_set1_ps(1.0), self.0) })
    }

    /// The smallest lane, reduced pairwise as `min` does.
    #[inline(always)]
    pub fn min_element(self) -> f32 {
        unsafe {
            let m = _mm256_min_ps(self.0, _mm256_permute2f128_ps::<1>(self.0, self.0));
            let m = _mm256_min_ps(m, _mm256_permute_ps::<0b01_00_11_10>(m));
            let m = _mm256_min_ps(m, _mm256_permute_ps::<0b10_11_00_01>(m));
            _mm256_cvtss_f32(m)
        }
    }

    compare! {
        /// Lanes where `self == o`.
        cmpeq _CMP_EQ_OQ;
        /// Lanes where `self >= o`.
        cmpge _CMP_GE_OQ;
        /// Lanes where `self <= o`.
        cmple _CMP_LE_OQ;
        /// Lanes where `self > o`.
        cmpgt _CMP_GT_OQ;
        /// Lanes where `self < o`.
        cmplt _CMP_LT_OQ;
        /// Lanes where `self != o` (true where either is NaN, as SSE's `cmpneq`).
        cmpne _CMP_NEQ_UQ;
    }

    /// Lane-wise `m ? a : b`.
    #[inline(always)]
    pub fn select(m: M8, a: F32x8, b: F32x8) -> F32x8 {
        F32x8(unsafe { _mm256_blendv_ps(b.0, a.0, m.0) })
    }
}

/// Lane `k` (below 4) of each of four vectors, gathered into one: `(a[k], b[k], c[k], d[k])`
/// for `v = [a, b, c, d]`, bit for bit. In registers (the other lanes masked off, then the four
/// folded together by shuffles and ors): reading the lanes back one by one from a stored
/// vector waits on that store.
#[inline(always)]
pub fn gather_lane4(v: [glam::Vec4; 4], k: usize) -> glam::Vec4 {
    debug_assert!(k < 4);
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of x86-64.
    unsafe {
        let one_hot = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_set_epi32(3, 2, 1, 0), _mm_set1_epi32(k as i32)));
        let [a, b, c, d] = v.map(|x| _mm_and_ps(__m128::from(x), one_hot));
        fold_one_hot4(a, b, c, d).into()
    }
    #[cfg(not(target_arch = "x86_64"))]
    glam::Vec4::new(v[0][k], v[1][k], v[2][k], v[3][k])
}

/// `(Σ a, Σ b, Σ c, Σ d)` as bits (an or of the lanes) of four vectors that are zero but in
/// one lane, the same lane in each.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn fold_one_hot4(a: __m128, b: __m128, c: __m128, d: __m128) -> __m128 {
    // (a0|a2, b0|b2, a1|a3, b1|b3) and the same of c and d.
    let ab = _mm_or_ps(_mm_unpacklo_ps(a, b), _mm_unpackhi_ps(a, b));
    let cd = _mm_or_ps(_mm_unpacklo_ps(c, d), _mm_unpackhi_ps(c, d));
    _mm_or_ps(_mm_movelh_ps(ab, cd), _mm_movehl_ps(cd, ab))
}

#[cfg(target_arch = "x86_64")]
impl F32x8 {
    /// Lane `k` (below 8) of each of four vectors, gathered into one: `(a[k], b[k], c[k],
    /// d[k])` for `v = [a, b, c, d]`, bit for bit, in registers (see [`gather_lane4`]).
    #[inline(always)]
    pub fn gather_lane(v: [F32x8; 4], k: usize) -> glam::Vec4 {
        debug_assert!(k < 8);
        unsafe {
            let iota = _mm256_set_ps(7.0, 6.0, 5.0, 4.0, 3.0, 2.0, 1.0, 0.0);
            let one_hot = _mm256_cmp_ps::<_CMP_EQ_OQ>(iota, _mm256_set1_ps(k as f32));
            let [a, b, c, d] = v.map(|x| {
                let m = _mm256_and_ps(x.0, one_hot);
                _mm_or_ps(_mm256_castps256_ps128(m), _mm256_extractf128_ps::<1>(m))
            });
            fold_one_hot4(a, b, c, d).into()
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl M8 {
    /// Bit k set where lane k holds.
    #[inline(always)]
    pub fn bitmask(self) -> u32 {
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }

    /// Whether any lane holds.
    #[inline(always)]
    pub fn any(self) -> bool {
        unsafe { _mm256_testz_ps(self.0, self.0) == 0 }
    }
}

#[cfg(target_arch = "x86_64")]
macro_rules! binary {
    ($($trait:ident $method:ident $ty:ident $intrinsic:ident;)*) => {$(
        impl std::ops::$trait for $ty {
            type Output = $ty;
            #[inline(always)]
            fn $method(self, o: $ty) -> $ty {
                $ty(unsafe { $intrinsic(self.0, o.0) })
            }
        }
    )*};
}

#[cfg(target_arch = "x86_64")]
binary! {
    Add add F32x8 _mm256_add_ps;
    Sub sub F32x8 _mm256_sub_ps;
    Mul mul F32x8 _mm256_mul_ps;
    BitAnd bitand M8 _mm256_and_ps;
    BitOr bitor M8 _mm256_or_ps;
}

/// `x · v` in every lane (as glam's `f32 * Vec4`).
#[cfg(target_arch = "x86_64")]
impl std::ops::Mul<F32x8> for f32 {
    type Output = F32x8;
    #[inline(always)]
    fn mul(self, v: F32x8) -> F32x8 {
        F32x8(unsafe { _mm256_mul_ps(_mm256_set1_ps(self), v.0) })
    }
}

#[cfg(test)]
#[cfg(target_arch = "x86_64")]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;
    use glam::Vec4;

    /// Every operation gives, lane for lane, the bits SSE's four lanes give (NaN, infinities
    /// and signed zeros among the inputs), and the reductions pick the same lane.
    #[test]
    fn lanes_match_sse() {
        let Some(avx) = Avx::detect() else { return };
        let mut rng = Pcg32::new(9, 1);
        let special = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -0.0, 1e-40, 3.0e38];
        for round in 0..2000 {
            let mut value = |k: usize| {
                if (round + k).is_multiple_of(9) {
                    special[(round + k) % special.len()]
                } else {
                    (rng.next_f32() - 0.5) * 8.0
                }
            };
            let a: [f32; 8] = std::array::from_fn(&mut value);
            let b: [f32; 8] = std::array::from_fn(|k| value(k + 3));
            let (x, y) = (F32x8::load(avx, &a), F32x8::load(avx, &b));
            let halves = |v: &[f32; 8]| [Vec4::from_slice(&v[..4]), Vec4::from_slice(&v[4..])];
            let (xa, ya) = (halves(&a), halves(&b));
            let same = |v: F32x8, f: &dyn Fn(Vec4, Vec4) -> Vec4| {
                let w = v.to_array();
                for h in 0..2 {
                    let r = f(xa[h], ya[h]).to_array();
                    for k in 0..4 {
                        assert_eq!(w[4 * h + k].to_bits(), r[k].to_bits(), "round {round} lane {}", 4 * h + k);
                    }
                }
            };
            same(x + y, &|p, q| p + q);
            same(x - y, &|p, q| p - q);
            same(x * y, &|p, q| p * q);
            same(x.min(y), &|p, q| p.min(q));
            same(x.max(y), &|p, q| p.max(q));
            same(x.abs(), &|p, _| p.abs());
            same(x.recip(), &|p, _| p.recip());
            same(F32x8::select(x.cmplt(y), x, y), &|p, q| Vec4::select(p.cmplt(q), p, q));
            let masks = [
                (x.cmpeq(y), [xa[0].cmpeq(ya[0]), xa[1].cmpeq(ya[1])]),
                (x.cmpge(y), [xa[0].cmpge(ya[0]), xa[1].cmpge(ya[1])]),
                (x.cmple(y), [xa[0].cmple(ya[0]), xa[1].cmple(ya[1])]),
                (x.cmpgt(y), [xa[0].cmpgt(ya[0]), xa[1].cmpgt(ya[1])]),
                (x.cmplt(y), [xa[0].cmplt(ya[0]), xa[1].cmplt(ya[1])]),
                (x.cmpne(y), [xa[0].cmpne(ya[0]), xa[1].cmpne(ya[1])]),
                (
                    x.cmplt(y) & x.cmpgt(y),
                    [xa[0].cmplt(ya[0]) & xa[0].cmpgt(ya[0]), xa[1].cmplt(ya[1]) & xa[1].cmpgt(ya[1])],
                ),
                (
                    x.cmplt(y) | x.cmpeq(y),
                    [xa[0].cmplt(ya[0]) | xa[0].cmpeq(ya[0]), xa[1].cmplt(ya[1]) | xa[1].cmpeq(ya[1])],
                ),
            ];
            for (m, [m0, m1]) in masks {
                assert_eq!(m.bitmask(), m0.bitmask() | m1.bitmask() << 4, "round {round}");
                assert_eq!(m.any(), m0.any() || m1.any());
            }
            if a.iter().all(|v| !v.is_nan()) {
                let expected = a.iter().copied().fold(f32::INFINITY, f32::min);
                assert_eq!(x.min_element(), expected, "round {round}");
            }
            assert!(F32x8::splat(avx, a[0]).to_array().iter().all(|v| v.to_bits() == a[0].to_bits()));
        }
    }

    /// Gathering lane k of four vectors gives exactly those lanes' bits (NaN payloads, −0,
    /// infinities, subnormals included), at every k, for both widths.
    #[test]
    fn gathered_lanes_keep_their_bits() {
        let mut rng = Pcg32::new(17, 3);
        let special = [f32::NAN, -f32::NAN, f32::from_bits(0x7fc0_1234), -0.0, 0.0, f32::INFINITY, -1e-40, 1.5];
        let avx = Avx::detect();
        for round in 0..500 {
            let rows: [[f32; 8]; 4] = std::array::from_fn(|r| {
                std::array::from_fn(|k| {
                    if (round + 3 * r + k) % 5 == 0 {
                        special[(round + r + k) % special.len()]
                    } else {
                        rng.next_f32() * 200.0 - 100.0
                    }
                })
            });
            let bits = |v: Vec4| v.to_array().map(f32::to_bits);
            for k in 0..4 {
                let v = rows.map(|row| Vec4::from_slice(&row[..4]));
                assert_eq!(bits(gather_lane4(v, k)), rows.map(|row| row[k].to_bits()), "round {round} lane {k}");
            }
            if let Some(avx) = avx {
                for k in 0..8 {
                    let v = rows.map(|row| F32x8::load(avx, &row));
                    assert_eq!(bits(F32x8::gather_lane(v, k)), rows.map(|row| row[k].to_bits()), "round {round} lane {k}");
                }
            }
        }
    }
}
