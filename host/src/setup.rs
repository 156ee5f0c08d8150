//! From a prepared scene and an estimator's configuration to a renderer ready for its
//! passes, the way every host that renders a scene file does it: the command line and
//! the Python package share these steps, so the same arguments give the same bits.
//!
//! 1. the configuration checked ([`check_config`]) before anything is estimated from it;
//! 2. the scene plan ([`plan_for`], its pilot mapped on threads where SPCBPT's decision
//!    needs one), unless the host asks to keep every technique;
//! 3. the memory check ([`check_memory`]);
//! 4. the core's renderer with the hosts' parameters ([`new_renderer`]: PT's power
//!    heuristic), its setup phases run ([`crate::driver::run_setup`]), and the kernel
//!    radius it chose checked against the scene's size ([`check_radius`]);
//! 5. the passes: [`pass_limit`] of them, or until a time budget.
//!
//! Messages are plain text naming the option (`--memory-limit`, `--radius 10`) as the
//! command line spells it.

use ember_core::estimators::{EstimatorConfig, Renderer};
use ember_core::math::simd::Level;
use ember_core::merge::RadiusRule;
use ember_core::plan::{PilotStats, Plan, SceneFacts, pilot};
use ember_core::render::Context;
use ember_core::scene::Scene;
use ember_core::transport::{Heuristic, MaxDepth, RenderParams};
use rayon::prelude::*;

use crate::scene::PreparedScene;

/// Passes rendered when neither a pass count nor a time budget is given and the scene
/// file gives no `sample_count` (pbrt's default; the built-in scenes always use it).
pub const DEFAULT_SPP: u32 = 16;

/// The passes a render asks for: `spp` where given, else unlimited under a time budget,
/// else the scene file's `sample_count`, else [`DEFAULT_SPP`].
pub fn pass_limit(spp: Option<u32>, time: Option<f64>, file_spp: Option<u32>) -> u32 {
    match (spp, time, file_spp) {
        (Some(n), _, _) => n,
        (None, Some(_), _) => u32::MAX,
        (None, None, Some(n)) => n,
        (None, None, None) => DEFAULT_SPP,
    }
}

/// The longest time budget: ten years (a larger `--time 1e300` overflowed `Instant`'s
/// arithmetic and panicked after the scene had loaded).
pub const MAX_SECONDS: f64 = 10.0 * 365.0 * 86400.0;

/// A time budget in seconds, checked: positive, finite and at most [`MAX_SECONDS`]; the
/// message shows it as `given` (the text the user typed).
pub fn check_seconds(v: f64, given: impl core::fmt::Display) -> Result<f64, String> {
    if v.is_finite() && v > 0.0 && v <= MAX_SECONDS {
        Ok(v)
    } else {
        Err(format!("the time budget must be positive and at most {MAX_SECONDS} seconds (ten years), got {given}"))
    }
}

/// The render parameters every host uses: PT combines its two techniques with the power
/// heuristic (as Mitsuba does); BDPT's weights are the balance heuristic by construction.
/// `simd` is the level the lane kernels run with (`Accel::shading_level`).
pub fn render_params(max_depth: i32, seed: u64, simd: Level) -> RenderParams {
    RenderParams { max_depth: MaxDepth(max_depth), seed, heuristic: Heuristic::Power, simd, ..RenderParams::default() }
}

/// `config` validated, the message naming the estimator and the option (`bpf beta = -1
/// is outside its allowed range 0 to 16`). Options are checked before anything is
/// estimated from them (an out-of-range subspace count was reported as too much memory).
pub fn check_config(config: &EstimatorConfig) -> Result<(), String> {
    config.validate().map_err(|e| format!("{} {e}", config.kind()))
}

/// Pilot samples per rayon task.
const PILOT_CHUNK: u32 = 256;

/// Run `samples` pilot samples on `threads` threads (the counts do not depend on them).
pub fn run_pilot(prepared: &PreparedScene, max_depth: i32, seed: u64, samples: u32, threads: usize) -> Result<PilotStats, String> {
    let params = render_params(max_depth, seed, prepared.accel.shading_level());
    let ctx = Context { scene: &prepared.scene, tracer: &prepared.accel };
    let pool = crate::driver::thread_pool(threads, "ember-pilot").map_err(|e| e.to_string())?;
    let chunks = samples.div_ceil(PILOT_CHUNK);
    let parts: Vec<PilotStats> = pool.install(|| {
        (0..chunks)
            .into_par_iter()
            .map(|c| {
                let range = c * PILOT_CHUNK..((c + 1) * PILOT_CHUNK).min(samples);
                pilot::map(&ctx, &params, range, samples)
            })
            .collect()
    });
    // Summed in chunk order: the energies (floating point) do not depend on the threads.
    Ok(parts.into_iter().fold(PilotStats::default(), |mut a, b| {
        a += b;
        a
    }))
}

/// Does deciding for `config` need the pilot? (Only SPCBPT's Γ decision reads it.)
pub fn needs_pilot(config: &EstimatorConfig) -> bool {
    matches!(config, EstimatorConfig::Spcbpt(_))
}

