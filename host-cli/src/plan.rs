//! The scene plan on the host: the core's facts and decisions ([`ember_core::plan`]),
//! its pilot mapped on threads, and `ember plan`'s report (text or JSON).

use ember_core::estimators::{EstimatorConfig, EstimatorKind};
use ember_core::plan::{PilotStats, Plan, SceneFacts, pilot};
use ember_core::render::Context;
use ember_core::transport::{Heuristic, MaxDepth, RenderParams};
use rayon::prelude::*;

use ember_host::scene::PreparedScene;

/// Pilot samples per rayon task.
const PILOT_CHUNK: u32 = 256;

/// Run `samples` pilot samples on `threads` threads (the counts do not depend on them).
pub fn run_pilot(prepared: &PreparedScene, max_depth: i32, seed: u64, samples: u32, threads: usize) -> Result<PilotStats, String> {
    let params = RenderParams { max_depth: MaxDepth(max_depth), seed, heuristic: Heuristic::Power, ..RenderParams::default() };
    let ctx = Context { scene: &prepared.scene, tracer: &prepared.accel };
    let pool = ember_host::driver::thread_pool(threads, "ember-pilot").map_err(|e| e.to_string())?;
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
fn film_pixels(prepared: &PreparedScene) -> u32 {
    let camera = &prepared.scene.camera;
    (camera.width() as u64 * camera.height() as u64).min(u32::MAX as u64) as u32
}

/// The plan for `config` on `prepared` at depth `max_depth`, with a pilot of `samples`
/// where the decisions need one.
pub fn plan_for(prepared: &PreparedScene, config: EstimatorConfig, max_depth: i32, seed: u64, threads: usize, samples: u32) -> Result<Plan, String> {
    let facts = SceneFacts::new(&prepared.scene, MaxDepth(max_depth));
    let pilot = if needs_pilot(&config) { Some(run_pilot(prepared, max_depth, seed, samples, threads)?) } else { None };
    Ok(Plan::decide(facts, pilot, config, film_pixels(prepared)))
}

/// `ember plan`'s report in words: the facts and the pilot once, then per estimator its
/// memory and its decisions.
pub fn describe_all(prepared: &PreparedScene, plans: &[Plan]) -> String {
    let mut out = String::new();
    let camera = &prepared.scene.camera;
    out.push_str(&format!("plan for {} at {}x{}\n", prepared.name, camera.width(), camera.height()));
    if let Some(first) = plans.first() {
        for l in first.facts_lines() {
            out.push_str(&format!("  {l}\n"));
        }
    }
    for p in plans {
        let (bytes, estimate) = prepared.memory_need(&p.asked);
        let (planned_bytes, _) = prepared.memory_need(&p.planned);
        out.push_str(&format!(
            "{:<8} memory about {} ({} the largest part){}\n",
            p.asked.kind().name(),
            ember_host::memory::human(bytes),
            estimate.largest,
            if planned_bytes != bytes { format!(", as planned {}", ember_host::memory::human(planned_bytes)) } else { String::new() }
        ));
        for l in p.decision_lines() {
            out.push_str(&format!("         {l}\n"));
        }
    }
    out
}

/// A JSON string literal.
fn json_str(s: &str) -> String {
    let mut o = String::with_capacity(s.len() + 2);
    o.push('"');
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => o.push_str(&format!("\\u{:04x}", c as u32)),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// `ember plan --json`: the same content as [`describe_all`], machine-readable.
pub fn json_all(prepared: &PreparedScene, plans: &[Plan]) -> String {
    let camera = &prepared.scene.camera;
    let mut o = String::from("{\n");
    o.push_str(&format!("  \"scene\": {},\n  \"width\": {},\n  \"height\": {},\n", json_str(&prepared.name), camera.width(), camera.height()));
    if let Some(first) = plans.first() {
        let f = &first.facts;
        let (m, l) = (&f.materials, &f.lights);
        o.push_str(&format!(
            "  \"materials\": {{\"dirac\": {}, \"dirac_and_continuous\": {}, \"glossy\": {}, \"rough\": {}}},\n",
            m.dirac, m.dirac_and_continuous, m.glossy, m.rough
        ));
        o.push_str(&format!(
            "  \"lights\": {{\"surface\": {}, \"point\": {}, \"directional\": {}, \"environment\": {}, \"emitter_extent\": {}}},\n",
            l.surface, l.point, l.directional, l.environment, f.emitter_extent
        ));
        o.push_str(&format!("  \"max_depth\": {},\n  \"specular_chains\": {},\n", f.max_depth.0, f.specular_chains));
        match &first.pilot {
            Some(p) => o.push_str(&format!(
                "  \"pilot\": {{\"samples\": {}, \"emitter_seen\": {}, \"connections\": {}, \"occluded\": {}, \"light_samples\": {}, \"light_samples_occluded\": {}, \"rays\": {}, \"energy_by_technique\": {{{}}}, \"energy_by_length\": {:?}, \"shadow_rays_by_technique\": {{{}}}}},\n",
                p.samples,
                p.emitter_seen,
                p.connections,
                p.occluded,
                p.light_samples,
                p.light_samples_occluded,
                p.rays,
                pilot::TECHNIQUES.iter().zip(p.technique_shares()).map(|(n, v)| format!("{}: {v}", json_str(n))).collect::<Vec<_>>().join(", "),
                p.length_shares(),
                pilot::TECHNIQUES.iter().zip(p.shadow_rays).map(|(n, v)| format!("{}: {v}", json_str(n))).collect::<Vec<_>>().join(", ")
            )),
            None => o.push_str("  \"pilot\": null,\n"),
        }
    }
    o.push_str("  \"estimators\": [\n");
    for (i, p) in plans.iter().enumerate() {
        let (bytes, _) = prepared.memory_need(&p.asked);
        let (planned_bytes, _) = prepared.memory_need(&p.planned);
        o.push_str(&format!(
            "    {{\"estimator\": {}, \"renders\": {}, \"memory_bytes\": {bytes}, \"planned_memory_bytes\": {planned_bytes}, \"decisions\": [",
            json_str(p.asked.kind().name()),
            json_str(p.planned.kind().name())
        ));
        for (j, d) in p.decisions.iter().enumerate() {
            o.push_str(&format!(
                "{}{{\"technique\": {}, \"kept\": {}, \"why\": {}, \"bytes\": {}}}",
                if j > 0 { ", " } else { "" },
                json_str(d.technique.name()),
                d.kept,
                json_str(&d.why),
                d.bytes
            ));
        }
        o.push_str(&format!("]}}{}\n", if i + 1 < plans.len() { "," } else { "" }));
    }
    o.push_str("  ]\n}\n");
    o
}

/// The plans `ember plan` prints: every estimator, each with its default configuration
/// and the one pilot.
pub fn plans_for_all(prepared: &PreparedScene, max_depth: i32, seed: u64, threads: usize, samples: u32) -> Result<Vec<Plan>, String> {
    let facts = SceneFacts::new(&prepared.scene, MaxDepth(max_depth));
    let pilot = run_pilot(prepared, max_depth, seed, samples, threads)?;
    let pixels = film_pixels(prepared);
    Ok(EstimatorKind::ALL.iter().map(|k| Plan::decide(facts, Some(pilot), k.default_config(), pixels)).collect())
}
