//! The one accumulation film: per-pixel sums of every pass's camera samples and splats,
//! the pass count and the tallies of what was thrown away.
//!
//! A pass is staged, then committed whole: an estimator's phases write the pass's camera
//! samples ([`Film::set_camera_samples`]) and append its splats ([`Film::push_splats`]) in
//! index order; its last phase calls [`Film::end_pass`] with the pass's splat factor
//! (e.g. 1/M for M light paths), which adds the camera samples and then the splats to the
//! sums. A pass that never ends leaves the sums as they were, so a render interrupted
//! mid-pass never holds a pixel with one sample fewer than its neighbours or splats
//! without their normalisation.
//!
//! # Exact sums
//! The image is the mean over passes, `sum / passes`. The sums are fixed-point integers,
//! not floats: every camera sample and every scaled splat is rounded once, on its own, to
//! a multiple of the quantum 2⁻⁶⁴ ([`QUANTUM_BITS`]), and added to a `u128` per channel.
//! Integer addition is associative, so the sums do not depend on the order in which
//! samples, splats, passes or whole films ([`Film::merge`]) are added: a render split
//! into pass ranges on several machines and merged equals the single-process render bit
//! for bit (docs/distributed.md). f64 sums could not promise that: (a + b) + c and
//! a + (b + c) differ in the last bit.
//!
//! The range: a pixel's sum holds up to 2⁶⁴ ≈ 1.8·10¹⁹ (over all passes); a sample's
//! part below 2⁻⁶⁵ ≈ 2.7·10⁻²⁰ is rounded away (round half up). A sum that would pass the
//! top stays at the top and is tallied in [`Film::saturated`]. Radiance from 10⁻⁸ to 10⁸
//! times the built-in box's renders linearly (`tests/tests/stability_extremes.rs`).
//!
//! # The pixel filter
//! Under the box a camera sample is added to its own pixel, as it always was, and the
//! image is `sum / passes`. Under a tent or a gaussian the film spreads each camera sample
//! over the pixels around its film point and keeps, per pixel, Σ f L and Σ f apart from
//! the splats' sums ([`WeightedSum`]): Mitsuba's weighted film, a ratio estimator,
//! consistent but not unbiased ([`spread`] holds its essay). Such a pixel's image is
//! Σ f L / Σ f + `sum / passes`. A splat at x is spread over the pixels c within the filter's radius with the weights
//! h_c(x) of `crate::pixel_filter` (eq. 1–2); each weighted addition is rounded on its own, so
//! the sums stay order independent. The box film ([`Film::new`]) adds a splat to the
//! pixel containing it with weight 1, as it always did. Merged films are not checked for
//! equal filters: committed sums are already filtered, and a film read back by
//! [`Film::from_exact`] (a box film, given its weighted sums by
//! [`Film::with_weighted_sums`]) only merges.
//!
//! A sample with a NaN, infinite or negative channel is never added: it counts as zero
//! (the pass still counts) and is tallied in [`Film::discarded`], so an estimator bug shows
//! up as a number instead of a black or white pixel.

use alloc::vec;
use alloc::vec::Vec;
use core::ops::Range;

use crate::camera::PerspectiveCamera;
use crate::math;
use crate::pixel_filter::Filter;
use crate::spectrum::Rgb;
use crate::transport::Splat;

mod bands;
mod spread;

use crate::camera::CameraPass;
pub use bands::{Band, ParallelBands};
use bands::{Lists, commit_camera_sample};
pub use spread::WeightedSum;
use spread::spread_camera_rows;

/// Bits of a sum below the binary point: a sum is an integer count of 2⁻⁶⁴.
pub const QUANTUM_BITS: u32 = 64;
const SCALE: f64 = (1u128 << QUANTUM_BITS) as f64;
const INV_SCALE: f64 = 1.0 / SCALE;

