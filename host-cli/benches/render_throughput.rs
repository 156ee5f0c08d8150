//! Render throughput on the default scene (the built-in Cornell box): how fast the path
//! tracer's hot loop runs against how fast the same rays traverse the `Accel` alone,
//! and how the full driver scales with threads. Results and their reading are in
//! `docs/performance.md`.
//!
//! 1. **PT hot loop**: `pt::render_pixels` over every pixel of a 256² image, unbounded
//!    depth, `HOT_PASSES` passes, one thread, no driver; rays/s = the estimator's own
//!    ray count (closest hit + shadow) / seconds.
//! 2. **Raw traversal of the same rays**: one untimed run of the same passes through a
//!    recording `RayQuery` that keeps every ray given to `intersect` and to `occluded`;
//!    then exactly those rays are traced through the `Accel` alone, one thread
//!    (closest hit for the first list, occlusion for the second). The ratio
//!    PT rays/s ÷ raw rays/s is the share of the hot loop's time spent in ray queries.
//!    Parts 1 and 2 alternate `HOT_REPS` times; medians are printed.
//! 3. **Thread scaling**: the full driver (`driver::render`, progress off) on the
//!    default scene exactly as `ember render` builds it (512², unbounded depth, seed 0),
//!    `SCALE_SPP` passes, for pt, lt and bdpt, with 1, 2 (and all, if more) threads.
//!    Each round runs every thread count back to back, in alternating order, and the
//!    speedup t₁ / tₙ is taken within the round. The machine is shared, so each render
//!    also reports the cores it actually got (process CPU seconds ÷ wall seconds, from
//!    `/proc/self/stat`); a round counts as clean when every render got at least
//!    `CLEAN_SHARE` of the cores it asked for. Rounds run until `SCALE_ROUNDS` are
//!    clean (at most `SCALE_MAX_ROUNDS`); medians are over the clean rounds (over all,
//!    flagged CONTENDED, when none was). The films of all thread counts are compared
//!    bit for bit. Every work item (chunk) the driver hands out is logged with its
//!    worker and times, giving the end-of-pass idle time ("tail idle": workers waiting
//!    for a pass's last chunk, as a share of worker time, and the longest wait), a
//!    number that other processes on the machine hardly move. Two controls frame the
//!    speedups: the same driver over pure arithmetic (`spin`: what the machine gives
//!    right now), and the reductions (the per-pass merge) timed within the runs: at one
//!    thread, with the Amdahl bound they would set if they stayed serial, and at every
//!    thread count (the splat commit runs on the pool since issue 24's second session).
//!
//! Run: `cargo bench -p ember-cli --bench render_throughput` (1–2.5 minutes on 2 cores,
//! longer while other processes load the machine).

use std::cell::RefCell;
use std::hint::black_box;
use std::sync::Mutex;
use std::time::Instant;

use clap::Parser;

use ember_cli::cli::{Cli, Command, RenderArgs};
use ember_cli::estimators::CoreRenderer;
use ember_cli::setup::prepare_builtin;
use ember_core::Rgb;
use ember_core::estimators::pt;
use ember_core::estimators::{ChunkOutput, PhaseData};
use ember_core::geometry::{Ray, RayQuery, SurfaceHit};
use ember_core::render::{Context, Cursor, Film, Phase, Phased, Stage};
use ember_host::accel::Accel;
use ember_host::driver::{self, Limits};
use ember_host::scene::PreparedScene;

const HOT_RES: u32 = 256;
const HOT_PASSES: u32 = 4;
const HOT_REPS: usize = 5;
const SCALE_SPP: u32 = 1;
const SCALE_ROUNDS: usize = 5;
/// Rounds tried at most to collect `SCALE_ROUNDS` clean ones.
const SCALE_MAX_ROUNDS: usize = 8;
/// A round is clean when each render's process CPU ÷ wall time reaches this share of
/// its thread count (other processes took little of the cores meanwhile).
const CLEAN_SHARE: f64 = 0.85;

/// `ember render` options, parsed as the binary parses them.
fn args(extra: &[&str]) -> RenderArgs {
    let mut v = vec!["ember", "render"];
    v.extend_from_slice(extra);
    let Command::Render(a) = Cli::parse_from(v).command else { unreachable!("parsed a render command") };
    a
}

/// The built-in scene and estimator as `ember render` (no scene file) builds them.
fn default_renderer(a: &RenderArgs) -> CoreRenderer {
    let prepared = prepare_builtin(a).expect("built-in scene");
    let ember_cli::cli::EstimatorChoice::Fixed(kind) = a.estimator else { unreachable!("the benchmark names its estimator") };
    CoreRenderer::new(prepared, kind, a.max_depth_or(-1), a.seed).expect("renderer")
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// Forwards to the `Accel` and keeps every query ray.
struct Recorder<'a> {
    accel: &'a Accel,
    closest: RefCell<Vec<Ray>>,
    shadow: RefCell<Vec<Ray>>,
}

