use super::*;

use crate::cli::{Cli, Command};
use crate::driver::{PassStats, Splat};
use clap::Parser;
use ember_core::Rgb;

/// A renderer drawing a horizontal ramp, one ray per sample.
struct Ramp {
    w: u32,
    h: u32,
}

impl PassRenderer for Ramp {
    fn width(&self) -> u32 {
        self.w
    }
    fn height(&self) -> u32 {
        self.h
    }
    fn camera_pass(
        &self,
        _: u32,
        pixels: core::ops::Range<u32>,
        out: &mut [Rgb],
        _: &mut dyn FnMut(Splat),
    ) -> PassStats {
        for (i, o) in pixels.clone().zip(out.iter_mut()) {
            *o = Rgb::splat((i % self.w) as f32 / self.w as f32);
        }
        PassStats { rays: pixels.len() as u64, samples: pixels.len() as u64 }
    }
    fn light_paths_per_pass(&self) -> u32 {
        0
    }
    fn light_pass(&self, _: u32, _: core::ops::Range<u32>, _: &mut dyn FnMut(Splat)) -> PassStats {
        PassStats::default()
    }
    fn splat_scale(&self) -> f64 {
        1.0
    }
}

fn args(extra: &[&str]) -> RenderArgs {
    let mut v = vec!["ember", "render"];
    v.extend_from_slice(extra);
    match Cli::parse_from(v).command {
        Command::Render(r) => r,
        other => panic!("expected render, got {other:?}"),
    }
}

fn temp_dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("ember-cli-app-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn render_writes_exr_and_png_and_reports() {
    let out = temp_dir().join("ramp.exr");
    let a = args(&["--spp", "3", "--threads", "2", "--width", "8", "--height", "4", "-o", out.to_str().unwrap()]);
    let report = render(&a, Instant::now(), false, |a| {
        let (w, h) = builtin_resolution(a);
        Ok(Built { renderer: Box::new(Ramp { w, h }), scene: "ramp".into(), max_depth: -1, file_spp: None })
    })
    .unwrap();
    assert_eq!(report.summary.passes, 3);
    assert_eq!(report.summary.stats.samples, 3 * 32);
    assert_eq!(report.png, temp_dir().join("ramp.png"));
    let img = image_io::read_exr(&out).unwrap();
    assert_eq!((img.width, img.height), (8, 4));
    assert_eq!(img.pixels[8 + 3], [3.0 / 8.0; 3]);
    assert!(report.png.is_file());
    let text = report.to_string();
    for word in ["3 (samples per pixel)", "8x4", "max depth -1 (unbounded)", "rays/s", "discarded  0", "ramp.png"] {
        assert!(text.contains(word), "summary lacks {word}:\n{text}");
    }
}

#[test]
fn a_missing_scene_file_is_reported_with_its_name() {
    let e = render(&args(&["no-such-scene.xml"]), Instant::now(), false, crate::estimators::make_built).unwrap_err();
    assert!(e.to_string().contains("no-such-scene.xml"), "{e}");
}

#[test]
fn bad_outputs_and_estimator_errors_are_reported() {
    let e = render(&args(&["-o", "/nonexistent-ember-dir/x.exr"]), Instant::now(), false, |_| panic!("must not build"))
        .unwrap_err();
    assert!(e.to_string().contains("/nonexistent-ember-dir"), "{e}");
    let e = render(&args(&["-o", "x.png"]), Instant::now(), false, |_| panic!("must not build")).unwrap_err();
    assert!(e.to_string().contains(".exr"), "{e}");
    let e = render(&args(&[]), Instant::now(), false, |_| Err("no lights".into())).unwrap_err();
    assert_eq!(e.to_string(), "cannot set up the renderer: no lights");
}
