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

/// Work standing in for path tracing, so that chunks overlap in time on several
/// threads and finish out of order (without it one thread may finish every chunk before
/// the others wake up, and a merge in completion order would go unnoticed).
fn busy_work(s: &mut SampleStream) {
    let mut acc = 0u64;
    for _ in 0..400 {
        acc = acc.wrapping_add(s.next_u64());
    }
    std::hint::black_box(acc);
    s.set_dimension(0);
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
            busy_work(&mut s);
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
            busy_work(&mut s);
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
    let fake = Fake { w: 61, h: 47, light_paths: 1001 };
    let mut film = Film::new(61, 47);
    let config = DriverConfig { threads, pixel_chunk: 13, light_chunk: 7, progress: false };
    let summary = render(&fake, &mut film, Limits { spp, deadline: None }, config, Instant::now()).unwrap();
    (film, summary)
}

/// Panics naming the first value whose bits differ.
fn assert_same_bits(a: &Film, b: &Film, what: &str) {
    let (a, b) = (a.sums(), b.sums());
    assert_eq!(a.len(), b.len());
    let bits = |v: &[f64; 3]| v.map(f64::to_bits);
    if let Some(i) = (0..a.len()).find(|&i| bits(&a[i]) != bits(&b[i])) {
        panic!("{what}: pixel {i} differs: {:?} vs {:?}", a[i], b[i]);
    }
}

/// Seen to fail (with the next test) when the driver was made to merge splats in
/// completion order through a shared `Mutex<Vec<Splat>>`.
#[test]
fn film_is_bit_identical_for_1_2_and_3_threads() {
    let (f1, s1) = run(1, 6);
    let (f2, s2) = run(2, 6);
    let (f3, s3) = run(3, 6);
    assert_same_bits(&f1, &f2, "1 vs 2 threads");
    assert_same_bits(&f1, &f3, "1 vs 3 threads");
    assert_eq!(f1.discarded(), f2.discarded());
    assert_eq!(f1.discarded(), f3.discarded());
    assert!(f1.discarded() > 0, "the fake renderer emits invalid samples");
    assert_eq!((s1.stats, s2.stats, s3.stats), (s1.stats, s1.stats, s1.stats));
    assert_eq!(s1.stats, PassStats { rays: 6 * (3 * 61 * 47 + 5 * 1001), samples: 6 * (61 * 47 + 1001) });
    assert_eq!(s1.passes, 6);
    assert!(f1.to_rgb_f32().iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
}

/// The same film, merged as a whole in the driver's order by hand: camera samples,
/// then camera splats, then light splats, each in index order.
#[test]
fn driver_merges_in_pixel_then_path_order() {
    let fake = Fake { w: 61, h: 47, light_paths: 1001 };
    let mut film = Film::new(61, 47);
    for pass in 0..2 {
        let mut out = vec![Rgb::ZERO; 61 * 47];
        let mut splats = Vec::new();
        fake.camera_pass(pass, 0..61 * 47, &mut out, &mut |s| splats.push(s));
        fake.light_pass(pass, 0..1001, &mut |s| splats.push(s));
        film.add_camera_samples(0..61 * 47, &out);
        film.add_splats(&splats, fake.splat_scale());
        film.end_pass();
    }
    let (driven, _) = run(2, 2);
    assert_same_bits(&film, &driven, "by hand vs driven");
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
