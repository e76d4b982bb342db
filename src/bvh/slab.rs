//! The slab test of a ray against the eight child boxes of a [`Node8`], in two
//! implementations that give bit-identical answers: [`Slab8`] with 8-wide AVX vectors, and
//! [`Slab4x2`] with two 4-wide halves (SSE on x86-64, portable elsewhere). The traversal picks
//! one per CPU at run time.
//!
//! Per lane: `t_near = max(t_x,near, t_y,near, t_z,near, 0)`, `t_far = min(t_x,far, t_y,far,
//! t_z,far) · (1 + 2γ₃)` clamped to `t_max`, with `t = (plane - o) / d` computed as
//! `(plane - o) · (1/d)`; the child is hit when `t_near ≤ t_far`. The far distance is enlarged
//! so that round-off never culls a box the ray enters. Both implementations evaluate the same
//! operations in the same order (`min`/`max` with the same operand order, so NaN lanes fall
//! the same way).

use super::{Node8, WIDTH};
use crate::math::float::gamma;
use crate::math::simd::Avx;
use crate::math::Ray;
use glam::Vec4;

/// A ray prepared for slab tests against [`Node8`] children.
pub(super) trait SlabTest {
    /// Bit mask of the children hit within `(0, t_max)` (bit k: slot k) and their entry
    /// distances.
    fn test(&self, node: &Node8, t_max: f32) -> (u32, [f32; WIDTH]);
    /// The AVX token where this test runs in AVX code (leaf tests may then use AVX too).
    fn avx(&self) -> Option<Avx>;
}

/// The far-distance enlargement `1 + 2γ₃` (round-off of the three slab distances).
fn far_scale() -> f32 {
    1.0 + 2.0 * gamma(3)
}

/// Per axis, the byte offset in [`Node8::bounds`] of the row holding the plane the ray enters
/// through (`near`) and leaves through (`far`). Byte offsets, not row numbers: the traversal
/// then loads a row at `bounds + offset` without scaling the row number at every node.
fn planes(ray: &Ray) -> ([usize; 3], [usize; 3]) {
    let inv = ray.d.recip();
    // Bit a set: the ray goes down axis a, so it enters through the upper plane.
    let neg = inv.cmplt(crate::math::Vec3::ZERO).bitmask() as usize;
    let row = size_of::<[f32; WIDTH]>();
    (
        [3 * (neg & 1), 1 + 3 * (neg >> 1 & 1), 2 + 3 * (neg >> 2)].map(|r| r * row),
        [3 - 3 * (neg & 1), 4 - 3 * (neg >> 1 & 1), 5 - 3 * (neg >> 2)].map(|r| r * row),
    )
}

/// Lanes `first .. first + n` of the row of `node`'s bounds at byte offset `offset` (an offset
/// from [`planes`]). Safety: `offset` is one of `planes`' and `first + n ≤ WIDTH`.
#[inline(always)]
unsafe fn row_at(node: &Node8, offset: usize, first: usize) -> *const f32 {
    // SAFETY: `planes` gives offsets of the six rows of `bounds`; the caller keeps `first` within
    // the row.
    unsafe { (node.bounds.as_ptr() as *const u8).add(offset).cast::<f32>().add(first) }
}

/// The test in two 4-wide halves (glam's `Vec4`: SSE on x86-64).
pub(super) struct Slab4x2 {
    o: [Vec4; 3],
    inv_d: [Vec4; 3],
    near: [usize; 3],
    far: [usize; 3],
}

impl Slab4x2 {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Slab4x2 {
        let inv = ray.d.recip();
        let (near, far) = planes(ray);
        Slab4x2 {
            o: [Vec4::splat(ray.o.x), Vec4::splat(ray.o.y), Vec4::splat(ray.o.z)],
            inv_d: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near,
            far,
        }
    }
}

impl SlabTest for Slab4x2 {
    #[inline(always)]
    fn avx(&self) -> Option<Avx> {
        None
    }

    #[inline(always)]
    fn test(&self, node: &Node8, t_max: f32) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut t_out = [0.0; WIDTH];
        for half in 0..2 {
            // SAFETY: the offsets come from `planes`, and 4 · half + 4 ≤ WIDTH.
            let row = |r: usize| Vec4::from_slice(unsafe { std::slice::from_raw_parts(row_at(node, r, 4 * half), 4) });
            let tn = |a: usize| (row(self.near[a]) - self.o[a]) * self.inv_d[a];
            let tf = |a: usize| (row(self.far[a]) - self.o[a]) * self.inv_d[a];
            let t_near = tn(0).max(tn(1)).max(tn(2)).max(Vec4::ZERO);
            let t_far = (tf(0).min(tf(1)).min(tf(2)) * far_scale()).min(Vec4::splat(t_max));
            // Unused slots hold empty boxes (min +∞, max -∞), which no ray enters.
            mask |= t_near.cmple(t_far).bitmask() << (4 * half);
            t_near.write_to_slice(&mut t_out[4 * half..4 * half + 4]);
        }
        (mask, t_out)
    }
}

/// The test in one 8-wide AVX vector. Only for CPUs with AVX, from code compiled for it.
#[cfg(target_arch = "x86_64")]
pub(super) struct Slab8 {
    o: [std::arch::x86_64::__m256; 3],
    inv_d: [std::arch::x86_64::__m256; 3],
    near: [usize; 3],
    far: [usize; 3],
}

