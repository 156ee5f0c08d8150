//! Native checks of what the module does, against the CLI: the browser test
//! (scripts/test-browser.sh) checks the same in a real browser, these catch a broken
//! protocol or ray-query structure in seconds and without one.
//!
//! Injected bugs these tests were seen to catch:
//! * splat scale 1/(W·H) dropped in `Renderer::render` (scale = 1) →
//!   `page_protocol_matches_the_cli_film` fails (cornell lt: mean 123 against 0.12);
//! * barycentrics of the closest hit replaced by (⅓, ⅓, ⅓) in `accel.rs` →
//!   `page_protocol_matches_the_cli_film` fails (cornell pt: 974 of 1024 pixels differ);
//! * band end off by one (`p0..p1 - 1` in `render_like_the_page`) →
//!   `bands_do_not_change_the_image` fails (4 pixels differ);
//! * PFM rows written top to bottom (no flip) → `pfm_round_trip_keeps_rows_in_place` fails;
//! * the block z-test's standard error taken from both images (hot pixels widen their
//!   own bound: |z| 2.3) → the hot-pixel case of
//!   `compare_rejects_blank_nan_and_biased_images` fails; hence the native image's only.

use std::time::Instant;

use ember_cli::cli::{Cli, Command, EstimatorKind, RenderArgs};
use ember_cli::driver::{DriverConfig, Limits};
use ember_cli::estimators::{CoreRenderer, prepare_builtin};
use ember_cli::film::Film;

use crate::Renderer;
use crate::compare::{Criteria, LinearImage, compare, parse_pfm};
use crate::page::PageFilm;

fn args(extra: &[&str]) -> RenderArgs {
    let mut v = vec!["ember", "render"];
    v.extend_from_slice(extra);
    match clap::Parser::parse_from(v) {
        Cli { command: Command::Render(r), .. } => r,
        _ => panic!("expected render"),
    }
}

const SIZE: u32 = 32;
const PASSES: u32 = 2;
const SEED: u64 = 11;

/// Render as the page does: `bands` workers, each a band of pixels and of light paths;
/// the page's film (the core's) stages every band's camera values, then every band's
/// splats in band order, and commits the pass with the renderer's splat scale.
fn render_like_the_page(scene: u32, estimator: u32, bands: u32) -> LinearImage {
    let mut r = Renderer::new(scene, estimator, SIZE, SIZE, -1, SEED).expect("setup");
    let mut film = PageFilm::new(SIZE, SIZE).expect("film");
    let n = SIZE * SIZE;
    let paths = r.light_paths_per_pass();
    let cut = |total: u32, k: u32| (total as u64 * k as u64 / bands as u64) as u32;
    for pass in 0..PASSES {
        let mut splats: Vec<Vec<f32>> = Vec::new();
        for k in 0..bands {
            let (p0, p1) = (cut(n, k), cut(n, k + 1));
            r.render(pass, p0..p1, cut(paths, k)..cut(paths, k + 1)).expect("render");
            film.camera(p0, r.camera_values());
            splats.push(r.splat_values().to_vec());
        }
        for s in &splats {
            film.splats(s);
        }
        film.film.end_pass(r.splat_scale());
    }
    let pixels = film.image().chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    LinearImage { width: SIZE as usize, height: SIZE as usize, pixels }
}

/// The CLI's render of the same scene (its CWBVH, its driver and film).
fn render_with_the_cli(scene: &str, estimator: EstimatorKind) -> LinearImage {
    let size = SIZE.to_string();
    let a = args(&["--builtin", scene, "--width", &size, "--height", &size]);
    let prepared = prepare_builtin(&a).expect("scene");
    let mut renderer = CoreRenderer::new(prepared, estimator, -1, SEED).expect("renderer");
    let mut film = Film::new(SIZE, SIZE);
    let config = DriverConfig { progress: false, ..DriverConfig::with_threads(2) };
    renderer.render(&mut film, Limits { spp: PASSES, deadline: None, interrupt: None, first_pass: 0 }, config, Instant::now()).expect("render");
    LinearImage { width: SIZE as usize, height: SIZE as usize, pixels: film.to_rgb_f32() }
}

#[test]
fn page_protocol_matches_the_cli_film() {
    let estimators = [(0, EstimatorKind::Pt), (1, EstimatorKind::Lt), (2, EstimatorKind::Bdpt)];
    for (scene, name) in crate::SCENES.iter().enumerate() {
        for &(e, arg) in &estimators {
            let page = render_like_the_page(scene as u32, e, 3);
            let cli = render_with_the_cli(name, arg);
            let v = compare(&page, &cli, Criteria::default());
            eprintln!("{name} / {arg:?}: {}", v.report.replace('\n', "; "));
            assert!(v.ok, "{name} / {arg:?}:\n{}", v.report);
        }
    }
}

#[test]
fn bands_do_not_change_the_image() {
    for e in 0..3 {
        let one = render_like_the_page(1, e, 1);
        let five = render_like_the_page(1, e, 5);
        // The film reduces in pixel and light-path order whatever the bands: the same bits.
        assert!(
            five.pixels.iter().flatten().map(|v| v.to_bits()).eq(one.pixels.iter().flatten().map(|v| v.to_bits())),
            "estimator {e}: bands changed the image"
        );
    }
}

#[test]
fn pfm_round_trip_keeps_rows_in_place() {
    // Written the way www/main.js writes it: header, then rows bottom to top, LE f32.
    let (w, h) = (3usize, 2usize);
    let pixels: Vec<[f32; 3]> = (0..w * h).map(|i| [i as f32, 10.0 + i as f32, -(i as f32)]).collect();
    let mut bytes = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    for y in (0..h).rev() {
        for x in 0..w {
            for c in pixels[y * w + x] {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let img = parse_pfm(&bytes).expect("parses");
    assert_eq!((img.width, img.height), (w, h));
    assert_eq!(img.pixels, pixels);
    assert!(parse_pfm(&bytes[..bytes.len() - 1]).is_err(), "truncated data is an error");
}

#[test]
fn compare_rejects_blank_nan_and_biased_images() {
    let good = render_like_the_page(0, 0, 1);
    assert!(compare(&good, &good, Criteria::default()).ok);
    let blank = LinearImage { pixels: vec![[0.0; 3]; good.pixels.len()], ..good.clone() };
    assert!(!compare(&blank, &good, Criteria::default()).ok);
    let mut nan = good.clone();
    nan.pixels[5][1] = f32::NAN;
    assert!(!compare(&nan, &good, Criteria::default()).ok);
    let mut brighter = good.clone();
    for p in &mut brighter.pixels[..64] {
        p[0] *= 1.01;
    }
    assert!(!compare(&brighter, &good, Criteria::default()).ok);
    // Few pixels (within the 1 % allowance), but far off: the block z-test catches it.
    let mut hot = good.clone();
    for i in [0, 1, 2, 32, 33] {
        hot.pixels[i] = [50.0; 3];
    }
    let v = compare(&hot, &good, Criteria::default());
    assert!(!v.ok && v.pixels_differing <= 10 && v.worst_z > v.critical_z, "{}", v.report);
}
