use super::*;

use crate::cli::{Cli, Command};
use crate::estimators::Render;
use crate::setup::builtin_resolution;
use clap::Parser;
use ember_core::Rgb;
use ember_core::estimators::ChunkOutput;
use ember_core::render::{Context, Cursor, Phase, Phased, Stage};

/// A renderer drawing a horizontal ramp, one ray per sample.
struct Ramp {
    w: u32,
    h: u32,
    cursor: Cursor,
}

impl<Q: ember_core::geometry::RayQuery + ?Sized> Phased<Q> for Ramp {
    type Data = ember_core::estimators::PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        let Some(Stage::Pass(p, _)) = self.cursor.stage() else { return None };
        Some(Phase { name: "camera", id: 0, pass: Some(p), items: self.w * self.h, chunk: 5, samples: true })
    }
    fn start_pass(&mut self, pass: u32) {
        self.cursor.start_pass(pass);
    }
    fn map(&self, _: &Context<'_, Q>, _: &Phase, out: &mut ChunkOutput) {
        for i in out.items.clone() {
            out.pixels.push(Rgb::splat((i % self.w) as f32 / self.w as f32));
            out.counters.rays += 1;
        }
    }
    fn reduce(&mut self, _: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        for out in outputs.iter() {
            film.set_camera_samples(ember_core::camera::CameraPass { seed: 0, pass: phase.pass.unwrap_or(0) }, out.items.clone(), &out.pixels);
        }
        if self.cursor.advance() {
            film.end_pass(1.0);
        }
    }
}

/// The ramp with a scene of its size for the context (which it does not read).
struct RampHost {
    ramp: Ramp,
    scene: ember_core::scene::Scene,
    accel: ember_host::accel::Accel,
}

impl Render for RampHost {
    fn size(&self) -> (u32, u32) {
        (self.ramp.w, self.ramp.h)
    }
    fn render(&mut self, film: &mut Film, limits: Limits, config: DriverConfig, start: Instant) -> Result<RenderSummary, DriverError> {
        let ctx = Context { scene: &self.scene, tracer: &self.accel };
        config.render(&mut self.ramp, &ctx, film, limits, start)
    }
}

fn ramp_host(w: u32, h: u32) -> RampHost {
    let (scene, geometry, _) = ember_core::scene::builtin::cornell_box(w, h).build().expect("built-in scene");
    RampHost { ramp: Ramp { w, h, cursor: Cursor::new(0, 1) }, scene, accel: ember_host::accel::Accel::new(&geometry) }
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
        Ok(Built {
            renderer: Box::new(ramp_host(w, h)),
            scene: "ramp".into(),
            max_depth: -1,
            simd: ember_host::accel::Isa::best(),
            shading: Default::default(),
            file_spp: None,
            film: None,
        })
    })
    .unwrap();
    assert_eq!(report.summary.passes, 3);
    assert_eq!(report.summary.stats.samples, 3 * 32);
    assert_eq!(report.png, Some(temp_dir().join("ramp.png")));
    let img = image_io::read_exr(&out).unwrap();
    assert_eq!((img.width, img.height), (8, 4));
    assert_eq!(img.pixels[8 + 3], [3.0 / 8.0; 3]);
    assert!(report.png.as_ref().is_some_and(|p| p.is_file()));
    let text = report.to_string();
    for word in ["3 (samples per pixel)", "8x4", "max depth -1 (unbounded)", "rays/s", "discarded  0", "ramp.png"] {
        assert!(text.contains(word), "summary lacks {word}:\n{text}");
    }
}

#[test]
fn a_missing_scene_file_is_reported_with_its_name() {
    let e = render(&args(&["no-such-scene.xml"]), Instant::now(), false, crate::setup::make_built).unwrap_err();
    assert!(e.to_string().contains("no-such-scene.xml"), "{e}");
}

#[test]
fn bad_outputs_and_estimator_errors_are_reported() {
    let e = render(&args(&["-o", "/nonexistent-ember-dir/x.exr"]), Instant::now(), false, |_| panic!("must not build")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent-ember-dir"), "{e}");
    let e = render(&args(&["-o", "x.png"]), Instant::now(), false, |_| panic!("must not build")).unwrap_err();
    assert!(e.to_string().contains(".exr"), "{e}");
    let e = render(&args(&[]), Instant::now(), false, |_| Err("no lights".into())).unwrap_err();
    assert_eq!(e.to_string(), "cannot set up the renderer: no lights");
}

/// A film that already holds passes (auto's race, when PT wins: `Built::film`) is
/// continued: the image equals a render of all its passes from scratch, the report
/// counts them all, and only the missing passes are rendered. A film holding more
/// passes than asked for is not used. Seen failing when the driver restarted the pass
/// indices at 0 for a held film (the two held passes' random numbers repeated: the
/// images differ), and when `render` ignored the held film (5 passes' samples drawn).
#[test]
fn a_held_film_is_continued_not_restarted() {
    let dir = temp_dir();
    let render_with = |spp: &str, held: u32, name: &str| {
        let out = dir.join(name);
        let a = args(&["--spp", spp, "--threads", "2", "--width", "16", "--height", "12", "--seed", "7", "-o", out.to_str().unwrap()]);
        let report = render(&a, Instant::now(), false, |a| {
            let mut r = crate::setup::make_core_renderer(a)?;
            let film = (held > 0).then(|| {
                let mut film = Film::with_filter(16, 12, r.camera_filter());
                let limits = Limits { spp: held, deadline: None, interrupt: None, first_pass: 0 };
                r.render(&mut film, limits, DriverConfig { progress: false, ..DriverConfig::with_threads(2) }, Instant::now()).unwrap();
                film
            });
            Ok(Built {
                scene: "box".into(),
                max_depth: -1,
                simd: ember_host::accel::Isa::best(),
                shading: Default::default(),
                file_spp: None,
                renderer: Box::new(r),
                film,
            })
        })
        .unwrap();
        (report, image_io::read_exr(&out).unwrap().pixels)
    };
    let (fresh, fresh_image) = render_with("5", 0, "fresh.exr");
    let (continued, continued_image) = render_with("5", 2, "continued.exr");
    assert_eq!(continued_image, fresh_image);
    assert_eq!((fresh.summary.passes, continued.summary.passes), (5, 5));
    assert_eq!(continued.summary.stats.samples, 3 * 16 * 12, "only the three missing passes are rendered");
    let (fewer, fewer_image) = render_with("1", 2, "fewer.exr");
    let (one, one_image) = render_with("1", 0, "one.exr");
    assert_eq!((fewer.summary.passes, fewer_image), (1, one_image));
    assert_eq!(one.summary.passes, 1);
}