/// Accumulated radiance of a `width × height` image (pixel index `y·width + x`).
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    /// Per pixel and channel, the sum in units of 2⁻⁶⁴ ([`QUANTUM_BITS`]).
    sum: Vec<[u128; 3]>,
    passes: u32,
    tallies: Tallies,
    /// The pass being staged: one camera sample per pixel (zero where no phase wrote one).
    camera: Vec<Rgb>,
    /// The staged camera samples' pass, once a phase wrote some.
    camera_pass: Option<CameraPass>,
    /// Per pixel, the camera samples spread by a wide filter (empty for the box).
    weighted: Vec<WeightedSum>,
    /// The pass's splats, in staging order.
    splats: Vec<Splat>,
    /// How splats are spread over pixels.
    filter: Filter,
    /// The host's way of committing a pass on several threads, if it has one.
    workers: Workers,
    /// Scratch of the parallel commit ([`bands`]).
    lists: Lists,
}

/// A [`ParallelBands`] runner held by a film; it never changes the film's contents, so
/// it takes no part in comparisons.
#[derive(Clone, Copy, Default)]
struct Workers(Option<ParallelBands>);

impl PartialEq for Workers {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl core::fmt::Debug for Workers {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(if self.0.is_some() { "Workers(parallel)" } else { "Workers(sequential)" })
    }
}

/// What a film threw away or clamped, summed over its passes (and over merged films).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tallies {
    /// Samples and splats with a NaN, infinite or negative value.
    pub discarded: u64,
    /// Splats with finite positions outside the image.
    pub splats_outside: u64,
    /// Additions that would have passed a sum's top (the sum stayed at the top).
    pub saturated: u64,
}

impl Tallies {
    fn add(&mut self, o: &Tallies) {
        self.discarded += o.discarded;
        self.splats_outside += o.splats_outside;
        self.saturated += o.saturated;
    }
}

/// Why two films cannot be merged, or parts not assembled into a film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilmError {
    /// The films' sizes differ.
    Size {
        /// This film's width and height.
        this: (u32, u32),
        /// The other film's.
        other: (u32, u32),
    },
    /// The pass count would pass `u32::MAX`.
    PassCount,
    /// `sums` does not hold `width × height` pixels.
    Pixels {
        /// width × height.
        expected: usize,
        /// The sums given.
        got: usize,
    },
}

impl core::fmt::Display for FilmError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Size { this, other } => write!(f, "a {}x{} film cannot take a {}x{} one", this.0, this.1, other.0, other.1),
            Self::PassCount => f.write_str("more than 2^32 - 1 passes"),
            Self::Pixels { expected, got } => write!(f, "{got} pixel sums for {expected} pixels"),
        }
    }
}

impl Film {
    /// A black box-filtered film with no passes. Allocates the sums and the staging
    /// buffer once.
    pub fn new(width: u32, height: u32) -> Self {
        Self::with_filter(width, height, Filter::Box)
    }

