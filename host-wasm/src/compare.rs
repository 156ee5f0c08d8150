//! The browser test's verdict (native only): does the page's linear image (PFM) agree
//! with the native CLI's render (EXR) of the same scene, seed and passes?
//!
//! # What is compared, and how strictly
//! The browser runs the same core code (estimators, libm-only math, counter-based RNG)
//! and the same primitive tests (the CLI's watertight triangle and f64 sphere files,
//! compiled into the module) as the CLI; wasm never fuses multiply-adds and neither does
//! the default x86-64 build. So almost every pixel is the same number. What can differ:
//! the f64 summation order of splats (the page sums per-worker splat films; the CLI
//! sums per-chunk lists), a few ulps; and hits tied at a shared triangle edge, which
//! the CLI's CWBVH and the browser's BVH2 may give to different triangles (the hit point
//! moves by an ulp and the path diverges from there): measured, about 2 pixels in 1024
//! at 32² and 2 passes. Hence two checks:
//! 1. all but `max_differing_fraction` (1 %) of the pixels agree to `pixel_tolerance`
//!    (10⁻⁵ relative): this catches any change of seed, pass count, splat scale, band
//!    or worker bookkeeping, which changes nearly every pixel;
//! 2. a z-test per 8 × 8 block and channel of the difference of the two means against
//!    their combined standard error, √2 × the native block mean's (estimated from the
//!    spread of the block's native pixels, which includes the image's own structure, so
//!    the bound is conservative), Šidák-corrected to a family-wise α = 10⁻³: the few
//!    diverged pixels may not move any block beyond its noise.
//!
//! Plus: the browser image has no NaN or infinity and is not blank.

use std::fmt::Write as _;

/// A linear RGB image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

/// Parse a colour PFM ("PF", little-endian when the scale is negative, rows bottom to
/// top), as the page writes it.
pub fn parse_pfm(bytes: &[u8]) -> Result<LinearImage, String> {
    // Header: three whitespace-separated lines of ASCII.
    let mut fields = Vec::new();
    let mut pos = 0;
    while fields.len() < 4 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err("PFM header ends early".into());
        }
        fields.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
    }
    pos += 1; // the single whitespace byte after the scale
    if fields[0] != "PF" {
        return Err(format!("not a colour PFM (magic {:?})", fields[0]));
    }
    let width: usize = fields[1].parse().map_err(|_| "bad PFM width")?;
    let height: usize = fields[2].parse().map_err(|_| "bad PFM height")?;
    let scale: f32 = fields[3].parse().map_err(|_| "bad PFM scale")?;
    let little = scale < 0.0;
    let n = width.checked_mul(height).filter(|&n| n <= 1 << 26).ok_or("PFM too large")?;
    let data = bytes.get(pos..pos + 12 * n).ok_or("PFM data truncated")?;
    let mut pixels = vec![[0.0f32; 3]; n];
    for (k, chunk) in data.chunks_exact(4).enumerate() {
        let b = [chunk[0], chunk[1], chunk[2], chunk[3]];
        let v = if little { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) };
        let (row_from_bottom, x, c) = (k / 3 / width, (k / 3) % width, k % 3);
        pixels[(height - 1 - row_from_bottom) * width + x][c] = v;
    }
    Ok(LinearImage { width, height, pixels })
}

/// The outcome of [`compare`].
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    pub ok: bool,
    pub report: String,
    /// Pixels whose channels differ by more than `pixel_tolerance` (relative).
    pub pixels_differing: usize,
    /// The largest per-block |z| and the Šidák-corrected critical value it is held to.
    pub worst_z: f64,
    pub critical_z: f64,
}

/// Two-sided standard normal tail probability P(|Z| > z).
fn two_sided_p(z: f64) -> f64 {
    libm::erfc(z.abs() / core::f64::consts::SQRT_2)
}