/// The film's pixel count, which sizes the plan's memory estimates.
pub fn film_pixels(prepared: &PreparedScene) -> u32 {
    let camera = &prepared.scene.camera;
    (camera.width() as u64 * camera.height() as u64).min(u32::MAX as u64) as u32
}

/// The plan for `config` on `prepared` at depth `max_depth`, with a pilot of `samples`
/// where the decisions need one. A pure function of the scene, the options and the seed,
/// so `ember train` and the renders that load its model plan alike.
pub fn plan_for(prepared: &PreparedScene, config: EstimatorConfig, max_depth: i32, seed: u64, threads: usize, samples: u32) -> Result<Plan, String> {
    let facts = SceneFacts::new(&prepared.scene, MaxDepth(max_depth));
    let pilot = if needs_pilot(&config) { Some(run_pilot(prepared, max_depth, seed, samples, threads)?) } else { None };
    Ok(Plan::decide(facts, pilot, config, film_pixels(prepared)))
}

/// The memory a run may claim, `limit` or else what the machine has available
/// ([`crate::memory`]), with how messages name it.
pub fn memory_budget(limit: Option<u64>) -> (Option<u64>, &'static str) {
    match limit {
        Some(l) => (Some(l), "--memory-limit"),
        None => (crate::memory::available_bytes(), "available memory"),
    }
}

/// Refuse, before anything large is allocated, a render whose estimated memory exceeds
/// `limit` or, without one, the memory available. Under a limit (a budget for the whole
/// process) the loaded geometry counts too; measured against the memory available it
/// does not, since it is already allocated and so already missing from that figure.
pub fn check_memory(prepared: &PreparedScene, config: &EstimatorConfig, limit: Option<u64>) -> Result<(), String> {
    let camera = &prepared.scene.camera;
    let (bytes, estimate) = prepared.memory_need(config);
    let geometry = if limit.is_some() { prepared.geometry_bytes() } else { 0 };
    match memory_budget(limit) {
        (Some(a), source) if bytes.saturating_add(geometry) > a => {
            let (largest, lower) = if geometry > bytes {
                (format!("the scene's geometry, {} triangles,", prepared.accel.triangle_count()), "the scene's triangle count")
            } else {
                (format!("{} at {}×{}", estimate.largest, camera.width(), camera.height()), estimate.lower)
            };
            Err(format!(
                "{} would need about {} ({largest} is the largest part{}), more than the {} of {source}; lower {lower} or raise --memory-limit",
                config.kind(),
                crate::memory::human(bytes.saturating_add(geometry)),
                if geometry > 0 { format!("; the geometry holds {}", crate::memory::human(geometry)) } else { String::new() },
                crate::memory::human(a),
            ))
        }
        _ => Ok(()),
    }
}

/// The core's renderer for `config` on `prepared` with [`render_params`] (its lane
/// kernels at the accelerator's shading level); its setup phases are still to run.
pub fn new_renderer(prepared: &PreparedScene, config: EstimatorConfig, max_depth: i32, seed: u64) -> Result<Renderer, String> {
    let params = render_params(max_depth, seed, prepared.accel.shading_level());
    Renderer::new(&prepared.scene, params, config).map_err(|e| format!("{} {e}", config.kind()))
}

/// The kernel radius r₀ `renderer`'s setup chose, with the rule that chose it: the
/// merging estimators (where the plan keeps merging), the path filters and segment
/// kernels of the disk; `None` for the others.
pub fn initial_radius(renderer: &Renderer) -> Option<(f32, RadiusRule)> {
    match renderer {
        Renderer::Merging(m) if m.config.merges(m.mode) => Some((m.r0, m.config.radius)),
        Renderer::Segment(s) => match s.kernel {
            ember_core::segment::Kernel::Disk { radius } => Some((radius, s.config.radius)),
            ember_core::segment::Kernel::Dirac => None,
        },
        Renderer::Filter(f) => Some((f.r0, f.config.radius)),
        Renderer::PhotonFilter(f) => Some((f.r0, f.config.radius)),
        Renderer::BidirectionalFilter(f) => Some((f.r0, f.config.radius)),
        _ => None,
    }
}

/// Refuse a kernel radius larger than the scene's bounding-box diagonal: every merge or
/// filter kernel would then span the whole scene, and the image came out nearly black
/// with exit 0 (`--radius 10` on the 2-unit Cornell box: 2 % of the right mean).
pub fn check_radius(renderer: &Renderer, scene: &Scene) -> Result<(), String> {
    let Some((r0, rule)) = initial_radius(renderer) else { return Ok(()) };
    let bounds = &scene.bounds;
    let diagonal = if bounds.is_empty() { 0.0 } else { (bounds.max - bounds.min).length() };
    if !(diagonal > 0.0) || r0 <= diagonal {
        return Ok(());
    }
    let option = match rule {
        RadiusRule::Footprints(k) => format!("--radius-footprints {k}"),
        RadiusRule::SceneFraction(f) => format!("--radius-scene {f}"),
        RadiusRule::Absolute(r) => format!("--radius {r}"),
    };
    Err(format!(
        "{option} gives {} a kernel radius r0 = {r0:.4e}, larger than the scene itself (its bounding box's diagonal is {diagonal:.4e}): every kernel would span the whole scene; lower it",
        renderer.kind().name()
    ))
}
