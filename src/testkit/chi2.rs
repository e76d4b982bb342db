//! Pearson's χ² goodness-of-fit and homogeneity tests on histograms.

use super::domain::Domain;
use super::quadrature::{gauss_legendre_5, gauss_legendre_5x5};
use super::stats::chi2_sf;
use crate::sampling::rng::Pcg32;
use std::fmt;

/// Generous count of the statistical tests in one `cargo test` run, for the Šidák correction.
/// Raise it if the suite ever grows past it.
pub const SUITE_TESTS: u32 = 250;

/// Settings shared by the χ² tests.
#[derive(Clone, Debug)]
pub struct Chi2Config {
    /// Family-wise significance level of the whole suite (probability that a correct suite
    /// fails somewhere by chance).
    pub significance: f64,
    /// Number of tests sharing that level (Šidák correction).
    pub tests_in_run: u32,
    /// Cells whose expected count is below this are pooled into one cell.
    pub min_expected: f64,
    /// Seed of the generator that feeds the sampler under test.
    pub seed: u64,
}

impl Default for Chi2Config {
    fn default() -> Self {
        Chi2Config { significance: 0.01, tests_in_run: SUITE_TESTS, min_expected: 5.0, seed: 0x5eed_2026 }
    }
}

impl Chi2Config {
    /// Same settings with another seed.
    pub fn with_seed(&self, seed: u64) -> Chi2Config {
        Chi2Config { seed, ..self.clone() }
    }

    /// The per-test level after the Šidák correction: `1 - (1 - α)^(1/m)`.
    pub fn per_test_alpha(&self) -> f64 {
        1.0 - (1.0 - self.significance).powf(1.0 / self.tests_in_run.max(1) as f64)
    }
}

/// Result of a χ² test.
#[derive(Clone, Debug)]
pub struct Chi2Outcome {
    /// Pearson's statistic.
    pub statistic: f64,
    /// Degrees of freedom (cells after pooling, minus one).
    pub dof: usize,
    /// Probability of a statistic at least this large under the null hypothesis.
    pub p_value: f64,
    /// Per-test significance level (after the Šidák correction) that `p_value` must reach.
    pub alpha: f64,
    /// Number of low-expectation cells pooled.
    pub pooled_cells: usize,
    /// A failure found before any statistics (a sample off the domain, a pdf that integrates to
    /// more than one, samples where the pdf is zero).
    pub failure: Option<String>,
}

impl Chi2Outcome {
    /// Whether the null hypothesis (samples follow the pdf) survives.
    pub fn passed(&self) -> bool {
        self.failure.is_none() && self.p_value >= self.alpha
    }

    fn failed(reason: String, cfg: &Chi2Config) -> Chi2Outcome {
        Chi2Outcome {
            statistic: f64::INFINITY,
            dof: 0,
            p_value: 0.0,
            alpha: cfg.per_test_alpha(),
            pooled_cells: 0,
            failure: Some(reason),
        }
    }
}

impl fmt::Display for Chi2Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(reason) = &self.failure {
            return write!(f, "χ² test failed outright: {reason}");
        }
        write!(
            f,
            "χ² = {:.2} with {} dof, p = {:.3e} (rejected below {:.3e}; {} cells pooled): {}",
            self.statistic,
            self.dof,
            self.p_value,
            self.alpha,
            self.pooled_cells,
            if self.passed() { "accepted" } else { "REJECTED" }
        )
    }
}

