//! Floating-point error helpers for robust ray spawning (pbrt-v4 §6.8, Higham's γₙ).
//!
//! Intersection routines return a conservative absolute error bound `p_err` on each coordinate
//! of the hit point. A new ray leaves the surface from [`offset_ray_origin`]: the hit point pushed
//! along the geometric normal just past that error box, to the side the ray goes, then rounded
//! away from the surface, so that the ray never re-hits the surface it left. No fixed epsilon.

use glam::Vec3;

/// Unit round-off of `f32` (half the machine epsilon).
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// Higham's bound `γₙ = n ε / (1 - n ε)` on the relative error of `n` chained `f32` operations.
#[inline]
pub const fn gamma(n: i32) -> f32 {
    (n as f32 * MACHINE_EPSILON) / (1.0 - n as f32 * MACHINE_EPSILON)
}

/// The smallest `f32` greater than `v` (`v` itself for +∞ and NaN).
#[inline]
pub fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 || v.is_nan() {
        return v;
    }
    let v = if v == -0.0 { 0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v >= 0.0 { bits + 1 } else { bits - 1 };
    f32::from_bits(bits)
}

/// The largest `f32` smaller than `v` (`v` itself for -∞ and NaN).
#[inline]
pub fn next_float_down(v: f32) -> f32 {
    if v.is_infinite() && v < 0.0 || v.is_nan() {
        return v;
    }
    let v = if v == 0.0 { -0.0 } else { v };
    let bits = v.to_bits();
    let bits = if v > 0.0 { bits - 1 } else { bits + 1 };
    f32::from_bits(bits)
}

/// Origin for a ray leaving a surface point `p` (with per-coordinate absolute error bound
/// `p_err`, world units) in direction `w`: `p` offset along the geometric normal `n` by
/// `|n|·p_err` to the side of `w`, each coordinate then rounded away from `p`.
#[inline]
pub fn offset_ray_origin(p: Vec3, p_err: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    // The side as a sign bit, without a branch (w · n has no predictable sign).
    let flip = ((w.dot(n) < 0.0) as u32) << 31;
    let d = f32::from_bits(n.abs().dot(p_err).to_bits() ^ flip);
    let offset = n * d;
    step_toward_sign3(p + offset, offset)
}

/// [`step_toward_sign`] on the three coordinates at once: SSE2 integer lanes on x86-64 (the
/// same bit operations, lane by lane), the scalar function elsewhere.
#[inline(always)]
fn step_toward_sign3(c: Vec3, o: Vec3) -> Vec3 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        // SAFETY: SSE2 is part of the x86-64 baseline; only register operations.
        unsafe {
            let cv = _mm_castps_si128(_mm_set_ps(0.0, c.z, c.y, c.x));
            let ov = _mm_castps_si128(_mm_set_ps(0.0, o.z, o.y, o.x));
            let sign = _mm_set1_epi32(i32::MIN);
            let mag = _mm_andnot_si128(sign, cv);
            let zero_mag = _mm_cmpeq_epi32(mag, _mm_setzero_si128());
            let same_sign = _mm_cmpeq_epi32(_mm_and_si128(_mm_xor_si128(cv, ov), sign), _mm_setzero_si128());
            let grow = _mm_or_si128(zero_mag, same_sign);
            // +1 where growing, -1 elsewhere.
            let delta = _mm_sub_epi32(_mm_and_si128(grow, _mm_set1_epi32(2)), _mm_set1_epi32(1));
            let new_mag = _mm_add_epi32(mag, delta);
            let new_sign = _mm_or_si128(
                _mm_and_si128(zero_mag, _mm_and_si128(ov, sign)),
                _mm_andnot_si128(zero_mag, _mm_and_si128(cv, sign)),
            );
            let stepped = _mm_or_si128(new_sign, new_mag);
            // Keep c where o = ±0 or c is infinite or NaN.
            let o_zero = _mm_castps_si128(_mm_cmpeq_ps(_mm_castsi128_ps(ov), _mm_setzero_ps()));
            let not_finite = _mm_cmpgt_epi32(mag, _mm_set1_epi32(0x7f7f_ffff));
            let keep = _mm_or_si128(o_zero, not_finite);
            let r = _mm_castsi128_ps(_mm_or_si128(_mm_and_si128(keep, cv), _mm_andnot_si128(keep, stepped)));
            let mut out = [0.0f32; 4];
            _mm_storeu_ps(out.as_mut_ptr(), r);
            Vec3::new(out[0], out[1], out[2])
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec3::new(step_toward_sign(c.x, o.x), step_toward_sign(c.y, o.y), step_toward_sign(c.z, o.z))
    }
}

