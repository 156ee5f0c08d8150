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
//!    right now), and the driver's sequential per-pass merge timed alone (the Amdahl
//!    bound it sets).
//!
//! Run: `cargo bench -p ember-cli --bench render_throughput` (1–2.5 minutes on 2 cores,
//! longer while other processes load the machine).

use std::cell::RefCell;
use std::hint::black_box;
use std::ops::Range;
use std::sync::Mutex;
use std::time::Instant;

use clap::Parser;

use ember_cli::accel::Accel;
use ember_cli::cli::{Cli, Command, RenderArgs};
use ember_cli::driver::{self, DriverConfig, Limits, PassRenderer, PassStats, Splat};
use ember_cli::estimators::{CoreRenderer, prepare_builtin};
use ember_cli::film::Film;
use ember_core::Rgb;
use ember_core::geometry::{Ray, RayQuery, SurfaceHit};
use ember_core::integrator::pt;

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
    CoreRenderer::new(prepared, a.estimator, a.max_depth_or(-1), a.seed)
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
        rays += pt::render_pixels(&r.prepared.scene, tracer, &r.params, pass, 0..pixels, out).rays;
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
    println!(
        "[1,2] PT hot loop: Cornell box {HOT_RES}², {HOT_PASSES} passes, unbounded depth, 1 thread, {} triangles",
        accel.triangle_count()
    );
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
    println!(
        "      raw Accel, same rays    {raw:>7.2} Mrays/s  (closest {:.2}, occlusion {:.2})",
        median(c_rate),
        median(s_rate)
    );
    println!(
        "      ratio PT / raw          {:>7.3}   (traversal share of the hot loop, per round: {:.3})",
        pt / raw,
        median(share)
    );
}

/// A `PassRenderer` that does pure arithmetic: the machine's own scaling, right now.
#[derive(Debug)]
struct Spin;

fn spin(seed: u32) -> Rgb {
    let mut x = seed as u64 | 1;
    for _ in 0..600 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
    }
    Rgb::splat((x >> 40) as f32)
}

