//! The browser test's verdict (native only): does the page's linear image (PFM) agree
//! with the native CLI's render (EXR) of the same scene, seed and passes?
//!
//! # What is compared, and how strictly
//! The browser runs the same core code (estimators, libm-only math, counter-based RNG)
//! and the same ray queries (ember-host's BVH4, its build and its watertight triangle and
//! f64 sphere tests, compiled into the module) as the CLI; wasm never fuses
//! multiply-adds and neither does the default x86-64 build. So almost every pixel is the
//! same number. What could differ: the summation order of splats, and hits tied at a
//! shared triangle edge where two hierarchies give them to different triangles (the hit
//! point moves by an ulp and the path diverges from there: about 2 pixels in 1024 at 32²
//! and 2 passes while the browser had a BVH2 of its own, before issue 49). Hence two
//! checks:
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

use ember_tests::chi2::sidak;
use ember_tests::stats::{normal_two_sided_p, student_t_two_sided_p};

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

/// The |x| whose two-sided tail probability `tail(|x|)` is `p`, by bisection (`tail`
/// decreasing, p in (0, 1)).
fn critical(p: f64, tail: impl Fn(f64) -> f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1e4f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if tail(mid) > p { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// The verdict's text and outcome as the checks add to them.
struct Report {
    text: String,
    ok: bool,
}

impl Report {
    fn new() -> Self {
        Self { text: String::new(), ok: true }
    }
    fn fail(&mut self, msg: impl std::fmt::Display) {
        self.ok = false;
        let _ = writeln!(self.text, "FAIL: {msg}");
    }
    /// A verdict for inputs that could not be compared at all.
    fn refused(mut self, msg: impl std::fmt::Display) -> Verdict {
        self.fail(msg);
        Verdict { ok: self.ok, report: self.text, pixels_differing: usize::MAX, worst_z: f64::INFINITY, critical_z: 0.0 }
    }
}

/// Mean over every pixel and channel.
fn image_mean(img: &LinearImage) -> f64 {
    img.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>() / (3 * img.pixels.len()).max(1) as f64
}

/// What both verdicts require of the browser image: no NaN or infinity, not blank.
/// Reports the means (`native` describes the native side).
fn check_browser_image(report: &mut Report, browser: &LinearImage, native_mean: f64, native: &str) {
    let non_finite = browser.pixels.iter().flatten().filter(|v| !v.is_finite()).count();
    if non_finite > 0 {
        report.fail(format!("{non_finite} non-finite values in the browser image"));
    }
    let mb = image_mean(browser);
    let lit = browser.pixels.iter().filter(|p| p.iter().any(|&v| v > 0.0)).count();
    let _ = writeln!(report.text, "means: browser {mb:.6}, native {native_mean:.6}{native}; {lit} of {} browser pixels non-black", browser.pixels.len());
    if !(mb > 0.0) || lit < browser.pixels.len() / 10 {
        report.fail("the browser image is blank");
    }
}

/// |diff| / se, where identical blocks score 0 whatever their spread and a difference in
/// a flat block (se = 0) or a NaN is infinitely significant.
fn score(diff: f64, se: f64) -> f64 {
    let s = if diff == 0.0 {
        0.0
    } else if se > 0.0 {
        diff.abs() / se
    } else {
        f64::INFINITY
    };
    if s.is_nan() { f64::INFINITY } else { s }
}

/// The worst per-block score of a verdict and where it is.
struct Worst {
    score: f64,
    at: (usize, usize, usize),
}

impl Worst {
    fn new() -> Self {
        Self { score: 0.0, at: (0, 0, 0) }
    }
    fn add(&mut self, score: f64, at: (usize, usize, usize)) {
        if !(score <= self.score) {
            *self = Self { score, at };
        }
    }
}

/// The top-left corners of the `b × b` blocks of `img`, row by row.
fn blocks(img: &LinearImage, b: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
    (0..img.height).step_by(b).flat_map(move |by| (0..img.width).step_by(b).map(move |bx| (bx, by)))
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
    let mut report = Report::new();
    if (browser.width, browser.height) != (native.width, native.height) || browser.pixels.len() != browser.width * browser.height {
        return report.refused(format!("sizes differ: browser {}x{}, native {}x{}", browser.width, browser.height, native.width, native.height));
    }
    let mn = image_mean(native);
    check_browser_image(&mut report, browser, mn, "");

    // 1. Pixel by pixel: the same value up to summation order, except diverged paths.
    let same = |a: f32, b: f32| {
        let (a, b) = (a as f64, b as f64);
        (a - b).abs() <= criteria.pixel_tolerance * a.abs().max(b.abs()).max(1e-6 * mn.abs())
    };
    let pixels_differing = browser.pixels.iter().zip(&native.pixels).filter(|(a, b)| !(0..3).all(|c| same(a[c], b[c]))).count();
    let allowed = (criteria.max_differing_fraction * browser.pixels.len() as f64).floor() as usize;
    let _ = writeln!(
        report.text,
        "{pixels_differing} of {} pixels differ by more than {:.0e} relative (allowed {allowed})",
        browser.pixels.len(),
        criteria.pixel_tolerance
    );
    if pixels_differing > allowed {
        report.fail(format!("{pixels_differing} pixels differ, more than {allowed}"));
    }

    // 2. Per block and channel, a z-test of the difference of means against the
    // combined standard error (see the module documentation).
    let b = criteria.block.max(1);
    let tests = 3 * browser.width.div_ceil(b) * browser.height.div_ceil(b);
    let z_crit = critical(sidak(criteria.alpha, tests), normal_two_sided_p);
    let mut worst = Worst::new();
    for (bx, by) in blocks(browser, b) {
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
            worst.add(score((stats[0].0 - stats[1].0) / n, se), (bx, by, c));
        }
    }
    let worst_z = worst.score;
    let _ = writeln!(
        report.text,
        "worst {b}x{b} block |z| = {worst_z:.3} at ({}, {}) channel {}; Šidák critical |z| = {z_crit:.3} ({tests} tests, family α = {})",
        worst.at.0, worst.at.1, worst.at.2, criteria.alpha
    );
    if !(worst_z <= z_crit) {
        report.fail(format!("block means differ significantly (|z| {worst_z:.3} > {z_crit:.3})"));
    }
    Verdict { ok: report.ok, report: report.text, pixels_differing, worst_z, critical_z: z_crit }
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
    let mut report = Report::new();
    let k = natives.len();
    let bad_size = natives.iter().any(|n| (n.width, n.height) != (browser.width, browser.height) || n.pixels.len() != n.width * n.height);
    if k < 3 || bad_size || browser.pixels.len() != browser.width * browser.height {
        return report.refused(format!("need 3 or more native renders of the browser's size ({k} given, sizes differ: {bad_size})"));
    }
    let mn = natives.iter().map(image_mean).sum::<f64>() / k as f64;
    check_browser_image(&mut report, browser, mn, &format!(" ({k} seeds)"));
    let b = criteria.block.max(1);
    let tests = 3 * browser.width.div_ceil(b) * browser.height.div_ceil(b);
    let nu = (k - 1) as f64;
    let t_crit = critical(sidak(criteria.alpha, tests), |t| student_t_two_sided_p(t, nu));
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
    let mut worst = Worst::new();
    for (bx, by) in blocks(browser, b) {
        for c in 0..3 {
            let m: Vec<f64> = natives.iter().map(|n| block_mean(n, bx, by, c)).collect();
            let avg = m.iter().sum::<f64>() / k as f64;
            let var = m.iter().map(|v| (v - avg) * (v - avg)).sum::<f64>() / nu;
            let se = (var * (1.0 + 1.0 / k as f64)).sqrt();
            worst.add(score(block_mean(browser, bx, by, c) - avg, se), (bx, by, c));
        }
    }
    let worst_t = worst.score;
    let _ = writeln!(
        report.text,
        "worst {b}x{b} block |t| = {worst_t:.3} at ({}, {}) channel {}; Šidák critical |t| = {t_crit:.3} ({tests} tests, {nu} dof, family α = {})",
        worst.at.0, worst.at.1, worst.at.2, criteria.alpha
    );
    if !(worst_t <= t_crit) {
        report.fail(format!("block means differ significantly (|t| {worst_t:.3} > {t_crit:.3})"));
    }
    Verdict { ok: report.ok, report: report.text, pixels_differing: 0, worst_z: worst_t, critical_z: t_crit }
}

#[cfg(test)]
mod student_tests {
    use super::*;

    /// The t quantiles the verdict uses, against tabulated ones: two-sided 5 % at 1, 5, 30
    /// dof (12.706, 2.571, 2.042) and 1 % at 10 dof (3.169); and the normal limit.
    /// Injected bug it caught: the incomplete beta's continued fraction with the odd
    /// step's sign flipped (t(5 %, 5) came out 2.567).
    #[test]
    fn t_quantiles_match_the_tables() {
        let t = |p: f64, nu: f64| critical(p, |t| student_t_two_sided_p(t, nu));
        for (p, nu, want) in [(0.05, 1.0, 12.706), (0.05, 5.0, 2.571), (0.05, 30.0, 2.042), (0.01, 10.0, 3.169)] {
            assert!((t(p, nu) - want).abs() < 2e-3, "t({p}, {nu}) = {} not {want}", t(p, nu));
        }
        assert!((t(1e-3, 1e6) - critical(1e-3, normal_two_sided_p)).abs() < 1e-3);
    }
}
