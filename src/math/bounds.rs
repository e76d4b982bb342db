//! Axis-aligned bounding boxes.

use super::Ray;
use glam::Vec3;

/// An axis-aligned box `[min, max]`. The empty box has `min = +∞`, `max = -∞`, so that
/// [`Bounds3::union`] with it is the identity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds3 {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Bounds3 {
    fn default() -> Self {
        Bounds3::EMPTY
    }
}

impl Bounds3 {
    /// The empty box.
    pub const EMPTY: Bounds3 = Bounds3 { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    /// Box spanned by two points (in any order).
    pub fn new(a: Vec3, b: Vec3) -> Bounds3 {
        Bounds3 { min: a.min(b), max: a.max(b) }
    }

    /// Degenerate box holding one point.
    pub fn from_point(p: Vec3) -> Bounds3 {
        Bounds3 { min: p, max: p }
    }

    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Whether both corners are finite (no NaN or infinite coordinate).
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// Smallest box holding both.
    #[inline]
    pub fn union(&self, o: &Bounds3) -> Bounds3 {
        Bounds3 { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    /// Smallest box holding this one and `p`.
    #[inline]
    pub fn union_point(&self, p: Vec3) -> Bounds3 {
        Bounds3 { min: self.min.min(p), max: self.max.max(p) }
    }

    /// Intersection of the two boxes (possibly empty).
    pub fn intersection(&self, o: &Bounds3) -> Bounds3 {
        Bounds3 { min: self.min.max(o.min), max: self.max.min(o.max) }
    }

    /// Whether `p` lies inside or on the boundary.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// `max - min` (negative for the empty box).
    #[inline]
    pub fn diagonal(&self) -> Vec3 {
        self.max - self.min
    }

    /// Centre point.
    #[inline]
    pub fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Surface area (0 for the empty box), the SAH cost measure.
    #[inline]
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let d = self.diagonal();
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// Index (0, 1, 2) of the longest axis.
    pub fn max_extent(&self) -> usize {
        let d = self.diagonal();
        if d.x >= d.y && d.x >= d.z {
            0
        } else if d.y >= d.z {
            1
        } else {
            2
        }
    }

    /// Position of `p` relative to the box: 0 at `min`, 1 at `max`, per axis.
    pub fn offset(&self, p: Vec3) -> Vec3 {
        let d = self.diagonal();
        let o = p - self.min;
        Vec3::new(
            if d.x > 0.0 { o.x / d.x } else { 0.0 },
            if d.y > 0.0 { o.y / d.y } else { 0.0 },
            if d.z > 0.0 { o.z / d.z } else { 0.0 },
        )
    }

    /// Corner `i` ∈ 0..8: bit 0 selects max x, bit 1 max y, bit 2 max z.
    pub fn corner(&self, i: usize) -> Vec3 {
        Vec3::new(
            if i & 1 != 0 { self.max.x } else { self.min.x },
            if i & 2 != 0 { self.max.y } else { self.min.y },
            if i & 4 != 0 { self.max.z } else { self.min.z },
        )
    }

    /// Centre and radius of a sphere that encloses the box.
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        if self.is_empty() {
            return (Vec3::ZERO, 0.0);
        }
        let c = self.centroid();
        let d = self.max - c;
        let m = d.abs().max_element();
        if m > 1e18 {
            // |d|² would overflow single precision: the length of d / m, times m, a hair longer
            // for the rounding (a box some 10¹⁹ units wide and more still has a finite sphere).
            return (c, m * (d / m).length() * (1.0 + 1e-6));
        }
        (c, d.length())
    }

    /// Slab test: the parametric interval `(t0, t1)` of the ray inside the box, clipped to
    /// `(0, ray.t_max)`, or `None`. `inv_d` is `1 / ray.d` per component. The far distance is
    /// scaled by `1 + 2γ₃` (pbrt-v4 §6.8.2) so that round-off never culls a true hit.
    #[inline]
    pub fn intersect_p(&self, ray: &Ray, inv_d: Vec3) -> Option<(f32, f32)> {
        let t_lo = (self.min - ray.o) * inv_d;
        let t_hi = (self.max - ray.o) * inv_d;
        let t_near = t_lo.min(t_hi);
        let t_far = t_lo.max(t_hi) * (1.0 + 2.0 * super::float::gamma(3));
        let t0 = t_near.max_element().max(0.0);
        let t1 = t_far.min_element().min(ray.t_max);
        if t0 <= t1 {
            Some((t0, t1))
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bounding sphere holds the box's corners, also where the box is too wide for its
    /// diagonal's square in single precision.
    #[test]
    fn bounding_sphere_holds_the_corners() {
        for (lo, hi) in [(Vec3::new(-1.0, 2.0, 0.5), Vec3::new(3.0, 2.5, 4.0)), (Vec3::ZERO, Vec3::new(1e30, 1.0, -3e29))] {
            let b = Bounds3::new(lo, hi);
            let (c, r) = b.bounding_sphere();
            assert!(r.is_finite(), "{r}");
            for k in 0..8 {
                let d = b.corner(k) - c;
                let m = d.abs().max_element().max(1.0);
                assert!((d / m).length() <= r / m, "corner {k}: {} > {r}", m * (d / m).length());
            }
        }
    }

    #[test]
    fn union_and_empty() {
        let e = Bounds3::EMPTY;
        assert!(e.is_empty());
        assert_eq!(e.surface_area(), 0.0);
        let b = e.union_point(Vec3::ONE).union_point(-Vec3::ONE);
        assert_eq!(b, Bounds3::new(-Vec3::ONE, Vec3::ONE));
        assert_eq!(b.union(&e), b);
        assert_eq!(b.surface_area(), 24.0);
        assert!(b.contains(Vec3::ZERO) && !b.contains(Vec3::splat(1.5)));
        assert!(b.intersection(&Bounds3::new(Vec3::splat(2.0), Vec3::splat(3.0))).is_empty());
        assert_eq!(Bounds3::new(Vec3::ZERO, Vec3::new(1.0, 3.0, 2.0)).max_extent(), 1);
        assert_eq!(b.offset(Vec3::ZERO), Vec3::splat(0.5));
        let (c, r) = b.bounding_sphere();
        assert_eq!(c, Vec3::ZERO);
        assert!((r - 3f32.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn slab_test_hits_and_misses() {
        let b = Bounds3::new(-Vec3::ONE, Vec3::ONE);
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        let (t0, t1) = b.intersect_p(&r, r.d.recip()).unwrap();
        assert!((t0 - 4.0).abs() < 1e-5 && (t1 - 6.0).abs() < 1e-4);
        let miss = Ray::new(Vec3::new(2.0, 0.0, -5.0), Vec3::Z);
        assert!(b.intersect_p(&miss, miss.d.recip()).is_none());
        let short = Ray::bounded(Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 3.0);
        assert!(b.intersect_p(&short, short.d.recip()).is_none());
        // Axis-parallel ray along a face plane still counts as a hit (inclusive slabs).
        let inside = Ray::new(Vec3::ZERO, Vec3::X);
        let (t0, _) = b.intersect_p(&inside, inside.d.recip()).unwrap();
        assert_eq!(t0, 0.0);
    }
}
