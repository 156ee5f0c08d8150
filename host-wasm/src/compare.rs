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
