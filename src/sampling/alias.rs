//! Walker's alias method (Vose's O(n) construction): O(1) sampling of a discrete distribution.
//!
//! Each of the `n` equal-probability bins holds a probability `q_i` of returning `i` and an
//! alias `a_i` returned otherwise. Building it pairs an under-full bin with an over-full one
//! until every bin holds exactly `1/n`. Used for picking triangles by area and lights by power.

use super::Sample;
use crate::math::ONE_MINUS_EPSILON;

#[derive(Clone, Copy, Debug)]
struct Bin {
    /// Probability of keeping this bin's own index.
    q: f32,
    /// Index returned otherwise.
    alias: u32,
    /// Normalized probability of this index.
    pmf: f32,
}

/// An alias table over `0..n`.
#[derive(Clone, Debug)]
pub struct AliasTable {
    bins: Vec<Bin>,
}

impl AliasTable {
    /// Table proportional to `weights`. `None` if empty, if any weight is negative or not
    /// finite, if all are zero, or if there are more than `u32::MAX` weights.
    pub fn new(weights: &[f32]) -> Option<AliasTable> {
        if weights.is_empty()
            || weights.len() > u32::MAX as usize
            || weights.iter().any(|w| !(w.is_finite() && *w >= 0.0))
        {
            return None;
        }
        let total: f64 = weights.iter().map(|&w| w as f64).sum();
        if total <= 0.0 {
            return None;
        }
        let n = weights.len();
        let mut bins: Vec<Bin> =
            weights.iter().map(|&w| Bin { q: 0.0, alias: 0, pmf: (w as f64 / total) as f32 }).collect();
        // Scaled probabilities p_i n, kept in f64 while pairing.
        let mut scaled: Vec<f64> = weights.iter().map(|&w| w as f64 / total * n as f64).collect();
        let (mut under, mut over): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(&u), Some(&o)) = (under.last(), over.last()) {
            under.pop();
            bins[u].q = scaled[u] as f32;
            bins[u].alias = o as u32;
            scaled[o] -= 1.0 - scaled[u];
            if scaled[o] < 1.0 {
                over.pop();
                under.push(o);
            }
        }
        // What remains is 1 up to round-off.
        for i in under.into_iter().chain(over) {
            bins[i].q = 1.0;
            bins[i].alias = i as u32;
        }
        Some(AliasTable { bins })
    }

    /// Number of outcomes.
    pub fn len(&self) -> usize {
        self.bins.len()
    }

    /// Whether the table is empty (never true for a constructed table).
    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// Probability of outcome `i` (0 out of range).
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.bins.get(i).map_or(0.0, |b| b.pmf)
    }

    /// An outcome, its probability (discrete measure), and a remapped uniform in `[0,1)` that can
    /// be reused. Domain `u ∈ [0,1)`.
    #[inline]
    pub fn sample(&self, u: f32) -> (Sample<usize>, f32) {
        let n = self.bins.len();
        let scaled = u * n as f32;
        let i = (scaled as usize).min(n - 1);
        let up = (scaled - i as f32).min(ONE_MINUS_EPSILON);
        let bin = &self.bins[i];
        if up < bin.q {
            (Sample::discrete(i, bin.pmf), (up / bin.q).min(ONE_MINUS_EPSILON))
        } else {
            let a = bin.alias as usize;
            (Sample::discrete(a, self.bins[a].pmf), ((up - bin.q) / (1.0 - bin.q)).clamp(0.0, ONE_MINUS_EPSILON))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_discrete, Chi2Config};

    #[test]
    fn alias_chi2_on_skewed_weights() {
        let w: Vec<f32> =
            (0..37).map(|i| if i % 5 == 3 { 0.0 } else { ((i * 7919) % 31) as f32 + 0.01 * i as f32 }).collect();
        let t = AliasTable::new(&w).unwrap();
        let out = chi2_discrete(
            w.len(),
            1_000_000,
            |r| Some(t.sample(r.next_f32()).0.value),
            |i| t.pmf(i) as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        let total: f32 = w.iter().sum();
        for (i, &wi) in w.iter().enumerate() {
            assert!((t.pmf(i) - wi / total).abs() < 1e-6);
        }
    }

    #[test]
    fn alias_and_cdf_agree_and_zero_weights_never_drawn() {
        let w = [5.0f32, 0.0, 1e-3, 2.0, 0.0, 7.0];
        let t = AliasTable::new(&w).unwrap();
        let d = crate::sampling::DiscreteCdf::new(&w).unwrap();
        let mut r = crate::sampling::Pcg32::new(4, 4);
        for _ in 0..200_000 {
            let (s, u2) = t.sample(r.next_f32());
            assert!(w[s.value] > 0.0);
            assert!((0.0..1.0).contains(&u2));
            assert_eq!(s.pdf, t.pmf(s.value));
        }
        for i in 0..w.len() {
            assert!((t.pmf(i) - d.pmf(i)).abs() < 1e-7);
        }
        assert!(AliasTable::new(&[0.0]).is_none());
        assert_eq!(AliasTable::new(&[3.0]).unwrap().sample(0.7).0.value, 0);
    }

    #[test]
    fn remapped_u_is_uniform() {
        let t = AliasTable::new(&[1.0, 4.0, 2.0]).unwrap();
        let out = crate::testkit::chi2_1d(
            (0.0, 1.0),
            20,
            200_000,
            |r| Some(t.sample(r.next_f32()).1 as f64),
            |_| 1.0,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
    }
}