impl RayQuery for Recorder<'_> {
    fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.closest.borrow_mut().push(*ray);
        self.accel.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.shadow.borrow_mut().push(*ray);
        self.accel.occluded(ray)
    }
}

/// The PT passes over the whole image, one thread: (rays counted, seconds).
fn pt_passes<Q: RayQuery + ?Sized>(r: &CoreRenderer, tracer: &Q, out: &mut [Rgb]) -> (u64, f64) {
    let pixels = out.len() as u32;
    let t = Instant::now();
    let mut rays = 0;
    for pass in 0..HOT_PASSES {
        rays += pt::render_pixels(&r.prepared.scene, tracer, r.renderer.params(), pass, 0..pixels, out).rays;
        black_box(&mut *out);
    }
    (rays, t.elapsed().as_secs_f64())
}

fn hot_loop() {
    let res = HOT_RES.to_string();
    let a = args(&["--estimator", "pt", "--width", &res, "--height", &res, "--max-depth", "-1"]);
    let r = default_renderer(&a);
    let accel = &r.prepared.accel;
    let mut out = vec![Rgb::ZERO; (HOT_RES * HOT_RES) as usize];

    // Record the rays of exactly the passes timed below.
    let rec = Recorder { accel, closest: RefCell::new(Vec::new()), shadow: RefCell::new(Vec::new()) };
    let (counted, _) = pt_passes(&r, &rec, &mut out);
    let (closest, shadow) = (rec.closest.into_inner(), rec.shadow.into_inner());
    let total = (closest.len() + shadow.len()) as u64;
    assert_eq!(counted, total, "the estimator's ray count disagrees with the queries it made");
    println!("[1,2] PT hot loop: Cornell box {HOT_RES}², {HOT_PASSES} passes, unbounded depth, 1 thread, {} triangles", accel.triangle_count());
    println!(
        "      {} rays = {} closest-hit + {} shadow ({:.2} rays per pixel sample)",
        total,
        closest.len(),
        shadow.len(),
        total as f64 / (HOT_PASSES * HOT_RES * HOT_RES) as f64
    );

    let (mut pt_rate, mut raw_rate, mut c_rate, mut s_rate, mut share) = (vec![], vec![], vec![], vec![], vec![]);
    for _ in 0..HOT_REPS {
        let (rays, t_pt) = pt_passes(&r, accel, &mut out);
        assert_eq!(rays, total);
        let t = Instant::now();
        let hits = closest.iter().filter(|ray| accel.intersect(black_box(ray)).is_some()).count();
        let t_c = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let blocked = shadow.iter().filter(|ray| accel.occluded(black_box(ray))).count();
        let t_s = t.elapsed().as_secs_f64();
        black_box((hits, blocked));
        pt_rate.push(total as f64 / t_pt / 1e6);
        raw_rate.push(total as f64 / (t_c + t_s) / 1e6);
        c_rate.push(closest.len() as f64 / t_c / 1e6);
        s_rate.push(shadow.len() as f64 / t_s / 1e6);
        share.push((t_c + t_s) / t_pt);
    }
    let pt = median(pt_rate);
    let raw = median(raw_rate);
    println!("      median of {HOT_REPS} (PT and raw alternating):");
    println!("      PT hot loop             {pt:>7.2} Mrays/s");
    println!("      raw Accel, same rays    {raw:>7.2} Mrays/s  (closest {:.2}, occlusion {:.2})", median(c_rate), median(s_rate));
    println!("      ratio PT / raw          {:>7.3}   (traversal share of the hot loop, per round: {:.3})", pt / raw, median(share));
}

/// A renderer that does pure arithmetic: the machine's own scaling, right now.
#[derive(Debug)]
struct Spin {
    cursor: Cursor,
}

fn spin(seed: u32) -> Rgb {
    let mut x = seed as u64 | 1;
    for _ in 0..600 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
    }
    Rgb::splat((x >> 40) as f32)
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Spin {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        let Some(Stage::Pass(p, _)) = self.cursor.stage() else { return None };
        Some(Phase { name: "camera", id: 0, pass: Some(p), items: 512 * 512, chunk: 1024, samples: true })
    }
    fn start_pass(&mut self, pass: u32) {
        self.cursor.start_pass(pass);
    }
    fn map(&self, _: &Context<'_, Q>, _: &Phase, out: &mut ChunkOutput) {
        for i in out.items.clone() {
            out.pixels.push(spin(i));
        }
    }
    fn reduce(&mut self, _: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        for o in outputs.iter() {
            film.set_camera_samples(ember_core::camera::CameraPass { seed: 0, pass: phase.pass.unwrap_or(0) }, o.items.clone(), &o.pixels);
        }
        if self.cursor.advance() {
            film.end_pass(1.0);
        }
    }
}