    /// A black film with no passes whose splats are spread by `filter`.
    pub fn with_filter(width: u32, height: u32, filter: Filter) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            sum: vec![[0; 3]; n],
            passes: 0,
            tallies: Tallies::default(),
            camera: vec![Rgb::ZERO; n],
            camera_pass: None,
            weighted: if filter.is_box() { Vec::new() } else { vec![WeightedSum::default(); n] },
            splats: Vec::new(),
            filter,
            workers: Workers(None),
            lists: Lists::default(),
        }
    }

    /// Commit splats through `run` from now on (`None`: on the calling thread). The result
    /// is the same either way ([`ParallelBands`]).
    pub fn set_parallel_splats(&mut self, run: Option<ParallelBands>) {
        self.workers = Workers(run);
    }

    /// The film of `camera`: its size and its filter.
    pub fn for_camera(camera: &PerspectiveCamera) -> Self {
        Self::with_filter(camera.width(), camera.height(), camera.filter())
    }

    /// The filter splats are spread by.
    pub fn filter(&self) -> Filter {
        self.filter
    }

    /// A film holding `passes` passes whose exact sums are `sums` (as [`Film::exact_sums`]
    /// gave them): how a host reads back a stored partial film.
    pub fn from_exact(width: u32, height: u32, sums: Vec<[u128; 3]>, passes: u32, tallies: Tallies) -> Result<Self, FilmError> {
        let expected = width as usize * height as usize;
        if sums.len() != expected {
            return Err(FilmError::Pixels { expected, got: sums.len() });
        }
        let mut film = Self::new(0, 0);
        film.width = width;
        film.height = height;
        film.sum = sums;
        film.camera = vec![Rgb::ZERO; expected];
        film.passes = passes;
        film.tallies = tallies;
        Ok(film)
    }

    /// This film with the camera samples' weighted sums `weighted` (as
    /// [`Film::weighted_sums`] gave them; empty: none, a box film's).
    pub fn with_weighted_sums(mut self, weighted: Vec<WeightedSum>) -> Result<Self, FilmError> {
        if !weighted.is_empty() && weighted.len() != self.sum.len() {
            return Err(FilmError::Pixels { expected: self.sum.len(), got: weighted.len() });
        }
        self.weighted = weighted;
        Ok(self)
    }

    /// Image width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Number of pixels.
    pub fn pixels(&self) -> usize {
        self.sum.len()
    }

    /// Completed passes (the per-pixel sample count of the camera side).
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// Samples and splats thrown away for a NaN, infinite or negative value.
    pub fn discarded(&self) -> u64 {
        self.tallies.discarded
    }

    /// Splats with finite positions outside the image (dropped, not an error: a light
    /// path may connect to a lens point whose pixel lies off the film's edge).
    pub fn splats_outside(&self) -> u64 {
        self.tallies.splats_outside
    }

    /// Additions clamped at the top of a sum (2⁶⁴): 0 unless radiance is astronomical.
    pub fn saturated(&self) -> u64 {
        self.tallies.saturated
    }

    /// All tallies.
    pub fn tallies(&self) -> Tallies {
        self.tallies
    }

    /// The exact per-pixel sums, in units of 2⁻⁶⁴ ([`QUANTUM_BITS`]).
    pub fn exact_sums(&self) -> &[[u128; 3]] {
        &self.sum
    }

    /// The camera samples' weighted sums under a wide filter, per pixel; empty for the box,
    /// whose camera samples are in [`Film::exact_sums`].
    pub fn weighted_sums(&self) -> &[WeightedSum] {
        &self.weighted
    }

    /// The per-pixel sums as f64 (each rounded once from the exact sum): the camera
    /// samples and splats of a box film, the splats alone of a wide one.
    pub fn sums(&self) -> Vec<[f64; 3]> {
        self.sum.iter().map(|s| s.map(|v| v as f64 * INV_SCALE)).collect()
    }

    /// Stage the camera samples of `pixels` drawn in pass `at` (`samples[i]` for pixel
    /// `pixels.start + i`); pixels beyond the image or the slice are ignored. A wide
    /// filter spreads each from the film point `at` gives it
    /// (`crate::camera::camera_film_point`); every call of a pass names the same `at`.
    pub fn set_camera_samples(&mut self, at: CameraPass, pixels: Range<u32>, samples: &[Rgb]) {
        debug_assert!(self.camera_pass.is_none_or(|p| p == at), "one pass's camera samples, one key");
        let start = (pixels.start as usize).min(self.camera.len());
        let end = (pixels.end as usize).clamp(start, self.camera.len());
        let n = (end - start).min(samples.len());
        self.camera[start..start + n].copy_from_slice(&samples[..n]);
        self.camera_pass = Some(at);
    }

    /// Stage splats of this pass (added after the camera samples, in this order).
    pub fn push_splats(&mut self, splats: &[Splat]) {
        self.splats.extend_from_slice(splats);
    }

    /// Commit the staged pass: camera samples, then the splats each multiplied by
    /// `splat_scale`, at the pixel containing the splat's continuous film position (pixel
    /// (x, y) covers [x, x+1) × [y, y+1)). The mean then divides by one more.
    pub fn end_pass(&mut self, splat_scale: f64) {
        let splats = core::mem::take(&mut self.splats);
        match self.workers.0.filter(|_| self.worth_bands(splats.len())) {
            Some(run) => self.commit_in_bands(run, &splats, splat_scale),
            None => self.commit_here(&splats, splat_scale),
        }
        self.camera_pass = None;
        self.splats = splats;
        self.splats.clear();
        self.passes += 1;
    }

    /// Add another film's passes to this one's (both must hold only committed passes of
    /// disjoint pass ranges for the mean to mean anything). Exact: merging in any order
    /// or grouping gives the same bits.
    pub fn merge(&mut self, other: &Film) -> Result<(), FilmError> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(FilmError::Size { this: (self.width, self.height), other: (other.width, other.height) });
        }
        let passes = self.passes.checked_add(other.passes).ok_or(FilmError::PassCount)?;
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            for c in 0..3 {
                a[c] = match a[c].checked_add(b[c]) {
                    Some(v) => v,
                    None => {
                        self.tallies.saturated += 1;
                        u128::MAX
                    }
                };
            }
        }
        if !other.weighted.is_empty() {
            if self.weighted.is_empty() {
                self.weighted = vec![WeightedSum::default(); self.sum.len()];
            }
            for (a, b) in self.weighted.iter_mut().zip(&other.weighted) {
                self.tallies.saturated += a.merge(b);
            }
        }
        self.passes = passes;
        self.tallies.add(&other.tallies);
        Ok(())
    }

    /// Back to a black film with no passes and no tallies (the buffers are kept).
    pub fn clear(&mut self) {
        self.sum.fill([0; 3]);
        self.weighted.fill(WeightedSum::default());
        self.passes = 0;
        self.tallies = Tallies::default();
        self.discard_staged();
    }

    /// Drop a staged, uncommitted pass.
    pub fn discard_staged(&mut self) {
        self.camera.fill(Rgb::ZERO);
        self.camera_pass = None;
        self.splats.clear();
    }

    /// [`Self::end_pass`] on the calling thread.
    fn commit_here(&mut self, splats: &[Splat], scale: f64) {
        let (width, height, filter) = (self.width, self.height, self.filter);
        match self.camera_pass {
            None => {}
            Some(_) if filter.is_box() || self.weighted.is_empty() => {
                for (acc, v) in self.sum.iter_mut().zip(&mut self.camera) {
                    commit_camera_sample(&mut self.tallies, acc, v);
                }
            }
            Some(at) => {
                spread_camera_rows(filter, at, width, height, &self.camera, &mut self.weighted, 0..height, &mut self.tallies);
                self.camera.fill(Rgb::ZERO);
            }
        }
        for s in splats {
            if admit(&mut self.tallies, s, width, height) {
                self.tallies.saturated += splat_rows(filter, width, height, &mut self.sum, 0..height, s, scale);
            }
        }
    }

    /// The image: the mean over passes (black before the first pass), plus under a wide
    /// filter the camera samples' weighted mean Σ f L / Σ f.
    pub fn to_rgb_f32(&self) -> Vec<[f32; 3]> {
        self.to_rgb_f64().into_iter().map(|p| p.map(|v| v as f32)).collect()
    }

    /// [`Self::to_rgb_f32`] before its rounding to f32.
    pub fn to_rgb_f64(&self) -> Vec<[f64; 3]> {
        let inv = if self.passes == 0 { 0.0 } else { INV_SCALE / self.passes as f64 };
        if self.weighted.is_empty() {
            return self.sum.iter().map(|s| s.map(|v| v as f64 * inv)).collect();
        }
        self.sum.iter().zip(&self.weighted).map(|(s, w)| core::array::from_fn(|c| s[c] as f64 * inv + w.ratio(c))).collect()
    }
}