impl PassRenderer for Spin {
    fn width(&self) -> u32 {
        512
    }
    fn height(&self) -> u32 {
        512
    }
    fn camera_pass(&self, _: u32, pixels: Range<u32>, out: &mut [Rgb], _: &mut dyn FnMut(Splat)) -> PassStats {
        for (o, i) in out.iter_mut().zip(pixels) {
            *o = spin(i);
        }
        PassStats::default()
    }
    fn light_paths_per_pass(&self) -> u32 {
        0
    }
    fn light_pass(&self, _: u32, _: Range<u32>, _: &mut dyn FnMut(Splat)) -> PassStats {
        PassStats::default()
    }
    fn splat_scale(&self) -> f64 {
        1.0
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

/// Logs every work item the driver hands out: (pass, worker, start, end) in seconds.
struct Logged<'a> {
    inner: &'a dyn PassRenderer,
    t0: Instant,
    items: Mutex<Vec<(u32, usize, f64, f64)>>,
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

impl PassRenderer for Logged<'_> {
    fn width(&self) -> u32 {
        self.inner.width()
    }
    fn height(&self) -> u32 {
        self.inner.height()
    }
    fn camera_pass(&self, pass: u32, pixels: Range<u32>, out: &mut [Rgb], splat: &mut dyn FnMut(Splat)) -> PassStats {
        let t = Instant::now();
        let stats = self.inner.camera_pass(pass, pixels, out, splat);
        self.log(pass, t);
        stats
    }
    fn light_paths_per_pass(&self) -> u32 {
        self.inner.light_paths_per_pass()
    }
    fn light_pass(&self, pass: u32, paths: Range<u32>, splat: &mut dyn FnMut(Splat)) -> PassStats {
        let t = Instant::now();
        let stats = self.inner.light_pass(pass, paths, splat);
        self.log(pass, t);
        stats
    }
    fn splat_scale(&self) -> f64 {
        self.inner.splat_scale()
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
}

fn drive(r: &dyn PassRenderer, threads: usize, spp: u32) -> (Run, Film) {
    let logged = Logged { inner: r, t0: Instant::now(), items: Mutex::new(Vec::new()) };
    let mut film = Film::new(r.width(), r.height());
    let config = DriverConfig { progress: false, ..DriverConfig::with_threads(threads) };
    let start = Instant::now();
    let cpu = cpu_seconds();
    let s = driver::render(&logged, &mut film, Limits { spp, deadline: None }, config, start).expect("render");
    let cpu = cpu_seconds() - cpu;
    let (idle, worst_wait) = logged.tail_idle(threads, spp);
    (Run { wall: s.render_seconds, cpu, idle, worst_wait }, film)
}

fn same_bits(a: &Film, b: &Film) -> bool {
    a.passes() == b.passes()
        && a.discarded() == b.discarded()
        && a.sums().iter().flatten().map(|v| v.to_bits()).eq(b.sums().iter().flatten().map(|v| v.to_bits()))
}

/// The driver's merge of one pass on its own: camera samples and splats collected as
/// the driver collects them (chunk by chunk, one thread), then added to a film.
/// Returns (merge seconds, splats per pass).
fn merge_cost(r: &dyn PassRenderer) -> (f64, usize) {
    let config = DriverConfig::with_threads(1);
    let n = (r.width() * r.height()) as usize;
    let mut out = vec![Rgb::ZERO; n];
    let mut chunks: Vec<Vec<Splat>> = Vec::new();
    for (c, o) in out.chunks_mut(config.pixel_chunk as usize).enumerate() {
        let mut s = Vec::new();
        let start = c as u32 * config.pixel_chunk;
        r.camera_pass(0, start..start + o.len() as u32, o, &mut |x| s.push(x));
        chunks.push(s);
    }
    let m = r.light_paths_per_pass();
    for start in (0..m).step_by(config.light_chunk as usize) {
        let mut s = Vec::new();
        r.light_pass(0, start..(start + config.light_chunk).min(m), &mut |x| s.push(x));
        chunks.push(s);
    }
    let mut film = Film::new(r.width(), r.height());
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t = Instant::now();
        film.add_camera_samples(0..n as u32, &out);
        for s in &chunks {
            film.add_splats(s, r.splat_scale());
        }
        film.end_pass();
        best = best.min(t.elapsed().as_secs_f64());
    }
    black_box(&film);
    (best, chunks.iter().map(Vec::len).sum())
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
    println!(
        "    {:<6} {:>7} {:>8} {:>8} {:>6} {:>7} {:>15}   rounds / speedup per round",
        "", "threads", "seconds", "speedup", "cores", "CPU s", "tail idle"
    );

    let mut renderers: Vec<(&str, Box<dyn PassRenderer>)> = vec![("spin", Box::new(Spin))];
    for e in ["pt", "lt", "bdpt"] {
        let spp = SCALE_SPP.to_string();
        let a = args(&["--estimator", e, "--spp", &spp]);
        renderers.push((e, Box::new(default_renderer(&a))));
    }
    for (name, r) in &renderers {
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
                let (run, film) = drive(&**r, counts[k], SCALE_SPP);
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
        // The merge alone, as a share of a 1-thread pass, and the speedups it allows.
        let (merge, splats) = merge_cost(&**r);
        let f = (merge * SCALE_SPP as f64 / of(&|r| r[0].wall)).min(1.0);
        let bounds: Vec<String> =
            counts[1..].iter().map(|&n| format!("{:.2}", 1.0 / (f + (1.0 - f) / n as f64))).collect();
        println!(
            "    {:<6} film bits across thread counts: {}; merge {:.1} ms/pass ({} splats) = {:.1} % of a \
             1-thread pass; Amdahl bound {}",
            "",
            if identical { "identical" } else { "DIFFER" },
            merge * 1e3,
            splats,
            100.0 * f,
            bounds.join(" / ")
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