#[cfg(target_arch = "x86_64")]
impl Slab8 {
    /// Safety: the CPU must have AVX.
    #[inline(always)]
    pub(super) unsafe fn new(ray: &Ray) -> Slab8 {
        use std::arch::x86_64::_mm256_set1_ps;
        let inv = ray.d.recip();
        let (near, far) = planes(ray);
        Slab8 {
            o: [_mm256_set1_ps(ray.o.x), _mm256_set1_ps(ray.o.y), _mm256_set1_ps(ray.o.z)],
            inv_d: [_mm256_set1_ps(inv.x), _mm256_set1_ps(inv.y), _mm256_set1_ps(inv.z)],
            near,
            far,
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl SlabTest for Slab8 {
    #[inline(always)]
    fn avx(&self) -> Option<Avx> {
        // SAFETY: a `Slab8` exists only where the CPU has AVX (`Slab8::new` is unsafe).
        Some(unsafe { Avx::new_unchecked() })
    }

    /// The AVX intrinsics here inline into the traversal compiled for AVX (this function is
    /// always inlined into it; a `#[target_feature]` function of its own would stay a call).
    #[inline(always)]
    fn test(&self, node: &Node8, t_max: f32) -> (u32, [f32; WIDTH]) {
        use std::arch::x86_64::*;
        // SAFETY: a `Slab8` exists only where the CPU has AVX (`Slab8::new` is unsafe); the
        // offsets come from `planes`; loads and stores are unaligned ones of 8 floats.
        unsafe {
            let row = |k: usize| _mm256_loadu_ps(row_at(node, k, 0));
            let tn = |a: usize| _mm256_mul_ps(_mm256_sub_ps(row(self.near[a]), self.o[a]), self.inv_d[a]);
            let tf = |a: usize| _mm256_mul_ps(_mm256_sub_ps(row(self.far[a]), self.o[a]), self.inv_d[a]);
            let t_near = _mm256_max_ps(_mm256_max_ps(_mm256_max_ps(tn(0), tn(1)), tn(2)), _mm256_setzero_ps());
            let t_far = _mm256_min_ps(
                _mm256_mul_ps(_mm256_min_ps(_mm256_min_ps(tf(0), tf(1)), tf(2)), _mm256_set1_ps(far_scale())),
                _mm256_set1_ps(t_max),
            );
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far)) as u32;
            let mut t_out = [0.0; WIDTH];
            _mm256_storeu_ps(t_out.as_mut_ptr(), t_near);
            (mask, t_out)
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::math::{Bounds3, Vec3};
    use crate::sampling::Pcg32;

    /// Which boxes the ray enters within `(0, t_max)`, in double precision: `Some(true)` when
    /// clearly entered, `Some(false)` when clearly missed, `None` within 1e-3 of the border.
    fn reference(b: &Bounds3, o: Vec3, d: Vec3, t_max: f32) -> Option<bool> {
        let (mut t0, mut t1) = (0.0f64, t_max as f64);
        for a in 0..3 {
            let (lo, hi, o, d) = (b.min[a] as f64, b.max[a] as f64, o[a] as f64, d[a] as f64);
            if d == 0.0 {
                if o < lo - 1e-3 || o > hi + 1e-3 {
                    return Some(false);
                }
                if o < lo + 1e-3 || o > hi - 1e-3 {
                    return None;
                }
                continue;
            }
            let (ta, tb) = ((lo - o) / d, (hi - o) / d);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        if t0 < t1 - 1e-3 {
            Some(true)
        } else if t0 > t1 + 1e-3 {
            Some(false)
        } else {
            None
        }
    }

    /// Both implementations answer bit for bit alike, on random boxes (some empty slots) and
    /// rays, including axis-parallel directions (infinite reciprocals) and rays starting on a
    /// box's plane (0 · ∞ products); and both agree with a double-precision slab test on every
    /// box that is clearly entered or clearly missed.
    #[test]
    fn avx_and_sse_agree() {
        if !is_x86_feature_detected!("avx") {
            return;
        }
        let mut rng = Pcg32::new(5, 0);
        let mut f = || rng.next_f32();
        let mut checked = 0;
        for i in 0..20_000 {
            let mut node = Node8::empty();
            for slot in 0..WIDTH {
                if (i + slot) % 5 == 4 {
                    continue;
                }
                let c = Vec3::new(f(), f(), f()) * 4.0 - 2.0;
                let h = Vec3::new(f(), f(), f()) * 0.7;
                node.set(slot, &Bounds3::new(c - h, c + h), slot as u32, 1);
            }
            let mut d = Vec3::new(f() - 0.5, f() - 0.5, f() - 0.5).normalize();
            if i % 7 == 0 {
                d = Vec3::new(0.0, if i % 2 == 0 { 1.0 } else { -1.0 }, 0.0);
            }
            let o =
                if i % 11 == 0 { Vec3::new(node.bounds[0][0], 0.0, 0.0) } else { Vec3::new(f(), f(), f()) * 6.0 - 3.0 };
            let ray = Ray::new(o, d);
            let t_max = if i % 3 == 0 { f32::INFINITY } else { 4.0 * f() };
            let sse = Slab4x2::new(&ray).test(&node, t_max);
            // SAFETY: AVX detected above.
            let avx = unsafe { Slab8::new(&ray) }.test(&node, t_max);
            assert_eq!(sse.0, avx.0, "masks differ on case {i}");
            for slot in 0..WIDTH {
                assert_eq!(sse.1[slot].to_bits(), avx.1[slot].to_bits(), "entry distances differ on case {i}");

                let hit = sse.0 >> slot & 1 == 1;
                if !node.valid(slot) {
                    assert!(!hit, "case {i}: an empty slot was hit");
                } else if let Some(expected) = reference(&node.child_bounds(slot), o, d, t_max) {
                    assert_eq!(hit, expected, "case {i} slot {slot}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 100_000, "{checked}");
    }
}