/// Tally splat `s` if it is discarded or outside a `width × height` image; whether it is
/// added.
fn admit(tallies: &mut Tallies, s: &Splat, width: u32, height: u32) -> bool {
    if !s.value.is_valid_radiance() || !s.film.is_finite() {
        tallies.discarded += 1;
        return false;
    }
    let (x, y) = (math::floor(s.film.x), math::floor(s.film.y));
    if x < 0.0 || y < 0.0 || x >= width as f32 || y >= height as f32 {
        tallies.splats_outside += 1;
        return false;
    }
    true
}

/// The rows of a `height`-row image that admitted splat `s` reaches under `filter`: the
/// rows [`splat_rows`] adds to (its pixel's row for the box).
fn rows_reached(filter: Filter, s: &Splat, height: u32) -> Range<u32> {
    if filter.is_box() {
        let y = math::floor(s.film.y) as u32;
        y..y + 1
    } else {
        filter.splat_range(s.film.y, height)
    }
}

/// Add admitted splat `s` × `scale` to the pixels of rows `rows` it reaches; `sums` holds
/// exactly those rows. Returns how many channels saturated.
fn splat_rows(filter: Filter, width: u32, height: u32, sums: &mut [[u128; 3]], rows: Range<u32>, s: &Splat, scale: f64) -> u64 {
    let (x, y) = (math::floor(s.film.x) as u32, math::floor(s.film.y) as u32);
    let at = |px: u32, py: u32| (py - rows.start) as usize * width as usize + px as usize;
    if filter.is_box() {
        return if rows.contains(&y) { add(&mut sums[at(x, y)], s.value, scale) } else { 0 };
    }
    // Spread over the pixels within the filter's radius, h_c(x) each.
    let mut saturated = 0;
    for py in filter.splat_range(s.film.y, height) {
        if !rows.contains(&py) {
            continue;
        }
        let wy = filter.splat_weight(s.film.y, py, height);
        if wy <= 0.0 {
            continue;
        }
        for px in filter.splat_range(s.film.x, width) {
            let w = wy * filter.splat_weight(s.film.x, px, width);
            if w > 0.0 {
                saturated += add(&mut sums[at(px, py)], s.value, scale * w as f64);
            }
        }
    }
    saturated
}