/// CPU seconds this process has used (user + system, all threads), from
/// `/proc/self/stat` in 10 ms ticks; 0 where unavailable.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat.rsplit_once(')').map_or("", |(_, f)| f).split_whitespace().collect();
    let tick = |i: usize| fields.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (tick(11) + tick(12)) / 100.0
}

/// Logs every work item (chunk) the driver hands out, (pass, worker, start, end) in
/// seconds, and times the reductions (the serial merge of each phase).
/// Any estimator the bench drives, behind one pointer.
type DynRenderer = dyn Phased<ember_host::accel::Accel, Data = PhaseData> + Sync + Send;

struct Logged<'a> {
    inner: &'a mut DynRenderer,
    t0: Instant,
    items: Mutex<Vec<(u32, usize, f64, f64)>>,
    reduce_seconds: f64,
}

impl Logged<'_> {
    fn log(&self, pass: u32, start: Instant) {
        let worker = rayon::current_thread_index().unwrap_or(0);
        let (a, b) = ((start - self.t0).as_secs_f64(), self.t0.elapsed().as_secs_f64());
        self.items.lock().map(|mut v| v.push((pass, worker, a, b))).ok();
    }

    /// Worker time lost at the ends of passes: for each pass, every worker's wait from its
    /// last item to the pass's last item (while the driver still has work in flight),
    /// as a share of `threads` × the passes' spans; and the longest such wait (seconds).
    fn tail_idle(&self, threads: usize, passes: u32) -> (f64, f64) {
        let items = self.items.lock().map(|v| v.clone()).unwrap_or_default();
        let (mut idle, mut span, mut worst) = (0.0, 0.0, 0.0f64);
        for pass in 0..passes {
            let of_pass = || items.iter().filter(move |e| e.0 == pass);
            let start = of_pass().map(|e| e.2).fold(f64::INFINITY, f64::min);
            let end = of_pass().map(|e| e.3).fold(f64::NEG_INFINITY, f64::max);
            if end.is_nan() || end <= start {
                continue;
            }
            span += end - start;
            for w in 0..threads {
                let wait = end - of_pass().filter(|e| e.1 == w).map(|e| e.3).fold(start, f64::max);
                idle += wait;
                worst = worst.max(wait);
            }
        }
        (if span > 0.0 { idle / (threads as f64 * span) } else { 0.0 }, worst)
    }
}

impl Phased<ember_host::accel::Accel> for Logged<'_> {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        self.inner.next_phase()
    }
    fn start_pass(&mut self, pass: u32) {
        self.inner.start_pass(pass);
    }
    fn map(&self, ctx: &Context<'_, ember_host::accel::Accel>, phase: &Phase, out: &mut ChunkOutput) {
        let t = Instant::now();
        self.inner.map(ctx, phase, out);
        self.log(phase.pass.unwrap_or(0), t);
    }
    fn reduce(&mut self, ctx: &Context<'_, ember_host::accel::Accel>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        let t = Instant::now();
        self.inner.reduce(ctx, phase, outputs, film);
        self.reduce_seconds += t.elapsed().as_secs_f64();
    }
}

/// One render through the driver.
#[derive(Clone, Copy, Debug, Default)]
struct Run {
    /// Wall seconds of the pass loop.
    wall: f64,
    /// Process CPU seconds meanwhile.
    cpu: f64,
    /// End-of-pass idle share and longest wait (seconds), see [`Logged::tail_idle`].
    idle: f64,
    worst_wait: f64,
    /// Seconds of reductions (serial merges) per pass.
    merge: f64,
}

fn drive(r: &mut DynRenderer, scene: &PreparedScene, threads: usize, spp: u32) -> (Run, Film) {
    let mut logged = Logged { inner: r, t0: Instant::now(), items: Mutex::new(Vec::new()), reduce_seconds: 0.0 };
    let camera = &scene.scene.camera;
    let mut film = Film::new(camera.width(), camera.height());
    let ctx = Context { scene: &scene.scene, tracer: &scene.accel };
    let start = Instant::now();
    let cpu = cpu_seconds();
    let s = driver::render(&mut logged, &ctx, &mut film, Limits { spp, deadline: None, interrupt: None, first_pass: 0 }, threads, None, start).expect("render");
    let cpu = cpu_seconds() - cpu;
    let (idle, worst_wait) = logged.tail_idle(threads, spp);
    (Run { wall: s.render_seconds, cpu, idle, worst_wait, merge: logged.reduce_seconds / spp.max(1) as f64 }, film)
}

fn same_bits(a: &Film, b: &Film) -> bool {
    a.passes() == b.passes()
        && a.discarded() == b.discarded()
        && a.sums().iter().flatten().map(|v| v.to_bits()).eq(b.sums().iter().flatten().map(|v| v.to_bits()))
}

