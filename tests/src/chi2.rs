//! χ² goodness-of-fit tests of samplers against their densities.
//!
//! The domain (the sphere of directions, or the unit square) is cut into bins. Samples
//! are histogrammed; the expected count of each bin is N·∫_bin pdf, integrated by nested
//! adaptive Simpson quadrature in f64. Bins expecting fewer than five samples are pooled
//! (as in Mitsuba's `ChiSquareTest`), and samplers that sometimes produce nothing (a
//! BSDF absorbing part of the energy) are tested too: the fraction of `None` results is
//! its own bin, whose expected mass is 1 − ∫pdf. The statistic is compared with the χ²
//! distribution of the pooled bins' degrees of freedom; the p-value comes from the
//! regularised incomplete gamma function ([`crate::stats::chi2_survival`]).
//!
//! A sample landing in a bin whose integrated pdf is zero fails immediately: that is a
//! sampler producing directions its pdf says are impossible, the classic
//! inconsistency χ² alone can miss.

use ember_core::math::Frame;
use ember_core::rng::{SampleStream, Stream};
use glam::{DVec2, Vec2, Vec3};

use crate::stats::chi2_survival;

/// Per-test significance that keeps the family-wise false-alarm rate at `alpha_family`
/// over `tests` independent tests (Šidák): 1 − (1 − α)^(1/m).
pub fn sidak(alpha_family: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha_family).powf(1.0 / tests.max(1) as f64)
}

/// Pearson's χ² over discrete outcomes: `counts` holds (observed, expected) per outcome,
/// outcomes expecting fewer than 5 pooled as for the continuous tests. Returns (statistic,
/// degrees of freedom, p-value).
pub fn chi2_counts(counts: &[(f64, f64)]) -> (f64, usize, f64) {
    let bins = counts.iter().enumerate().map(|(b, &(o, e))| (b, o, e)).collect();
    let (statistic, dof, _) = pooled_statistic(bins);
    (statistic, dof, if dof == 0 { 1.0 } else { chi2_survival(statistic, dof as f64) })
}

/// How directions are binned: in (θ', φ') around `axis`, with θ' = π·s^concentration for
/// s uniform over the θ bins. Concentration 1 is uniform in θ'; larger values give finer
/// bins near the axis (point it at a narrow lobe).
#[derive(Clone, Copy, Debug)]
pub struct SphereBinning {
    pub axis: Vec3,
    pub concentration: f64,
}

impl SphereBinning {
    /// Uniform in θ around +z.
    pub fn uniform() -> Self {
        Self { axis: Vec3::Z, concentration: 1.0 }
    }
    /// Concentrated around `axis`.
    pub fn around(axis: Vec3, concentration: f64) -> Self {
        Self { axis: axis.normalize(), concentration: concentration.max(1.0) }
    }
}

/// Sample count, bin resolution and seed of one test.
#[derive(Clone, Copy, Debug)]
pub struct Chi2Config {
    pub samples: usize,
    pub theta_bins: usize,
    pub phi_bins: usize,
    pub seed: u64,
}

impl Default for Chi2Config {
    fn default() -> Self {
        Self { samples: 1_000_000, theta_bins: 64, phi_bins: 128, seed: 0x5eed }
    }
}

/// Outcome of one χ² test.
#[derive(Clone, Debug)]
pub struct Chi2Result {
    pub name: String,
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Fraction of sampler calls that produced a sample.
    pub sampled_fraction: f64,
    /// Integral of the pdf over the whole domain (should equal `sampled_fraction`).
    pub pdf_integral: f64,
    /// Set when a sample fell where the integrated pdf is zero (or outside the domain).
    pub impossible_sample: Option<String>,
    /// The bins contributing most to the statistic: (bin, observed, expected).
    pub worst_bins: Vec<(usize, f64, f64)>,
}

impl Chi2Result {
    /// Panic with a report if the test rejects at level `alpha`.
    pub fn assert_passes(&self, alpha: f64) {
        if let Some(why) = &self.impossible_sample {
            panic!("χ² {}: impossible sample: {why}", self.name);
        }
        if !(self.p_value >= alpha) {
            panic!(
                "χ² {} rejected: statistic {:.1} on {} dof, p = {:.3e} < α = {:.3e}; sampled {:.5}, ∫pdf {:.5}; worst bins (bin, observed, expected): {:?}",
                self.name, self.statistic, self.dof, self.p_value, alpha, self.sampled_fraction, self.pdf_integral, self.worst_bins
            );
        }
    }
}

