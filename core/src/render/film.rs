//! The one accumulation film: per-pixel f64 sums of every pass's camera samples and
//! splats, the pass count and the tallies of what was thrown away.
//!
//! A pass is staged, then committed whole: an estimator's phases write the pass's camera
//! samples ([`Film::set_camera_samples`]) and append its splats ([`Film::push_splats`]) in
//! index order; its last phase calls [`Film::end_pass`] with the pass's splat factor
//! (e.g. 1/M for M light paths), which adds the camera samples and then the splats, in
//! the order they were staged, to the sums. A pass that never ends leaves the sums as
//! they were, so a render interrupted mid-pass never holds a pixel with one sample fewer
//! than its neighbours or splats without their normalisation.
//!
//! The image is the mean over passes, `sum / passes`. Sums are f64, so thousands of passes
//! add without the drift f32 would show, and the staging order alone decides the bits:
//! a host that maps chunks on any number of threads and reduces them in index order
//! writes the same film as the serial runner.
//!
//! A sample with a NaN, infinite or negative channel is never added: it counts as zero
//! (the pass still counts) and is tallied in [`Film::discarded`], so an estimator bug shows
//! up as a number instead of a black or white pixel.

use alloc::vec;
use alloc::vec::Vec;
use core::ops::Range;

use crate::integrator::Splat;
use crate::math;
use crate::spectrum::Rgb;

/// Accumulated radiance of a `width × height` image (pixel index `y·width + x`).
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    sum: Vec<[f64; 3]>,
    passes: u32,
    discarded: u64,
    splats_outside: u64,
    /// The pass being staged: one camera sample per pixel (zero where no phase wrote one).
    camera: Vec<Rgb>,
    has_camera: bool,
    /// The pass's splats, in staging order.
    splats: Vec<Splat>,
}

impl Film {
    /// A black film with no passes. Allocates the sums and the staging buffer once.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            sum: vec![[0.0; 3]; n],
            passes: 0,
            discarded: 0,
            splats_outside: 0,
            camera: vec![Rgb::ZERO; n],
            has_camera: false,
            splats: Vec::new(),
        }
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
        self.discarded
    }

    /// Splats with finite positions outside the image (dropped, not an error: a light
    /// path may connect to a lens point whose pixel lies off the film's edge).
    pub fn splats_outside(&self) -> u64 {
        self.splats_outside
    }

    /// The raw per-pixel sums.
    pub fn sums(&self) -> &[[f64; 3]] {
        &self.sum
    }

    /// Stage this pass's camera samples of `pixels` (`samples[i]` for pixel
    /// `pixels.start + i`); pixels beyond the image or the slice are ignored.
    pub fn set_camera_samples(&mut self, pixels: Range<u32>, samples: &[Rgb]) {
        let start = (pixels.start as usize).min(self.camera.len());
        let end = (pixels.end as usize).clamp(start, self.camera.len());
        let n = (end - start).min(samples.len());
        self.camera[start..start + n].copy_from_slice(&samples[..n]);
        self.has_camera = true;
    }

    /// Stage splats of this pass (added after the camera samples, in this order).
    pub fn push_splats(&mut self, splats: &[Splat]) {
        self.splats.extend_from_slice(splats);
    }

    /// Commit the staged pass: camera samples, then the splats each multiplied by
    /// `splat_scale`, at the pixel containing the splat's continuous film position (pixel
    /// (x, y) covers [x, x+1) × [y, y+1)). The mean then divides by one more.
    pub fn end_pass(&mut self, splat_scale: f64) {
        if self.has_camera {
            for (acc, v) in self.sum.iter_mut().zip(&mut self.camera) {
                if v.is_valid_radiance() {
                    add(acc, *v, 1.0);
                } else {
                    self.discarded += 1;
                }
                *v = Rgb::ZERO;
            }
            self.has_camera = false;
        }
        let splats = core::mem::take(&mut self.splats);
        self.add_splats(&splats, splat_scale);
        self.splats = splats;
        self.splats.clear();
        self.passes += 1;
    }

    /// Back to a black film with no passes and no tallies (the buffers are kept).
    pub fn clear(&mut self) {
        self.sum.fill([0.0; 3]);
        self.passes = 0;
        self.discarded = 0;
        self.splats_outside = 0;
        self.discard_staged();
    }

    /// Drop a staged, uncommitted pass.
    pub fn discard_staged(&mut self) {
        self.camera.fill(Rgb::ZERO);
        self.has_camera = false;
        self.splats.clear();
    }

    fn add_splats(&mut self, splats: &[Splat], scale: f64) {
        for s in splats {
            if !s.value.is_valid_radiance() || !s.film.is_finite() {
                self.discarded += 1;
                continue;
            }
            let (x, y) = (math::floor(s.film.x), math::floor(s.film.y));
            if x < 0.0 || y < 0.0 || x >= self.width as f32 || y >= self.height as f32 {
                self.splats_outside += 1;
                continue;
            }
            let i = y as usize * self.width as usize + x as usize;
            add(&mut self.sum[i], s.value, scale);
        }
    }

    /// The image: the mean over passes (black before the first pass).
    pub fn to_rgb_f32(&self) -> Vec<[f32; 3]> {
        let inv = if self.passes == 0 { 0.0 } else { 1.0 / self.passes as f64 };
        self.sum.iter().map(|s| [(s[0] * inv) as f32, (s[1] * inv) as f32, (s[2] * inv) as f32]).collect()
    }
}

#[inline]
fn add(acc: &mut [f64; 3], v: Rgb, scale: f64) {
    acc[0] += v.r as f64 * scale;
    acc[1] += v.g as f64 * scale;
    acc[2] += v.b as f64 * scale;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;

    #[test]
    fn invalid_samples_are_discarded_and_counted() {
        let mut f = Film::new(3, 1);
        f.set_camera_samples(0..3, &[Rgb::new(f32::NAN, 0.0, 0.0), Rgb::new(1.0, 2.0, 3.0), Rgb::new(0.0, -1e-9, 0.0)]);
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
            f.set_camera_samples(0..4, &[Rgb::splat(pass as f32); 4]);
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
        f.set_camera_samples(0..2, &[Rgb::ONE; 2]);
        f.end_pass(1.0);
        let before = f.clone();
        f.set_camera_samples(0..2, &[Rgb::splat(5.0); 2]);
        f.push_splats(&[Splat { film: Vec2::new(0.5, 0.5), value: Rgb::ONE }]);
        f.discard_staged();
        assert_eq!(f.sums(), before.sums());
        assert_eq!(f.passes(), 1);
    }

    /// The film's bits depend on the order splats are added: this is why hosts reduce in
    /// chunk order, and why the determinism tests can detect a merge in completion order.
    #[test]
    fn summation_order_is_visible_in_the_bits() {
        let splats: Vec<Splat> =
            (0..64).map(|i| Splat { film: Vec2::new(0.5, 0.5), value: Rgb::splat((1.0 + math::sin(i as f32 * 0.37) * 1e3).abs() * 1.000_123) }).collect();
        let mut forward = Film::new(1, 1);
        forward.push_splats(&splats);
        forward.end_pass(1.0 / 3.0);
        let mut backward = Film::new(1, 1);
        let reversed: Vec<Splat> = splats.iter().rev().copied().collect();
        backward.push_splats(&reversed);
        backward.end_pass(1.0 / 3.0);
        assert_ne!(forward.sums()[0][0].to_bits(), backward.sums()[0][0].to_bits());
    }
}
