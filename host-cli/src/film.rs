//! The accumulation film: per-pixel f64 sums of every pass's camera samples and
//! splats, and the number of passes.
//!
//! Each pass adds one camera sample per pixel and any number of splats (light-tracing
//! and BDPT t = 1 contributions at continuous film positions, scaled by the pass's
//! splat factor). The image is the mean over passes: `sum / passes`. Sums are kept in
//! f64 so that thousands of passes add without the f32 drift that would otherwise make
//! long renders darker, and so that the merge order alone decides the bits (the driver
//! merges in a fixed order, making images independent of the thread count).
//!
//! A sample with a NaN, infinite or negative channel is never added: it counts as
//! zero (the pass still counts) and is tallied in [`Film::discarded`], so an estimator
//! bug shows up as a number in the summary instead of a black or white pixel.

use core::ops::Range;

use ember_core::Rgb;

use crate::driver::Splat;

/// Accumulated radiance of a `width × height` image (pixel index `y·width + x`).
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    width: u32,
    height: u32,
    sum: Vec<[f64; 3]>,
    passes: u32,
    discarded: u64,
    splats_outside: u64,
}

impl Film {
    /// A black film with no passes.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self { width, height, sum: vec![[0.0; 3]; n], passes: 0, discarded: 0, splats_outside: 0 }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
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

    /// Add one camera sample to each pixel of `pixels` (`samples[i]` to pixel
    /// `pixels.start + i`); pixels beyond the image or the slice are ignored.
    pub fn add_camera_samples(&mut self, pixels: Range<u32>, samples: &[Rgb]) {
        let start = (pixels.start as usize).min(self.sum.len());
        let end = (pixels.end as usize).clamp(start, self.sum.len());
        for (acc, &v) in self.sum[start..end].iter_mut().zip(samples) {
            if v.is_valid_radiance() {
                add(acc, v, 1.0);
            } else {
                self.discarded += 1;
            }
        }
    }

    /// Add splats, each multiplied by `scale`, at the pixel containing its continuous
    /// film position (pixel (x, y) covers [x, x+1) × [y, y+1)).
    pub fn add_splats(&mut self, splats: &[Splat], scale: f64) {
        for s in splats {
            if !s.value.is_valid_radiance() || !s.film.is_finite() {
                self.discarded += 1;
                continue;
            }
            let (x, y) = (s.film.x.floor(), s.film.y.floor());
            if x < 0.0 || y < 0.0 || x >= self.width as f32 || y >= self.height as f32 {
                self.splats_outside += 1;
                continue;
            }
            let i = y as usize * self.width as usize + x as usize;
            add(&mut self.sum[i], s.value, scale);
        }
    }

    /// Close a pass: the mean divides by one more.
    pub fn end_pass(&mut self) {
        self.passes += 1;
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
    use glam::Vec2;

    #[test]
    fn invalid_samples_are_discarded_and_counted() {
        let mut f = Film::new(3, 1);
        f.add_camera_samples(0..3, &[Rgb::new(f32::NAN, 0.0, 0.0), Rgb::new(1.0, 2.0, 3.0), Rgb::new(0.0, -1e-9, 0.0)]);
        let bad = [
            Splat { film: Vec2::new(0.5, 0.5), value: Rgb::splat(f32::INFINITY) },
            Splat { film: Vec2::new(f32::NAN, 0.5), value: Rgb::ONE },
            Splat { film: Vec2::new(2.5, 0.5), value: Rgb::new(1.0, f32::NEG_INFINITY, 1.0) },
            Splat { film: Vec2::new(2.5, 0.5), value: Rgb::splat(4.0) },
            Splat { film: Vec2::new(3.0, 0.5), value: Rgb::ONE },
            Splat { film: Vec2::new(-0.01, 0.5), value: Rgb::ONE },
        ];
        f.add_splats(&bad, 0.5);
        f.end_pass();
        assert_eq!(f.discarded(), 5);
        assert_eq!(f.splats_outside(), 2);
        let img = f.to_rgb_f32();
        assert_eq!(img, vec![[0.0; 3], [1.0, 2.0, 3.0], [2.0, 2.0, 2.0]]);
        assert!(img.iter().flatten().all(|v| v.is_finite()));
    }

    #[test]
    fn mean_over_passes() {
        let mut f = Film::new(2, 2);
        for pass in 0..4 {
            f.add_camera_samples(0..4, &[Rgb::splat(pass as f32); 4]);
            f.add_splats(&[Splat { film: Vec2::new(1.99, 1.0), value: Rgb::splat(8.0) }], 0.25);
            f.end_pass();
        }
        let img = f.to_rgb_f32();
        assert_eq!(img[0], [1.5; 3]);
        assert_eq!(img[3], [3.5; 3]);
        assert_eq!(f.passes(), 4);
        assert_eq!(Film::new(2, 1).to_rgb_f32(), vec![[0.0; 3]; 2], "no pass: black, not NaN");
    }

    /// The film's bits depend on the order splats are added: this is why the driver
    /// merges in chunk order, and why its determinism test can detect a merge in
    /// completion order (the test would be vacuous if the sums were order-independent).
    #[test]
    fn summation_order_is_visible_in_the_bits() {
        let splats: Vec<Splat> = (0..64)
            .map(|i| Splat { film: Vec2::new(0.5, 0.5), value: Rgb::splat(1.0 + (i as f32 * 0.37).sin() * 1e3) })
            .map(|mut s| {
                s.value = s.value.map(|v| v.abs() * 1.000_123);
                s
            })
            .collect();
        let mut forward = Film::new(1, 1);
        forward.add_splats(&splats, 1.0 / 3.0);
        let mut backward = Film::new(1, 1);
        let reversed: Vec<Splat> = splats.iter().rev().copied().collect();
        backward.add_splats(&reversed, 1.0 / 3.0);
        assert_ne!(forward.sums()[0][0].to_bits(), backward.sums()[0][0].to_bits());
    }
}