/// The z with P(|Z| > z) = p, by bisection (p in (0, 1)).
fn critical_z(p: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if two_sided_p(mid) > p { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// How two renders are held to agree; see the module documentation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Criteria {
    /// Block size of the z-test.
    pub block: usize,
    /// Family-wise significance level of the block z-tests (Šidák-corrected per test).
    pub alpha: f64,
    /// Relative difference under which two pixels count as the same value.
    pub pixel_tolerance: f64,
    /// Largest fraction of pixels allowed to differ by more (paths that diverged at a
    /// tied hit).
    pub max_differing_fraction: f64,
}

impl Default for Criteria {
    fn default() -> Self {
        Self { block: 8, alpha: 1e-3, pixel_tolerance: 1e-5, max_differing_fraction: 0.01 }
    }
}

/// Compare `browser` with `native`; see the module documentation.
pub fn compare(browser: &LinearImage, native: &LinearImage, criteria: Criteria) -> Verdict {
    let mut report = String::new();
    let mut ok = true;
    let mut fail = |report: &mut String, msg: String| {
        ok = false;
        let _ = writeln!(report, "FAIL: {msg}");
    };
    if (browser.width, browser.height) != (native.width, native.height) || browser.pixels.len() != browser.width * browser.height {
        fail(&mut report, format!("sizes differ: browser {}x{}, native {}x{}", browser.width, browser.height, native.width, native.height));
        return Verdict { ok, report, pixels_differing: usize::MAX, worst_z: f64::INFINITY, critical_z: 0.0 };
    }
    let non_finite = browser.pixels.iter().flatten().filter(|v| !v.is_finite()).count();
    if non_finite > 0 {
        fail(&mut report, format!("{non_finite} non-finite values in the browser image"));
    }
    let mean = |img: &LinearImage| img.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * img.pixels.len()).max(1) as f64;
    let (mb, mn) = (mean(browser), mean(native));
    let lit = browser.pixels.iter().filter(|p| p.iter().any(|&v| v > 0.0)).count();
    let _ = writeln!(report, "means: browser {mb:.6}, native {mn:.6}; {lit} of {} browser pixels non-black", browser.pixels.len());
    if !(mb > 0.0) || lit < browser.pixels.len() / 10 {
        fail(&mut report, "the browser image is blank".into());
    }

    // 1. Pixel by pixel: the same value up to summation order, except diverged paths.
    let same = |a: f32, b: f32| {
        let (a, b) = (a as f64, b as f64);
        (a - b).abs() <= criteria.pixel_tolerance * a.abs().max(b.abs()).max(1e-6 * mn.abs())
    };
    let pixels_differing = browser.pixels.iter().zip(&native.pixels).filter(|(a, b)| !(0..3).all(|c| same(a[c], b[c]))).count();
    let allowed = (criteria.max_differing_fraction * browser.pixels.len() as f64).floor() as usize;
    let _ = writeln!(
        report,
        "{pixels_differing} of {} pixels differ by more than {:.0e} relative (allowed {allowed})",
        browser.pixels.len(),
        criteria.pixel_tolerance
    );
    if pixels_differing > allowed {
        fail(&mut report, format!("{pixels_differing} pixels differ, more than {allowed}"));
    }

    // 2. Per block and channel, a z-test of the difference of means against the
    // combined standard error (see the module documentation).
    let b = criteria.block.max(1);
    let blocks = browser.width.div_ceil(b) * browser.height.div_ceil(b);
    let tests = 3 * blocks;
    let per_test = 1.0 - (1.0 - criteria.alpha).powf(1.0 / tests as f64);
    let z_crit = critical_z(per_test);
    let mut worst_z = 0.0f64;
    let mut worst_at = (0, 0, 0);
    for by in (0..browser.height).step_by(b) {
        for bx in (0..browser.width).step_by(b) {
            for c in 0..3 {
                let mut stats = [(0.0f64, 0.0f64); 2];
                let mut n = 0.0;
                for y in by..(by + b).min(browser.height) {
                    for x in bx..(bx + b).min(browser.width) {
                        let i = y * browser.width + x;
                        for (s, img) in stats.iter_mut().zip([browser, native]) {
                            let v = img.pixels[i][c] as f64;
                            s.0 += v;
                            s.1 += v * v;
                        }
                        n += 1.0;
                    }
                }
                let var_of_mean = |(s, s2): (f64, f64)| ((s2 - s * s / n) / (n - 1.0).max(1.0)).max(0.0) / n;
                // Both renders have the same noise; the native one's estimate is used for
                // both (√2 ×), so outliers in the browser image cannot widen their own bound.
                let se = (2.0 * var_of_mean(stats[1])).sqrt();
                let diff = (stats[0].0 - stats[1].0) / n;
                // Identical blocks have z = 0 whatever their spread; a difference in a
                // flat block (se = 0) is infinitely significant.
                let z = if diff == 0.0 {
                    0.0
                } else if se > 0.0 {
                    diff.abs() / se
                } else {
                    f64::INFINITY
                };
                if !(z <= worst_z) {
                    worst_z = if z.is_nan() { f64::INFINITY } else { z };
                    worst_at = (bx, by, c);
                }
            }
        }
    }
    let _ = writeln!(
        report,
        "worst {b}x{b} block |z| = {worst_z:.3} at ({}, {}) channel {}; Šidák critical |z| = {z_crit:.3} ({tests} tests, family α = {})",
        worst_at.0, worst_at.1, worst_at.2, criteria.alpha
    );
    if !(worst_z <= z_crit) {
        fail(&mut report, format!("block means differ significantly (|z| {worst_z:.3} > {z_crit:.3})"));
    }
    Verdict { ok, report, pixels_differing, worst_z, critical_z: z_crit }
}