/// χ² test of a direction sampler against its density per steradian.
pub fn chi2_sphere(
    name: &str,
    cfg: &Chi2Config,
    binning: &SphereBinning,
    mut sample: impl FnMut(&mut SampleStream) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f64 + Sync,
) -> Chi2Result {
    let frame = Frame::from_normal(binning.axis);
    let c = binning.concentration;
    let (nt, np) = (cfg.theta_bins, cfg.phi_bins);
    // Cell coordinates (s, φ/2π) ∈ [0,1]²  →  direction, and the Jacobian dω/(ds dv).
    let to_dir = |s: f64, v: f64| -> (Vec3, f64) {
        let theta = std::f64::consts::PI * s.powf(c);
        let dtheta_ds = std::f64::consts::PI * c * s.powf(c - 1.0);
        let phi = 2.0 * std::f64::consts::PI * v;
        let (st, ct) = theta.sin_cos();
        let local = Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, ct as f32);
        (frame.to_world(local), st * dtheta_ds * 2.0 * std::f64::consts::PI)
    };
    let bin_of = |w: Vec3| -> Option<usize> {
        if !w.is_finite() || (w.length() - 1.0).abs() > 1e-3 {
            return None;
        }
        let l = frame.to_local(w.normalize());
        // atan2 of (sin, cos) keeps θ accurate near the axis, where acos(z) of an f32 z
        // loses most of its digits (narrow lobes live exactly there).
        let theta = (l.x as f64).hypot(l.y as f64).atan2(l.z as f64);
        let s = (theta / std::f64::consts::PI).powf(1.0 / c);
        let mut v = (l.y as f64).atan2(l.x as f64) / (2.0 * std::f64::consts::PI);
        if v < 0.0 {
            v += 1.0;
        }
        let i = ((s * nt as f64) as usize).min(nt - 1);
        let j = ((v * np as f64) as usize).min(np - 1);
        Some(i * np + j)
    };
    let density = |s: f64, v: f64| {
        let (w, jac) = to_dir(s, v);
        let p = pdf(w);
        if p.is_finite() && p > 0.0 { p * jac } else { 0.0 }
    };
    run(name, cfg, nt, np, |rng| sample(rng).map(|w| bin_of(w).ok_or(w.to_string())), density)
}

/// χ² test of a sampler of the unit square against its density on [0,1]².
pub fn chi2_square(name: &str, cfg: &Chi2Config, mut sample: impl FnMut(&mut SampleStream) -> Option<Vec2>, pdf: impl Fn(Vec2) -> f64 + Sync) -> Chi2Result {
    let (nt, np) = (cfg.theta_bins, cfg.phi_bins);
    let bin_of = |p: Vec2| -> Option<usize> {
        if !(p.x >= 0.0 && p.x <= 1.0 && p.y >= 0.0 && p.y <= 1.0) {
            return None;
        }
        let i = ((p.x as f64 * nt as f64) as usize).min(nt - 1);
        let j = ((p.y as f64 * np as f64) as usize).min(np - 1);
        Some(i * np + j)
    };
    let density = |x: f64, y: f64| {
        let p = pdf(Vec2::new(x as f32, y as f32));
        if p.is_finite() && p > 0.0 { p } else { 0.0 }
    };
    run(name, cfg, nt, np, |rng| sample(rng).map(|p| bin_of(p).ok_or(p.to_string())), density)
}

/// Shared driver: histogram, integrate, pool, test.
fn run(
    name: &str,
    cfg: &Chi2Config,
    nx: usize,
    ny: usize,
    mut sample_bin: impl FnMut(&mut SampleStream) -> Option<Result<usize, String>>,
    density: impl Fn(f64, f64) -> f64 + Sync,
) -> Chi2Result {
    let cells = nx * ny;
    let mut observed = vec![0.0f64; cells];
    let mut produced = 0usize;
    let mut outside: Option<String> = None;
    for k in 0..cfg.samples {
        let mut rng = SampleStream::for_sample(cfg.seed, Stream::Aux, k as u32, (k >> 32) as u32, 0);
        match sample_bin(&mut rng) {
            Some(Ok(b)) => {
                observed[b] += 1.0;
                produced += 1;
            }
            Some(Err(w)) => {
                outside.get_or_insert(format!("sample {w} is not in the domain (non-finite or not unit)"));
                produced += 1;
            }
            None => {}
        }
    }

    // Integrate the density over every cell, in parallel over rows.
    let mut integral = vec![0.0f64; cells];
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).min(nx);
    std::thread::scope(|scope| {
        for (t, chunk) in integral.chunks_mut(ny * nx.div_ceil(threads)).enumerate() {
            let density = &density;
            scope.spawn(move || {
                let row0 = t * nx.div_ceil(threads);
                for (k, out) in chunk.iter_mut().enumerate() {
                    let (i, j) = (row0 + k / ny, k % ny);
                    let lo = DVec2::new(i as f64 / nx as f64, j as f64 / ny as f64);
                    let hi = DVec2::new((i + 1) as f64 / nx as f64, (j + 1) as f64 / ny as f64);
                    *out = integrate_2d(density, lo, hi);
                }
            });
        }
    });

    let n = cfg.samples as f64;
    let pdf_integral: f64 = integral.iter().sum();
    let sampled_fraction = produced as f64 / n;
    let mut impossible = outside;
    let mut bins: Vec<(usize, f64, f64)> = Vec::with_capacity(cells + 1);
    for b in 0..cells {
        let expected = integral[b] * n;
        if observed[b] > 0.0 && expected < 1e-9 * n.max(1.0) && integral[b] <= 1e-12 {
            impossible.get_or_insert(format!("{} samples in bin {b} whose integrated pdf is {:e}", observed[b], integral[b]));
        }
        bins.push((b, observed[b], expected));
    }
    // The "no sample" outcome is a bin of its own.
    bins.push((cells, n - produced as f64, (n * (1.0 - pdf_integral)).max(0.0)));

    let (statistic, dof, worst) = pooled_statistic(bins);
    let p_value = if dof == 0 { 1.0 } else { chi2_survival(statistic, dof as f64) };
    Chi2Result { name: name.to_string(), statistic, dof, p_value, sampled_fraction, pdf_integral, impossible_sample: impossible, worst_bins: worst }
}

