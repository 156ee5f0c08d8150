use super::*;

use ember_core::rng::{SampleStream, Stream};
use glam::Vec2;

/// A renderer whose samples and splats are pure functions of (pixel or path, pass), as
/// a real estimator's are: values over six orders of magnitude (so the f64 sums depend
/// on the merge order), occasional NaN and negative samples, splats from both sides.
struct Fake {
    w: u32,
    h: u32,
    light_paths: u32,
}

fn value(s: &mut SampleStream) -> Rgb {
    let mut v = || (s.next_f32() * 14.0 - 7.0).exp2() * 1.000_1;
    Rgb::new(v(), v(), v())
}

impl PassRenderer for Fake {
    fn width(&self) -> u32 {
        self.w
    }
    fn height(&self) -> u32 {
        self.h
    }
    fn camera_pass(&self, pass: u32, pixels: Range<u32>, out: &mut [Rgb], splat: &mut dyn FnMut(Splat)) -> PassStats {
        for (i, o) in pixels.clone().zip(out.iter_mut()) {
            let mut s = SampleStream::for_sample(9, Stream::Camera, i, 0, pass);
            *o = value(&mut s);
            let u = s.next_f32();
            if u < 0.01 {
                *o = Rgb::new(f32::NAN, 0.0, 0.0);
            } else if u < 0.02 {
                *o = Rgb::new(-1.0, 0.0, 0.0);
            }
            if s.next_f32() < 0.3 {
                let p = s.next_2d() * Vec2::new(self.w as f32, self.h as f32);
                splat(Splat { film: p, value: value(&mut s) });
            }
        }
        PassStats { rays: 3 * pixels.len() as u64, samples: pixels.len() as u64 }
    }
    fn light_paths_per_pass(&self) -> u32 {
        self.light_paths
    }
    fn light_pass(&self, pass: u32, paths: Range<u32>, splat: &mut dyn FnMut(Splat)) -> PassStats {
        for j in paths.clone() {
            let mut s = SampleStream::for_sample(9, Stream::Light, j, 0, pass);
            for _ in 0..3 {
                // A few splats land on the same pixels, in an order the merge must keep.
                let p = s.next_2d() * Vec2::new(4.0, 3.0);
                splat(Splat { film: p, value: value(&mut s) });
            }
        }
        PassStats { rays: 5 * paths.len() as u64, samples: paths.len() as u64 }
    }
    fn splat_scale(&self) -> f64 {
        1.0 / 7.0
    }
}

fn run(threads: usize, spp: u32) -> (Film, RenderSummary) {
    let fake = Fake { w: 23, h: 17, light_paths: 101 };
    let mut film = Film::new(23, 17);
    let config = DriverConfig { threads, pixel_chunk: 13, light_chunk: 7, progress: false };
    let summary = render(&fake, &mut film, Limits { spp, deadline: None }, config, Instant::now()).unwrap();
    (film, summary)
}

fn bits(f: &Film) -> Vec<u64> {
    f.sums().iter().flatten().map(|v| v.to_bits()).collect()
}

#[test]
fn film_is_bit_identical_for_1_2_and_3_threads() {
    let (f1, s1) = run(1, 6);
    let (f2, s2) = run(2, 6);
    let (f3, s3) = run(3, 6);
    assert_eq!(bits(&f1), bits(&f2));
    assert_eq!(bits(&f1), bits(&f3));
    assert_eq!(f1.discarded(), f2.discarded());
    assert_eq!(f1.discarded(), f3.discarded());
    assert!(f1.discarded() > 0, "the fake renderer emits invalid samples");
    assert_eq!((s1.stats, s2.stats, s3.stats), (s1.stats, s1.stats, s1.stats));
    assert_eq!(s1.stats, PassStats { rays: 6 * (3 * 23 * 17 + 5 * 101), samples: 6 * (23 * 17 + 101) });
    assert_eq!(s1.passes, 6);
    assert!(f1.to_rgb_f32().iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
}

/// The same film, merged as a whole in the driver's order by hand: camera samples,
/// then camera splats, then light splats, each in index order.
#[test]
fn driver_merges_in_pixel_then_path_order() {
    let fake = Fake { w: 23, h: 17, light_paths: 101 };
    let mut film = Film::new(23, 17);
    for pass in 0..2 {
        let mut out = vec![Rgb::ZERO; 23 * 17];
        let mut splats = Vec::new();
        fake.camera_pass(pass, 0..23 * 17, &mut out, &mut |s| splats.push(s));
        fake.light_pass(pass, 0..101, &mut |s| splats.push(s));
        film.add_camera_samples(0..23 * 17, &out);
        film.add_splats(&splats, fake.splat_scale());
        film.end_pass();
    }
    let (driven, _) = run(2, 2);
    assert_eq!(bits(&film), bits(&driven));
}

/// A time budget stops the loop between passes; at least one pass always runs.
#[test]
fn deadline_stops_between_passes() {
    let fake = Fake { w: 8, h: 8, light_paths: 0 };
    let mut film = Film::new(8, 8);
    let config = DriverConfig { threads: 2, pixel_chunk: 16, light_chunk: 16, progress: false };
    let past = Instant::now();
    let limits = Limits { spp: u32::MAX, deadline: Some(past) };
    let s = render(&fake, &mut film, limits, config, past).unwrap();
    assert_eq!(s.passes, 1);
    assert_eq!(film.passes(), 1);

    let mut film = Film::new(8, 8);
    let soon = Instant::now() + Duration::from_millis(50);
    let s = render(&fake, &mut film, Limits { spp: u32::MAX, deadline: Some(soon) }, config, past).unwrap();
    assert!(Instant::now() >= soon);
    assert!(s.passes > 1 && s.passes == film.passes());
}

#[test]
fn resolution_mismatch_is_an_error() {
    let fake = Fake { w: 8, h: 8, light_paths: 0 };
    let mut film = Film::new(8, 9);
    let config = DriverConfig::with_threads(1);
    let r = render(&fake, &mut film, Limits { spp: 1, deadline: None }, config, Instant::now());
    assert!(matches!(r, Err(DriverError::Resolution { .. })));
}
