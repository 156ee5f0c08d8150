//! The scene plan on the command line: `ember plan`'s report (text or JSON). The plan
//! itself, its pilot mapped on threads, is [`ember_host::setup`]'s, shared with every host.

use ember_core::estimators::EstimatorKind;
use ember_core::plan::{Plan, SceneFacts, pilot};
use ember_core::transport::MaxDepth;

use ember_host::scene::PreparedScene;

pub use ember_host::setup::{film_pixels, needs_pilot, plan_for, run_pilot};

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