/// `c` moved one ulp in the direction of `o`'s sign (up for `o > 0`, down for `o < 0`); `c`
/// itself for `o = 0` and for infinite or NaN `c`. The same as [`next_float_up`] /
/// [`next_float_down`] on finite values, without branches (the signs are unpredictable).
#[inline(always)]
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn step_toward_sign(c: f32, o: f32) -> f32 {
    const SIGN: u32 = 0x8000_0000;
    let (cb, ob) = (c.to_bits(), o.to_bits());
    let mag = cb & !SIGN;
    // Away from zero when c and o share a sign (or c is ±0, which takes o's sign); else toward.
    let grow = mag == 0 || (cb ^ ob) & SIGN == 0;
    let new_mag = if grow { mag + 1 } else { mag - 1 };
    let sign = if mag == 0 { ob & SIGN } else { cb & SIGN };
    let stepped = f32::from_bits(sign | new_mag);
    if o == 0.0 || mag >= 0x7f80_0000 {
        c
    } else {
        stepped
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::rng::Pcg32;

    #[test]
    fn next_float_steps_one_ulp() {
        assert!(next_float_up(1.0) > 1.0);
        assert_eq!(next_float_up(1.0).to_bits(), 1.0f32.to_bits() + 1);
        assert!(next_float_down(1.0) < 1.0);
        assert_eq!(next_float_up(0.0), f32::from_bits(1));
        assert_eq!(next_float_up(-0.0), f32::from_bits(1));
        assert_eq!(next_float_down(0.0), -f32::from_bits(1));
        assert!(next_float_up(-1.0) > -1.0);
        assert_eq!(next_float_up(f32::INFINITY), f32::INFINITY);
        assert_eq!(next_float_down(f32::NEG_INFINITY), f32::NEG_INFINITY);
        assert_eq!(next_float_up(f32::MAX), f32::INFINITY);
    }

    #[test]
    fn branchless_step_matches_next_float() {
        let mut rng = Pcg32::new(4, 4);
        let mut values = vec![0.0f32, -0.0, 1.0, -1.0, f32::MIN_POSITIVE, -f32::from_bits(1), f32::MAX, -f32::MAX];
        values.extend((0..10_000).map(|_| f32::from_bits(rng.next_u32() & 0xff7f_ffff)));
        for c in values {
            for o in [1e-3f32, -2.5, 0.0, -0.0] {
                let expected = if o > 0.0 {
                    next_float_up(c)
                } else if o < 0.0 {
                    next_float_down(c)
                } else {
                    c
                };
                assert_eq!(step_toward_sign(c, o).to_bits(), expected.to_bits(), "{c:e} toward {o}");
                // The three-lane version agrees in every lane, whatever the other lanes hold.
                for lane in 0..3 {
                    let (mut cv, mut ov) = (Vec3::new(2.0, -3.0, 0.0), Vec3::new(-1.0, 0.0, 1.0));
                    cv[lane] = c;
                    ov[lane] = o;
                    let got = step_toward_sign3(cv, ov);
                    assert_eq!(got[lane].to_bits(), expected.to_bits(), "lane {lane}: {c:e} toward {o}");
                    for other in (0..3).filter(|&k| k != lane) {
                        assert_eq!(got[other].to_bits(), step_toward_sign(cv[other], ov[other]).to_bits());
                    }
                }
            }
        }
        let inf = step_toward_sign3(Vec3::new(f32::INFINITY, f32::NAN, f32::NEG_INFINITY), Vec3::ONE);
        assert!(inf.x == f32::INFINITY && inf.y.is_nan() && inf.z == f32::NEG_INFINITY);
        assert_eq!(step_toward_sign(f32::INFINITY, 1.0), f32::INFINITY);
        assert!(step_toward_sign(f32::NAN, 1.0).is_nan());
    }

    #[test]
    fn gamma_bounds_accumulated_error() {
        assert!(gamma(1) > MACHINE_EPSILON && gamma(1) < 1.0001 * MACHINE_EPSILON);
        assert!(gamma(3) > 3.0 * MACHINE_EPSILON);
        // A sum of n products evaluated in f32 stays within γ_n of the exact (f64) value.
        let mut rng = Pcg32::new(3, 1);
        for _ in 0..10_000 {
            let a: Vec<f32> = (0..3).map(|_| rng.next_f32() * 10.0).collect();
            let b: Vec<f32> = (0..3).map(|_| rng.next_f32() * 10.0).collect();
            let f = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            let exact: f64 = (0..3).map(|i| a[i] as f64 * b[i] as f64).sum();
            assert!(((f as f64) - exact).abs() <= gamma(3) as f64 * exact);
        }
    }

    #[test]
    fn offset_origin_lands_on_the_side_of_the_ray() {
        // Points on a tilted plane through c with normal n: the offset origin must be strictly on
        // the side of w, and within a few error bounds of p.
        let mut rng = Pcg32::new(11, 2);
        let n = Vec3::new(0.3, -0.5, 0.81).normalize();
        let c = Vec3::new(100.0, -3.0, 7.0);
        let f = crate::math::Frame::from_z(n);
        for _ in 0..10_000 {
            let local = Vec3::new(rng.next_f32() * 200.0 - 100.0, rng.next_f32() * 200.0 - 100.0, 0.0);
            let p = c + f.to_world(local);
            // True plane distance in f64 of the rounded point: its error is the residual.
            let dist = |q: Vec3| {
                (q.x as f64 - c.x as f64) * n.x as f64
                    + (q.y as f64 - c.y as f64) * n.y as f64
                    + (q.z as f64 - c.z as f64) * n.z as f64
            };
            let err = Vec3::splat(gamma(6) * p.abs().max_element().max(c.abs().max_element()) * 4.0);
            for w in [n, -n] {
                let o = offset_ray_origin(p, err, n, w);
                let side = dist(o) * (w.dot(n) as f64).signum();
                assert!(side > 0.0, "offset origin on the wrong side of the surface");
                assert!((o - p).length() < 10.0 * err.length());
            }
        }
    }
}