/// `v` in units of the quantum, rounded half up; `None` at or past 2¹²⁸ units. `v` must be
/// finite and non-negative (callers check [`Rgb::is_valid_radiance`]). Integer work on
/// the float's bits: `v = m · 2^(e − 1075)` with a 53-bit `m`, so the count is `m`
/// shifted by `e − 1075 + 64` (a float-to-u128 cast costs a library call per channel,
/// which made depth-1 path tracing 33 % slower).
#[inline]
fn to_fixed(v: f64) -> Option<u128> {
    let bits = v.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32;
    if exponent == 0 {
        // Zero or subnormal: below 2⁻¹⁰²², far below half a quantum.
        return Some(0);
    }
    let m = ((bits & ((1 << 52) - 1)) | (1 << 52)) as u128;
    let shift = exponent - 1075 + QUANTUM_BITS as i32;
    if shift >= 0 {
        // m < 2⁵³, so m · 2^shift < 2¹²⁸ exactly when shift ≤ 75.
        (shift <= 75).then(|| m << shift)
    } else if shift >= -54 {
        let s = (-shift) as u32;
        Some((m + (1 << (s - 1))) >> s)
    } else {
        // m · 2^shift < 2⁻¹: rounds to zero.
        Some(0)
    }
}

/// Add `v · scale` to a pixel's sums; returns how many channels saturated.
#[inline]
fn add(acc: &mut [u128; 3], v: Rgb, scale: f64) -> u64 {
    let mut saturated = 0;
    for (a, c) in acc.iter_mut().zip([v.r, v.g, v.b]) {
        match to_fixed(c as f64 * scale).and_then(|n| a.checked_add(n)) {
            Some(sum) => *a = sum,
            None => {
                *a = u128::MAX;
                saturated += 1;
            }
        }
    }
    saturated
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;

    /// The pass key of the tests' camera samples.
    const AT: CameraPass = CameraPass { seed: 1, pass: 0 };

    /// Bands in reverse order, as a parallel runner may take them.
    fn reversed(bands: &mut [Band<'_>], work: &(dyn Fn(&mut Band<'_>) + Sync)) {
        for band in bands.iter_mut().rev() {
            work(band);
        }
    }

    /// The banded commit equals the sequential one bit for bit (sums and tallies), with a
    /// box and a wide filter, camera samples (one invalid) and splats on band edges,
    /// outside the image and invalid; and a film with camera samples alone. Seen to fail
    /// on injected bugs: a splat listed only under the band of its first row (the
    /// Gaussian's lower rows lost), a band's rows starting one row late, the last sort
    /// segment ending one splat short, and a band skipping its camera samples; and (issue
    /// 52) a band spreading only the camera samples of its own rows (`spread`'s reach 0),
    /// which loses its neighbours' samples near its edges.
    #[test]
    fn banded_commit_equals_the_sequential_one() {
        use super::bands::{PARALLEL_PIXELS, PARALLEL_SPLATS};
        let mut rng = crate::rng::SampleStream::for_sample(7, crate::rng::Stream::Aux, 0, 0, 0);
        let (w, h) = (37u32, 131u32);
        let n = PARALLEL_SPLATS + 4099;
        let mut splats: Vec<Splat> = (0..n)
            .map(|_| {
                let film = Vec2::new(rng.next_f32() * (w as f32 + 2.0) - 1.0, rng.next_f32() * (h as f32 + 2.0) - 1.0);
                Splat { film, value: Rgb::new(rng.next_f32(), 3.0 * rng.next_f32(), 0.25) }
            })
            .collect();
        splats[3].value = Rgb::new(f32::NAN, 0.0, 0.0);
        splats[4].film = Vec2::new(0.5, f32::INFINITY);
        // Exactly on the first rows of bands (3 rows per band at this height), and the
        // very last splat inside the image.
        for (k, y) in [3.0f32, 6.0, 129.0, 130.999].into_iter().enumerate() {
            splats[10 + k].film = Vec2::new(5.5, y);
        }
        splats[n - 1] = Splat { film: Vec2::new(1.5, 1.5), value: Rgb::splat(1e3) };
        let mut camera: Vec<Rgb> = (0..w * h).map(|_| Rgb::new(rng.next_f32(), 0.5, 2.0 * rng.next_f32())).collect();
        camera[77].g = -1.0;
        for filter in [Filter::Box, Filter::Gaussian { stddev: 1.5 }, Filter::Tent { radius: 2.0 }] {
            let mut one = Film::with_filter(w, h, filter);
            let mut banded = Film::with_filter(w, h, filter);
            banded.set_parallel_splats(Some(reversed));
            for film in [&mut one, &mut banded] {
                for pass in 0..2 {
                    film.set_camera_samples(AT, 0..w * h, &camera);
                    film.push_splats(&splats[pass * 100..]);
                    film.end_pass(0.125);
                }
            }
            assert!(one.splats_outside() > 0 && one.discarded() == 4, "{:?}", one.tallies());
            assert_eq!(one.tallies(), banded.tallies(), "{filter:?}");
            assert!(one.exact_sums() == banded.exact_sums(), "{filter:?}");
            assert!(one.weighted_sums() == banded.weighted_sums(), "{filter:?}: the camera samples' weighted sums");
            assert_eq!(one.weighted_sums().is_empty(), filter.is_box());
            // Too few splats to cut: committed on the calling thread, the same film.
            let mut few = Film::with_filter(w, h, filter);
            let mut few_banded = Film::with_filter(w, h, filter);
            few_banded.set_parallel_splats(Some(reversed));
            for film in [&mut few, &mut few_banded] {
                film.push_splats(&splats[..100]);
                film.end_pass(1.0);
            }
            assert!(few.exact_sums() == few_banded.exact_sums() && few.tallies() == few_banded.tallies(), "{filter:?}");
        }
        // Camera samples alone, enough pixels to cut (path tracing's passes).
        let (w, h) = (128u32, PARALLEL_PIXELS as u32 / 128 + 3);
        let camera: Vec<Rgb> = (0..w * h).map(|i| Rgb::new(i as f32 * 1e-3, rng.next_f32(), if i == 5 { f32::NAN } else { 1.0 })).collect();
        let mut one = Film::new(w, h);
        let mut banded = Film::new(w, h);
        banded.set_parallel_splats(Some(reversed));
        for film in [&mut one, &mut banded] {
            for _ in 0..2 {
                film.set_camera_samples(AT, 0..w * h, &camera);
                film.end_pass(1.0);
            }
        }
        assert_eq!(one.discarded(), 2);
        assert!(one.exact_sums() == banded.exact_sums() && one.tallies() == banded.tallies());
    }

    #[test]
    fn invalid_samples_are_discarded_and_counted() {
        let mut f = Film::new(3, 1);
        f.set_camera_samples(AT, 0..3, &[Rgb::new(f32::NAN, 0.0, 0.0), Rgb::new(1.0, 2.0, 3.0), Rgb::new(0.0, -1e-9, 0.0)]);
        let bad = [
            Splat { film: Vec2::new(0.5, 0.5), value: Rgb::splat(f32::INFINITY) },
            Splat { film: Vec2::new(f32::NAN, 0.5), value: Rgb::ONE },
            Splat { film: Vec2::new(2.5, 0.5), value: Rgb::new(1.0, f32::NEG_INFINITY, 1.0) },
            Splat { film: Vec2::new(2.5, 0.5), value: Rgb::splat(4.0) },
            Splat { film: Vec2::new(3.0, 0.5), value: Rgb::ONE },
            Splat { film: Vec2::new(-0.01, 0.5), value: Rgb::ONE },
        ];
        f.push_splats(&bad);
        f.end_pass(0.5);
        assert_eq!(f.discarded(), 5);
        assert_eq!(f.splats_outside(), 2);
        let img = f.to_rgb_f32();
        assert_eq!(img, vec![[0.0; 3], [1.0, 2.0, 3.0], [2.0, 2.0, 2.0]]);
    }

    #[test]
    fn mean_over_passes_and_staging_is_per_pass() {
        let mut f = Film::new(2, 2);
        for pass in 0..4 {
            f.set_camera_samples(AT, 0..4, &[Rgb::splat(pass as f32); 4]);
            f.push_splats(&[Splat { film: Vec2::new(1.99, 1.0), value: Rgb::splat(8.0) }]);
            f.end_pass(0.25);
        }
        // A pass whose phases wrote no camera samples adds none (the staging was cleared).
        f.push_splats(&[Splat { film: Vec2::new(0.5, 0.5), value: Rgb::splat(4.0) }]);
        f.end_pass(1.0);
        let img = f.to_rgb_f32();
        assert_eq!(img[0], [(6.0 + 4.0) / 5.0; 3]);
        assert_eq!(img[3], [(6.0 + 8.0) / 5.0; 3]);
        assert_eq!(f.passes(), 5);
        assert_eq!(Film::new(2, 1).to_rgb_f32(), vec![[0.0; 3]; 2], "no pass: black, not NaN");
    }

    #[test]
    fn a_staged_pass_that_never_ends_changes_nothing() {
        let mut f = Film::new(2, 1);
        f.set_camera_samples(AT, 0..2, &[Rgb::ONE; 2]);
        f.end_pass(1.0);
        let before = f.clone();
        f.set_camera_samples(AT, 0..2, &[Rgb::splat(5.0); 2]);
        f.push_splats(&[Splat { film: Vec2::new(0.5, 0.5), value: Rgb::ONE }]);
        f.discard_staged();
        assert_eq!(f.sums(), before.sums());
        assert_eq!(f.passes(), 1);
    }

    /// The sums are exact integers: the order of splats, and the grouping of passes into
    /// merged films, leaves every bit unchanged. (With f64 sums the reversed order
    /// differed in the last bit: this test failed on the film before issue 22.)
    #[test]
    fn summation_order_and_grouping_leave_the_bits_unchanged() {
        let splats: Vec<Splat> =
            (0..64).map(|i| Splat { film: Vec2::new(0.5, 0.5), value: Rgb::splat((1.0 + math::sin(i as f32 * 0.37) * 1e3).abs() * 1.000_123) }).collect();
        let mut forward = Film::new(1, 1);
        forward.push_splats(&splats);
        forward.end_pass(1.0 / 3.0);
        let mut backward = Film::new(1, 1);
        let reversed: Vec<Splat> = splats.iter().rev().copied().collect();
        backward.push_splats(&reversed);
        backward.end_pass(1.0 / 3.0);
        assert_eq!(forward.exact_sums(), backward.exact_sums());

        // Passes 0..8 in one film against ((0..3) + (6..8)) + (3..6) merged.
        let pass = |f: &mut Film, p: usize| {
            f.set_camera_samples(AT, 0..2, &[Rgb::splat(0.1 * p as f32 + 1e-7), Rgb::new(3.3e-9, 1e5, 0.7)]);
            f.push_splats(&splats[p * 8..p * 8 + 8]);
            f.end_pass(1.0 / 7.0);
        };
        let mut whole = Film::new(2, 1);
        (0..8).for_each(|p| pass(&mut whole, p));
        let part = |r: core::ops::Range<usize>| {
            let mut f = Film::new(2, 1);
            r.for_each(|p| pass(&mut f, p));
            f
        };
        let mut merged = part(0..3);
        merged.merge(&part(6..8)).unwrap();
        merged.merge(&part(3..6)).unwrap();
        assert_eq!(merged, whole);
        assert_eq!(merged.to_rgb_f32(), whole.to_rgb_f32());
        assert!(matches!(merged.merge(&Film::new(1, 2)), Err(FilmError::Size { .. })));
    }

    /// Rounding happens once per sample, to 2⁻⁶⁴; the top saturates and is counted.
    #[test]
    fn fixed_point_rounds_per_sample_and_saturates_at_the_top() {
        assert_eq!(to_fixed(1.0), Some(1 << 64));
        assert_eq!(to_fixed(0.0), Some(0));
        // Half a quantum rounds up, a third rounds away.
        assert_eq!(to_fixed(0.5 * INV_SCALE), Some(1));
        assert_eq!(to_fixed(INV_SCALE / 3.0), Some(0));
        assert_eq!(to_fixed(1e19), Some((1e19f64 * SCALE) as u128));
        assert_eq!(to_fixed(3.5e19), None);
        // The bit-level conversion against the float one, rounding half up, over
        // magnitudes from below the quantum to the top.
        let reference = |v: f64| -> Option<u128> {
            let x = v * SCALE;
            if !(x < u128::MAX as f64) {
                return None;
            }
            let n = x as u128;
            Some(if x - n as f64 >= 0.5 { n + 1 } else { n })
        };
        let mut v = 1e-25f64;
        while v < 1e20 {
            for w in [v, v * 1.000_000_1, v * 1.5, v * 1.999_999_9, f64::from_bits(v.to_bits() | 1)] {
                assert_eq!(to_fixed(w), reference(w), "{w:e}");
            }
            v *= 1.37;
        }
        for k in -70..-60 {
            let half = 2f64.powi(k);
            assert_eq!(to_fixed(half), reference(half), "2^{k}");
        }
        assert_eq!(to_fixed(2f64.powi(64) * (1.0 - f64::EPSILON)), reference(2f64.powi(64) * (1.0 - f64::EPSILON)));
        assert_eq!(to_fixed(2f64.powi(64)), None);
        assert_eq!(to_fixed(f64::MIN_POSITIVE / 2.0), Some(0));
        let mut f = Film::new(1, 1);
        for _ in 0..3 {
            f.set_camera_samples(AT, 0..1, &[Rgb::new(7e18, 1.0, 0.0)]);
            f.end_pass(1.0);
        }
        assert_eq!(f.saturated(), 1, "the third 7e18 passes 2^64");
        assert_eq!(f.exact_sums()[0][0], u128::MAX);
        assert_eq!(f.to_rgb_f32()[0][1], 1.0);
        let restored = Film::from_exact(1, 1, f.exact_sums().to_vec(), f.passes(), f.tallies()).unwrap();
        assert_eq!(restored, f);
        assert!(Film::from_exact(2, 1, vec![[0; 3]], 1, Tallies::default()).is_err());
    }
}