/// Pearson's χ² test of observed counts against expected counts (same total). Cells with
/// expected count below `cfg.min_expected` are pooled into one cell (and that pool into the
/// smallest regular cell if it is still too small). Observations in a cell whose expected count
/// is (numerically) zero fail the test outright: the sampler produced what the pdf says is
/// impossible.
pub fn pearson(observed: &[f64], expected: &[f64], cfg: &Chi2Config) -> Chi2Outcome {
    assert_eq!(observed.len(), expected.len());
    let total: f64 = expected.iter().sum();
    for (i, (&o, &e)) in observed.iter().zip(expected).enumerate() {
        if !e.is_finite() || e < 0.0 {
            return Chi2Outcome::failed(
                format!("cell {i}: expected count {e} is not a finite non-negative number"),
                cfg,
            );
        }
        if o > 0.0 && e <= 1e-9 * total.max(1.0) {
            return Chi2Outcome::failed(format!("cell {i}: {o} samples where the pdf integrates to {e}"), cfg);
        }
    }
    let mut cells: Vec<(f64, f64)> = Vec::with_capacity(observed.len());
    let (mut pool_o, mut pool_e, mut pooled) = (0.0, 0.0, 0usize);
    for (&o, &e) in observed.iter().zip(expected) {
        if e < cfg.min_expected {
            pool_o += o;
            pool_e += e;
            pooled += 1;
        } else {
            cells.push((o, e));
        }
    }
    if pooled > 0 && pool_e > 0.0 {
        if pool_e < cfg.min_expected && !cells.is_empty() {
            let smallest = (0..cells.len()).min_by(|&a, &b| cells[a].1.total_cmp(&cells[b].1)).unwrap();
            cells[smallest].0 += pool_o;
            cells[smallest].1 += pool_e;
        } else {
            cells.push((pool_o, pool_e));
        }
    } else if pool_o > 0.0 {
        return Chi2Outcome::failed(format!("{pool_o} samples in cells of zero expectation"), cfg);
    }
    if cells.len() < 2 {
        return Chi2Outcome::failed("fewer than two usable cells: too few samples for this histogram".into(), cfg);
    }
    let statistic: f64 = cells.iter().map(|&(o, e)| (o - e) * (o - e) / e).sum();
    let dof = cells.len() - 1;
    Chi2Outcome {
        statistic,
        dof,
        p_value: chi2_sf(statistic, dof as f64),
        alpha: cfg.per_test_alpha(),
        pooled_cells: pooled,
        failure: None,
    }
}

fn cell_index(x: f64, lo: f64, hi: f64, n: usize) -> usize {
    (((x - lo) / (hi - lo) * n as f64) as usize).min(n - 1)
}

/// Integral of `pdf` (in the domain's measure) over the whole domain, by 5×5 Gauss–Legendre
/// quadrature on a `res[0] × res[1]` grid of parameter cells.
pub fn integrate_pdf_2d<D: Domain>(domain: &D, res: [usize; 2], pdf: impl Fn(&D::Point) -> f64) -> f64 {
    cell_masses_2d(domain, res, &pdf).iter().sum()
}

fn cell_masses_2d<D: Domain>(domain: &D, res: [usize; 2], pdf: &impl Fn(&D::Point) -> f64) -> Vec<f64> {
    let [lo, hi] = domain.bounds();
    let (hs, ht) = ((hi[0] - lo[0]) / res[0] as f64, (hi[1] - lo[1]) / res[1] as f64);
    let mut masses = Vec::with_capacity(res[0] * res[1]);
    for j in 0..res[1] {
        for i in 0..res[0] {
            let (s0, t0) = (lo[0] + i as f64 * hs, lo[1] + j as f64 * ht);
            let f = |s: f64, t: f64| {
                let (x, jac) = domain.param_to_point([s, t]);
                pdf(&x) * jac
            };
            masses.push(integrate_cell(&f, s0, s0 + hs, t0, t0 + ht, 0));
        }
    }
    masses
}

/// Integral of `f` over a cell by 5×5 Gauss–Legendre quadrature, refined adaptively where a
/// discontinuity (a light's silhouette, a cone's edge) crosses the cell: when the rule disagrees
/// with the sum over the four sub-cells, or when the cell's corners disagree on whether `f` is
/// zero (the edge of the support passes through the cell, perhaps as a sliver no quadrature
/// node sees), the sub-cells are integrated recursively.
fn integrate_cell(f: &impl Fn(f64, f64) -> f64, x0: f64, x1: f64, y0: f64, y1: f64, depth: u32) -> f64 {
    let coarse = gauss_legendre_5x5(x0, x1, y0, y1, f);
    let (xm, ym) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let quads = [(x0, xm, y0, ym), (xm, x1, y0, ym), (x0, xm, ym, y1), (xm, x1, ym, y1)];
    let fine: f64 = quads.iter().map(|&(a, b, c, d)| gauss_legendre_5x5(a, b, c, d, f)).sum();
    let zero_corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)].iter().filter(|&&(x, y)| f(x, y) == 0.0).count();
    let edge_inside = (zero_corners > 0 && zero_corners < 4) || (zero_corners == 4) != (fine == 0.0);
    if depth >= 6 || (!edge_inside && (fine - coarse).abs() <= 1e-5 * fine.abs() + 1e-12) {
        return fine;
    }
    quads.iter().map(|&(a, b, c, d)| integrate_cell(f, a, b, c, d, depth + 1)).sum()
}