fn scaling() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut counts = vec![1, 2];
    if cores > 2 {
        counts.push(cores);
    }
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!();
    println!(
        "[3] driver scaling: default scene (512², unbounded depth, seed 0), {SCALE_SPP} pass(es) per render, \
         medians over clean rounds; {cores} cores; load average before: {}",
        load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
    );
    println!("    {:<6} {:>7} {:>8} {:>8} {:>6} {:>7} {:>15}   rounds / speedup per round", "", "threads", "seconds", "speedup", "cores", "CPU s", "tail idle");

    let scene = prepare_builtin(&args(&[])).expect("built-in scene");
    let mut renderers: Vec<(&str, Box<DynRenderer>)> = vec![("spin", Box::new(Spin { cursor: Cursor::new(0, 1) }))];
    for e in ["pt", "lt", "bdpt"] {
        let spp = SCALE_SPP.to_string();
        let a = args(&["--estimator", e, "--spp", &spp]);
        renderers.push((e, Box::new(default_renderer(&a).renderer)));
    }
    for (name, r) in &mut renderers {
        // Per round, per thread count.
        let (mut clean, mut all): (Vec<Vec<Run>>, Vec<Vec<Run>>) = (Vec::new(), Vec::new());
        let mut identical = true;
        let mut reference: Option<Film> = None;
        while clean.len() < SCALE_ROUNDS && all.len() < SCALE_MAX_ROUNDS {
            let mut order: Vec<usize> = (0..counts.len()).collect();
            if all.len() % 2 == 1 {
                order.reverse();
            }
            let mut round = vec![Run::default(); counts.len()];
            for k in order {
                let (run, film) = drive(&mut **r, &scene, counts[k], SCALE_SPP);
                round[k] = run;
                match &reference {
                    None => reference = Some(film),
                    Some(f) => identical &= same_bits(f, &film),
                }
            }
            // Clean: every render got nearly all the cores it asked for.
            if counts.iter().zip(&round).all(|(&n, run)| run.cpu / run.wall >= CLEAN_SHARE * n as f64) {
                clean.push(round.clone());
            }
            all.push(round);
        }
        let (rounds, note) = match clean.len() {
            0 => (&all, format!("CONTENDED: no clean round in {}", all.len())),
            c => (&clean, format!("{c} clean of {} rounds", all.len())),
        };
        let of = |f: &dyn Fn(&[Run]) -> f64| median(rounds.iter().map(|r| f(r)).collect());
        for (k, &n) in counts.iter().enumerate() {
            let per_round: Vec<String> = rounds.iter().map(|r| format!("{:.2}", r[0].wall / r[k].wall)).collect();
            let idle = format!("{:.1} % {:>3.0} ms", 100.0 * of(&|r| r[k].idle), 1e3 * of(&|r| r[k].worst_wait));
            println!(
                "    {:<6} {:>7} {:>8.3} {:>8.2} {:>6.2} {:>7.2} {:>15}   {}",
                if k == 0 { *name } else { "" },
                n,
                of(&|r| r[k].wall),
                of(&|r| r[0].wall / r[k].wall),
                of(&|r| r[k].cpu / r[k].wall),
                of(&|r| r[k].cpu),
                if k == 0 { String::new() } else { idle },
                if k == 0 { note.clone() } else { per_round.join(" ") },
            );
        }
        // The reductions alone (the serial merge), as a share of a 1-thread pass, and the
        // speedups it allows.
        let merge = of(&|r| r[0].merge);
        let f = (merge * SCALE_SPP as f64 / of(&|r| r[0].wall)).min(1.0);
        let bounds: Vec<String> = counts[1..].iter().map(|&n| format!("{:.2}", 1.0 / (f + (1.0 - f) / n as f64))).collect();
        // Since the splat commit runs on the pool (Film::set_parallel_splats), the
        // reductions shrink with threads: the bound above assumes they stay serial.
        let merges: Vec<String> = (0..counts.len()).map(|k| format!("{:.1}", 1e3 * of(&|r| r[k].merge))).collect();
        println!(
            "    {:<6} film bits across thread counts: {}; merge {:.1} ms/pass = {:.1} % of a \
             1-thread pass; Amdahl bound if serial {}; merge ms/pass at {} threads: {}",
            "",
            if identical { "identical" } else { "DIFFER" },
            merge * 1e3,
            100.0 * f,
            bounds.join(" / "),
            counts.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(" / "),
            merges.join(" / ")
        );
    }
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("    load average after: {}", load.split_whitespace().take(3).collect::<Vec<_>>().join(" "));
}

fn main() {
    let t = Instant::now();
    hot_loop();
    scaling();
    println!("\ntotal {:.1} s", t.elapsed().as_secs_f64());
}