/// Pool every bin expecting fewer than 5 samples into one, then sum (O−E)²/E.
fn pooled_statistic(mut bins: Vec<(usize, f64, f64)>) -> (f64, usize, Vec<(usize, f64, f64)>) {
    const MIN_EXPECTED: f64 = 5.0;
    bins.sort_by(|a, b| a.2.total_cmp(&b.2));
    let (mut pool_obs, mut pool_exp) = (0.0, 0.0);
    let mut terms: Vec<(usize, f64, f64, f64)> = Vec::new();
    for &(b, o, e) in &bins {
        if e < MIN_EXPECTED || pool_exp > 0.0 && pool_exp < MIN_EXPECTED {
            pool_obs += o;
            pool_exp += e;
        } else {
            terms.push((b, o, e, (o - e) * (o - e) / e));
        }
    }
    if pool_exp > 0.0 {
        if pool_exp >= MIN_EXPECTED || terms.is_empty() {
            terms.push((usize::MAX, pool_obs, pool_exp, (pool_obs - pool_exp).powi(2) / pool_exp));
        } else if let Some(last) = terms.first_mut() {
            // Too little pooled mass for a bin of its own: merge it into the smallest bin.
            last.1 += pool_obs;
            last.2 += pool_exp;
            last.3 = (last.1 - last.2).powi(2) / last.2;
        }
    } else if pool_obs > 0.0 {
        // Samples where nothing was expected at all.
        terms.push((usize::MAX, pool_obs, 1e-12, f64::INFINITY));
    }
    let statistic: f64 = terms.iter().map(|t| t.3).sum();
    let dof = terms.len().saturating_sub(1);
    terms.sort_by(|a, b| b.3.total_cmp(&a.3));
    let worst = terms.iter().take(8).map(|t| (t.0, t.1, t.2)).collect();
    (statistic, dof, worst)
}

/// ∫∫ over the rectangle [lo, hi] by nested adaptive Simpson, after splitting it into
/// 3×3 pieces so narrow peaks inside a cell are not stepped over.
fn integrate_2d(f: &(impl Fn(f64, f64) -> f64 + Sync), lo: DVec2, hi: DVec2) -> f64 {
    const SPLIT: usize = 3;
    let d = (hi - lo) / SPLIT as f64;
    let mut total = 0.0;
    for a in 0..SPLIT {
        let (x0, x1) = (lo.x + a as f64 * d.x, lo.x + (a + 1) as f64 * d.x);
        for b in 0..SPLIT {
            let (y0, y1) = (lo.y + b as f64 * d.y, lo.y + (b + 1) as f64 * d.y);
            let inner = |x: f64| simpson_adaptive(&|y| f(x, y), y0, y1, 1e-7, 8);
            total += simpson_adaptive(&inner, x0, x1, 1e-7, 8);
        }
    }
    total
}

fn simpson_adaptive(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64, depth: u32) -> f64 {
    let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
    let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    simpson_step(f, a, b, fa, fm, fb, whole, tol, depth)
}

fn simpson_step(f: &dyn Fn(f64) -> f64, a: f64, b: f64, fa: f64, fm: f64, fb: f64, whole: f64, tol: f64, depth: u32) -> f64 {
    let m = 0.5 * (a + b);
    let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
    let (flm, frm) = (f(lm), f(rm));
    let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    let delta = left + right - whole;
    if depth == 0 || delta.abs() <= 15.0 * tol {
        return left + right + delta / 15.0;
    }
    simpson_step(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1) + simpson_step(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1)
}