/// χ² goodness-of-fit of `n` draws of `sample` against `pdf` on a 2D `domain`, histogrammed on
/// a `res[0] × res[1]` grid of parameter cells (odd resolutions avoid aligning cell edges with
/// symmetry planes). `sample` receives the test's generator and may return `None` (no sample);
/// the probability of that is compared with `1 - ∫ pdf` through an extra cell.
pub fn chi2_2d<D: Domain>(
    domain: &D,
    res: [usize; 2],
    n: usize,
    mut sample: impl FnMut(&mut Pcg32) -> Option<D::Point>,
    pdf: impl Fn(&D::Point) -> f64,
    cfg: &Chi2Config,
) -> Chi2Outcome
where
    D::Point: fmt::Debug,
{
    match histogram_2d(domain, res, n, &mut sample, Pcg32::new(cfg.seed, 0x000c_4159)) {
        Ok(observed) => finish(observed, cell_masses_2d(domain, res, &pdf), n, cfg),
        Err(e) => Chi2Outcome::failed(e, cfg),
    }
}

/// Counts of `n` draws per parameter cell (row-major), plus a last cell for `None`; an error
/// names the first sample that is not on the domain.
fn histogram_2d<D: Domain>(
    domain: &D,
    res: [usize; 2],
    n: usize,
    sample: &mut impl FnMut(&mut Pcg32) -> Option<D::Point>,
    mut rng: Pcg32,
) -> Result<Vec<f64>, String>
where
    D::Point: fmt::Debug,
{
    let [lo, hi] = domain.bounds();
    let mut counts = vec![0.0; res[0] * res[1] + 1];
    for _ in 0..n {
        match sample(&mut rng) {
            None => *counts.last_mut().unwrap() += 1.0,
            Some(x) => {
                let p = domain.to_param(&x).ok_or_else(|| format!("sample {x:?} is not on the {}", domain.name()))?;
                let i = cell_index(p[0], lo[0], hi[0], res[0]);
                let j = cell_index(p[1], lo[1], hi[1], res[1]);
                counts[j * res[0] + i] += 1.0;
            }
        }
    }
    Ok(counts)
}

/// Turns cell probabilities into expected counts, adds the "no sample / outside" cell and runs
/// Pearson's test.
fn finish(observed: Vec<f64>, masses: Vec<f64>, n: usize, cfg: &Chi2Config) -> Chi2Outcome {
    let total: f64 = masses.iter().sum();
    if !total.is_finite() || total > 1.0 + 1e-3 {
        return Chi2Outcome::failed(format!("the pdf integrates to {total} > 1 over the domain"), cfg);
    }
    let mut expected: Vec<f64> = masses.iter().map(|m| m * n as f64).collect();
    expected.push((1.0 - total).max(0.0) * n as f64);
    pearson(&observed, &expected, cfg)
}

/// χ² goodness-of-fit of `n` draws of a 1D `sample` against `pdf` on `bins` equal cells of
/// `[lo, hi]`. Samples outside the interval (or `None`) fall into an overflow cell whose
/// expected probability is `1 - ∫_lo^hi pdf`, so unbounded supports (e.g. the exponential) are
/// tested too.
pub fn chi2_1d(
    (lo, hi): (f64, f64),
    bins: usize,
    n: usize,
    mut sample: impl FnMut(&mut Pcg32) -> Option<f64>,
    pdf: impl Fn(f64) -> f64,
    cfg: &Chi2Config,
) -> Chi2Outcome {
    let mut observed = vec![0.0; bins + 1];
    let mut rng = Pcg32::new(cfg.seed, 0x1d);
    for _ in 0..n {
        match sample(&mut rng) {
            Some(x) if x.is_nan() => return Chi2Outcome::failed("sample is NaN".into(), cfg),
            Some(x) if x >= lo && x <= hi => observed[cell_index(x, lo, hi, bins)] += 1.0,
            _ => observed[bins] += 1.0,
        }
    }
    finish(observed, masses_1d((lo, hi), bins, &pdf), n, cfg)
}

fn masses_1d((lo, hi): (f64, f64), bins: usize, pdf: &impl Fn(f64) -> f64) -> Vec<f64> {
    let h = (hi - lo) / bins as f64;
    (0..bins).map(|i| gauss_legendre_5(lo + i as f64 * h, lo + (i + 1) as f64 * h, pdf)).collect()
}