/// Compare `browser` with `natives`, renders of the same scene and passes with seeds
/// different from the browser's and from each other (K ≥ 3 of them).
///
/// The per-block test of [`compare`] takes a block mean's noise from the spread of the
/// block's pixels, which holds only while pixels are independent. Kernel estimators
/// (merging, filtering) average neighbouring pixels' photons or nodes, so their pixels
/// are correlated and that bound is too tight (measured: PhF at 48², one block at
/// |z| 5.2 on a correct image). Here the noise of each block mean comes from the K
/// independent native renders instead: with M and s² their mean and sample variance,
/// t = (b − M) / (s √(1 + 1/K)) follows Student's t with K − 1 degrees of freedom when
/// the browser's block mean b is a draw of the same estimator. Šidák-corrected over
/// blocks and channels to the family-wise α of `criteria`. No pixel is compared with a
/// pixel: the seeds differ. (A test of the whole image's mean was tried and dropped: the
/// image mean is dominated by the noisiest region, and on PT with a 30 % bias everywhere
/// it reached |t| 4.9 where the worst block reached 10.2.)
pub fn compare_independent(browser: &LinearImage, natives: &[LinearImage], criteria: Criteria) -> Verdict {
    let mut report = String::new();
    let mut ok = true;
    let mut fail = |report: &mut String, msg: String| {
        ok = false;
        let _ = writeln!(report, "FAIL: {msg}");
    };
    let k = natives.len();
    let bad_size = natives.iter().any(|n| (n.width, n.height) != (browser.width, browser.height) || n.pixels.len() != n.width * n.height);
    if k < 3 || bad_size || browser.pixels.len() != browser.width * browser.height {
        fail(&mut report, format!("need 3 or more native renders of the browser's size ({k} given, sizes differ: {bad_size})"));
        return Verdict { ok, report, pixels_differing: usize::MAX, worst_z: f64::INFINITY, critical_z: 0.0 };
    }
    let non_finite = browser.pixels.iter().flatten().filter(|v| !v.is_finite()).count();
    if non_finite > 0 {
        fail(&mut report, format!("{non_finite} non-finite values in the browser image"));
    }
    let mean = |img: &LinearImage| img.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * img.pixels.len()).max(1) as f64;
    let mb = mean(browser);
    let mn = natives.iter().map(mean).sum::<f64>() / k as f64;
    let lit = browser.pixels.iter().filter(|p| p.iter().any(|&v| v > 0.0)).count();
    let _ = writeln!(report, "means: browser {mb:.6}, native {mn:.6} ({k} seeds); {lit} of {} browser pixels non-black", browser.pixels.len());
    if !(mb > 0.0) || lit < browser.pixels.len() / 10 {
        fail(&mut report, "the browser image is blank".into());
    }
    let b = criteria.block.max(1);
    let tests = 3 * browser.width.div_ceil(b) * browser.height.div_ceil(b);
    let per_test = 1.0 - (1.0 - criteria.alpha).powf(1.0 / tests as f64);
    let nu = (k - 1) as f64;
    let t_crit = critical_t(per_test, nu);
    let block_mean = |img: &LinearImage, bx: usize, by: usize, c: usize| {
        let (mut s, mut n) = (0.0f64, 0.0f64);
        for y in by..(by + b).min(img.height) {
            for x in bx..(bx + b).min(img.width) {
                s += img.pixels[y * img.width + x][c] as f64;
                n += 1.0;
            }
        }
        s / n
    };
    let (mut worst, mut worst_at) = (0.0f64, (0, 0, 0));
    let blocks = (0..browser.height).step_by(b).flat_map(|by| (0..browser.width).step_by(b).map(move |bx| (bx, by)));
    for (bx, by) in blocks {
        for c in 0..3 {
            let m: Vec<f64> = natives.iter().map(|n| block_mean(n, bx, by, c)).collect();
            let avg = m.iter().sum::<f64>() / k as f64;
            let var = m.iter().map(|v| (v - avg) * (v - avg)).sum::<f64>() / nu;
            let diff = block_mean(browser, bx, by, c) - avg;
            let se = (var * (1.0 + 1.0 / k as f64)).sqrt();
            let t = if diff == 0.0 {
                0.0
            } else if se > 0.0 {
                diff.abs() / se
            } else {
                f64::INFINITY
            };
            let t = if t.is_nan() { f64::INFINITY } else { t };
            if !(t <= worst) {
                worst = t;
                worst_at = (bx, by, c);
            }
        }
    }
    let _ = writeln!(
        report,
        "worst {b}x{b} block |t| = {worst:.3} at ({}, {}) channel {}; Šidák critical |t| = {t_crit:.3} ({tests} tests, {nu} dof, family α = {})",
        worst_at.0, worst_at.1, worst_at.2, criteria.alpha
    );
    if !(worst <= t_crit) {
        fail(&mut report, format!("block means differ significantly (|t| {worst:.3} > {t_crit:.3})"));
    }
    Verdict { ok, report, pixels_differing: 0, worst_z: worst, critical_z: t_crit }
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, nine coefficients; |error| < 1e-13 here).
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let t = x + 7.5;
    let s = G[0] + (1..9).map(|i| G[i] / (x + i as f64)).sum::<f64>();
    0.5 * (2.0 * core::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

/// The regularised incomplete beta function I_x(a, b), by its continued fraction
/// (modified Lentz), using the symmetry I_x(a, b) = 1 − I_{1−x}(b, a) where it converges
/// faster.
fn incomplete_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front = (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    if x > (a + 1.0) / (a + b + 2.0) {
        return 1.0 - incomplete_beta(b, a, 1.0 - x);
    }
    let tiny = 1e-300;
    let (mut c, mut d) = (1.0f64, 1.0 - (a + b) * x / (a + 1.0));
    d = if d.abs() < tiny { 1.0 / tiny } else { 1.0 / d };
    let mut f = d;
    for m in 1..500 {
        let m = m as f64;
        for step in 0..2 {
            let num = if step == 0 {
                m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m))
            } else {
                -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0))
            };
            d = 1.0 + num * d;
            d = if d.abs() < tiny { 1.0 / tiny } else { 1.0 / d };
            c = 1.0 + num / c;
            if c.abs() < tiny {
                c = tiny;
            }
            f *= c * d;
        }
        if (c * d - 1.0).abs() < 1e-15 {
            break;
        }
    }
    front * f / a
}

/// P(|T| > t) for Student's t with `nu` degrees of freedom.
fn student_two_sided_p(t: f64, nu: f64) -> f64 {
    incomplete_beta(0.5 * nu, 0.5, nu / (nu + t * t))
}

/// The |t| whose two-sided tail probability is `p`.
fn critical_t(p: f64, nu: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1e4f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if student_two_sided_p(mid, nu) > p { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod student_tests {
    use super::*;

    /// Against tabulated quantiles: two-sided 5 % at 1, 5, 30 dof (12.706, 2.571, 2.042)
    /// and 1 % at 10 dof (3.169); and the normal limit. Injected bug it caught: the
    /// continued fraction's odd step with the sign flipped (t(5 %, 5) came out 2.567).
    #[test]
    fn t_quantiles_match_the_tables() {
        for (p, nu, t) in [(0.05, 1.0, 12.706), (0.05, 5.0, 2.571), (0.05, 30.0, 2.042), (0.01, 10.0, 3.169)] {
            assert!((critical_t(p, nu) - t).abs() < 2e-3, "t({p}, {nu}) = {} not {t}", critical_t(p, nu));
        }
        assert!((critical_t(1e-3, 1e6) - critical_z(1e-3)).abs() < 1e-3);
    }
}