/// Integral of a 1D `pdf` over `[lo, hi]` by Gauss–Legendre quadrature on `bins` cells.
pub fn integrate_pdf_1d(bounds: (f64, f64), bins: usize, pdf: impl Fn(f64) -> f64) -> f64 {
    masses_1d(bounds, bins, &pdf).iter().sum()
}

/// χ² goodness-of-fit of a discrete sampler over outcomes `0..outcomes` against `pmf`.
pub fn chi2_discrete(
    outcomes: usize,
    n: usize,
    mut sample: impl FnMut(&mut Pcg32) -> Option<usize>,
    pmf: impl Fn(usize) -> f64,
    cfg: &Chi2Config,
) -> Chi2Outcome {
    let mut observed = vec![0.0; outcomes + 1];
    let mut rng = Pcg32::new(cfg.seed, 0xd15c);
    for _ in 0..n {
        match sample(&mut rng) {
            Some(i) if i < outcomes => observed[i] += 1.0,
            Some(i) => return Chi2Outcome::failed(format!("outcome {i} out of range 0..{outcomes}"), cfg),
            None => observed[outcomes] += 1.0,
        }
    }
    finish(observed, (0..outcomes).map(pmf).collect(), n, cfg)
}

/// Two-sample χ² test of homogeneity: whether `sample_a` and `sample_b` (n draws each) follow
/// the same distribution on `domain`. Statistic `Σ (a_k - b_k)² / (a_k + b_k)` over cells with
/// `a_k + b_k ≥ 2 · min_expected` (the rest pooled), `cells - 1` degrees of freedom.
pub fn chi2_two_sample_2d<D: Domain>(
    domain: &D,
    res: [usize; 2],
    n: usize,
    mut sample_a: impl FnMut(&mut Pcg32) -> Option<D::Point>,
    mut sample_b: impl FnMut(&mut Pcg32) -> Option<D::Point>,
    cfg: &Chi2Config,
) -> Chi2Outcome
where
    D::Point: fmt::Debug,
{
    let a = match histogram_2d(domain, res, n, &mut sample_a, Pcg32::new(cfg.seed, 0xa)) {
        Ok(h) => h,
        Err(e) => return Chi2Outcome::failed(e, cfg),
    };
    let b = match histogram_2d(domain, res, n, &mut sample_b, Pcg32::new(cfg.seed, 0xb)) {
        Ok(h) => h,
        Err(e) => return Chi2Outcome::failed(e, cfg),
    };
    let mut cells = Vec::new();
    let (mut pa, mut pb, mut pooled) = (0.0, 0.0, 0);
    for (&x, &y) in a.iter().zip(&b) {
        if x + y < 2.0 * cfg.min_expected {
            pa += x;
            pb += y;
            pooled += 1;
        } else {
            cells.push((x, y));
        }
    }
    if pa + pb > 0.0 {
        cells.push((pa, pb));
    }
    if cells.len() < 2 {
        return Chi2Outcome::failed("fewer than two usable cells".into(), cfg);
    }
    let statistic: f64 = cells.iter().map(|&(x, y)| (x - y) * (x - y) / (x + y)).sum();
    let dof = cells.len() - 1;
    Chi2Outcome {
        statistic,
        dof,
        p_value: chi2_sf(statistic, dof as f64),
        alpha: cfg.per_test_alpha(),
        pooled_cells: pooled,
        failure: None,
    }
}

#[cfg(test)]
mod tests {
    use super::super::domain::{Rect, HEMISPHERE};
    use super::*;
    use glam::{Vec2, Vec3};

    #[test]
    fn sidak_level_is_below_family_level() {
        let c = Chi2Config::default();
        let a = c.per_test_alpha();
        assert!(a < 0.01 / 200.0 && a > 0.0);
        assert!((1.0 - (1.0 - a).powi(c.tests_in_run as i32) - 0.01).abs() < 1e-9);
    }

    #[test]
    fn pearson_accepts_exact_and_rejects_skewed_counts() {
        let cfg = Chi2Config::default();
        let e = vec![1000.0; 10];
        assert!(pearson(&e, &e, &cfg).passed());
        let mut o = e.clone();
        o[0] += 300.0;
        o[1] -= 300.0;
        assert!(!pearson(&o, &e, &cfg).passed());
        // Observations where nothing is expected fail outright.
        let out = pearson(&[5.0, 995.0], &[0.0, 1000.0], &cfg);
        assert!(out.failure.is_some());
    }

    #[test]
    fn pooling_merges_low_cells() {
        let cfg = Chi2Config::default();
        // The pool (expected 5.5) becomes a cell of its own...
        let e = [1.0, 2.0, 2.5, 100.0, 100.0];
        let o = [2.0, 1.0, 2.0, 101.0, 99.5];
        let out = pearson(&o, &e, &cfg);
        assert_eq!(out.pooled_cells, 3);
        assert_eq!(out.dof, 2);
        assert!(out.passed());
        // ... unless it is still too small (4.5): then it joins the smallest regular cell.
        let e = [1.0, 2.0, 1.5, 100.0, 100.0];
        let out = pearson(&o, &e, &cfg);
        assert_eq!(out.pooled_cells, 3);
        assert_eq!(out.dof, 1);
    }

    #[test]
    fn negative_control_cosine_samples_against_uniform_pdf() {
        // The harness must reject a sampler whose pdf is wrong: cosine-weighted directions tested
        // against the uniform-hemisphere pdf.
        let cfg = Chi2Config::default();
        let out = chi2_2d(
            &HEMISPHERE,
            [11, 21],
            200_000,
            |r| Some(crate::sampling::sample_cosine_hemisphere_malley(Vec2::new(r.next_f32(), r.next_f32())).value),
            |_w: &Vec3| 1.0 / (2.0 * std::f64::consts::PI),
            &cfg,
        );
        assert!(!out.passed(), "harness accepted a wrong pdf: {out}");
        // ... and accept it against the right one.
        let ok = chi2_2d(
            &HEMISPHERE,
            [11, 21],
            200_000,
            |r| Some(crate::sampling::sample_cosine_hemisphere_malley(Vec2::new(r.next_f32(), r.next_f32())).value),
            |w: &Vec3| w.z.max(0.0) as f64 / std::f64::consts::PI,
            &cfg,
        );
        assert!(ok.passed(), "{ok}");
    }

    #[test]
    fn negative_control_subtly_wrong_triangle_warp() {
        // The naive warp u = ξ₁, v = ξ₂ (1 - ξ₁) covers the triangle but not uniformly; the
        // harness must notice with the default sample count.
        let tri = super::super::domain::Triangle { p: [Vec3::ZERO, Vec3::X, Vec3::Y] };
        let out = chi2_2d(
            &tri,
            [15, 15],
            500_000,
            |r| {
                let (a, b) = (r.next_f32(), r.next_f32());
                Some(Vec3::new(a, b * (1.0 - a), 0.0))
            },
            |_| 2.0,
            &Chi2Config::default(),
        );
        assert!(!out.passed(), "{out}");
    }

    #[test]
    fn negative_control_unnormalized_pdf_and_off_domain_samples() {
        let cfg = Chi2Config::default();
        let out = chi2_2d(&Rect::UNIT, [9, 9], 10_000, |r| Some(Vec2::new(r.next_f32(), r.next_f32())), |_| 1.1, &cfg);
        assert!(out.failure.is_some(), "{out}");
        let out = chi2_2d(&Rect::UNIT, [9, 9], 10_000, |r| Some(Vec2::new(r.next_f32(), r.next_f32())), |_| 0.9, &cfg);
        assert!(!out.passed(), "a pdf integrating to 0.9 must be rejected: {out}");
        let out = chi2_2d(&Rect::UNIT, [9, 9], 10_000, |r| Some(Vec2::new(r.next_f32() + 0.5, 0.5)), |_| 1.0, &cfg);
        assert!(out.failure.is_some());
        let out = chi2_1d((0.0, 1.0), 10, 10_000, |r| Some(r.next_f64()), |x| 2.0 * x, &cfg);
        assert!(!out.passed());
        let out = chi2_discrete(3, 30_000, |r| Some(r.next_bounded(3) as usize), |_| 0.25, &cfg);
        assert!(!out.passed(), "missing mass must be found: {out}");
    }

    #[test]
    fn two_sample_test_separates_distributions() {
        let cfg = Chi2Config::default();
        let uniform = |r: &mut Pcg32| Some(Vec2::new(r.next_f32(), r.next_f32()));
        let same = chi2_two_sample_2d(&Rect::UNIT, [10, 10], 100_000, uniform, uniform, &cfg);
        assert!(same.passed(), "{same}");
        let skew = |r: &mut Pcg32| Some(Vec2::new(r.next_f32().sqrt(), r.next_f32()));
        let diff = chi2_two_sample_2d(&Rect::UNIT, [10, 10], 100_000, uniform, skew, &cfg);
        assert!(!diff.passed(), "{diff}");
    }
}
