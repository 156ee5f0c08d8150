//! The scene plan: what an estimator's techniques need, whether the scene has it, and
//! what is left out (issue 21: "leave out what a given scene does not need").
//!
//! Every estimator in this crate builds its whole machinery on every scene. Most of it
//! pays for itself only on some scenes, and some of it can be proven useless from the
//! scene description alone. The plan separates the two:
//!
//! 1. **Facts** ([`SceneFacts`], computed here from the scene and the depth, no rays):
//!    the materials by lobe (Dirac only, Dirac and continuous, glossy, rough), the
//!    lights by kind, the extent of the emitting surfaces, the depth, and from these
//!    whether a specular–diffuse–specular chain can exist.
//! 2. **A pilot** ([`pilot`], a few thousand camera and light sub-paths through the
//!    caller's ray queries, chunked like any phase): how often emitters are seen
//!    directly, and the share of connections and of light samples that are occluded.
//! 3. **Decisions** ([`Plan::decide`]): for one estimator configuration, the
//!    techniques kept and left out, each with its reason and the memory it would take,
//!    and the configuration that leaves them out.
//!
//! A decision may only leave out what cannot change the converged image. The rules:
//!
//! - **Vertex merging in VCM** is the only technique that samples a path whose every
//!   edge has a Dirac endpoint (E S D S L with a pinhole and a point light: neither a
//!   connection nor an emitter hit can). Such a path needs a Dirac vertex next to a
//!   non-Dirac one and a third vertex, so merging is left out when the scene has no
//!   material with a Dirac lobe, or none without one, or when the depth allows fewer
//!   than three scattering vertices. Left out, its count leaves VCM's balance heuristic
//!   too (the denominators must not count a technique that draws no samples: that is
//!   the first bug the plan test injects), and its photons and grid are never built.
//!   PPM and BPM are merging itself, so the plan never touches them.
//! - **Light-source bins in SPCBPT** let the cache hold light-source vertices so that
//!   Γ can steer s = 1 toward lights a region sees. With one compact emitter (every
//!   emitting surface inside a box under a quarter of the scene's diagonal) every region
//!   sees the same light, and next-event estimation is the better s = 1. Left out,
//!   s = 1 is NEE, which samples the same paths: the image's expectation is unchanged.
//! - **Γ training** (all of SPCBPT's preprocessing): where the pilot finds fewer than
//!   [`RARELY_OCCLUDED`] of connections occluded, a learned choice of light vertex
//!   can hardly beat the uniform one, and the plan renders LVCBPT (the same
//!   connections, chosen uniformly; where the build has it), which converges to the
//!   same image.
//!
//! The plan only removes; the estimator that runs is still unbiased (or consistent)
//! on its own. `ember plan` prints it, `ember render` prints it in its report.

pub mod pilot;

use alloc::string::String;
use alloc::vec::Vec;
use core::fmt::Write;

use crate::estimators::{EstimatorConfig, MergeMode};
use crate::math::Bounds3;
use crate::scene::Scene;
use crate::transport::MaxDepth;

pub use pilot::PilotStats;

/// Below this share of occluded connections the plan replaces SPCBPT by LVCBPT.
pub const RARELY_OCCLUDED: f64 = 0.1;
/// A microfacet α below this is glossy, above it rough.
pub const GLOSSY_ALPHA: f32 = 0.3;
/// Emitting surfaces inside a box whose diagonal is below this share of the scene's
/// diagonal count as one compact light.
pub const COMPACT_LIGHT: f32 = 0.25;

/// Materials by their lobes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MaterialCounts {
    /// Only Dirac lobes (smooth conductor, smooth dielectric).
    pub dirac: u32,
    /// A Dirac and a continuous lobe (smooth plastic).
    pub dirac_and_continuous: u32,
    /// Microfacet models with α below [`GLOSSY_ALPHA`].
    pub glossy: u32,
    /// Diffuse, and microfacet models with α at least [`GLOSSY_ALPHA`].
    pub rough: u32,
}

/// Lights by kind (an emitting mesh counts once per triangle, as the scene holds it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LightCounts {
    /// Emitting triangles and spheres.
    pub surface: u32,
    /// Point and spot lights.
    pub point: u32,
    /// Directional lights.
    pub directional: u32,
    /// Constant and image-based environments.
    pub environment: u32,
}

/// What the scene description says, before any ray is traced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneFacts {
    /// Materials by lobe.
    pub materials: MaterialCounts,
    /// Lights by kind.
    pub lights: LightCounts,
    /// The diagonal of the box around every emitting surface over the scene's
    /// diagonal (0 without surface lights).
    pub emitter_extent: f32,
    /// The depth the render uses (Mitsuba's `max_depth`; −1 unbounded).
    pub max_depth: MaxDepth,
    /// A specular–diffuse–specular chain is possible: a material with a Dirac lobe, one
    /// with a continuous lobe, and at least three scattering vertices allowed.
    pub specular_chains: bool,
}

impl SceneFacts {
    /// The facts of `scene` rendered at depth `max_depth`.
    pub fn new(scene: &Scene, max_depth: MaxDepth) -> Self {
        let mut materials = MaterialCounts::default();
        for m in &scene.materials {
            match (m.is_delta(), m.has_delta_lobe(), m.roughness()) {
                (true, _, _) => materials.dirac += 1,
                (false, true, _) => materials.dirac_and_continuous += 1,
                (false, false, Some(a)) if a < GLOSSY_ALPHA => materials.glossy += 1,
                _ => materials.rough += 1,
            }
        }
        let mut lights = LightCounts::default();
        let mut emitters = Bounds3::EMPTY;
        for l in &scene.lights {
            if let Some(b) = l.surface_bounds() {
                lights.surface += 1;
                emitters = emitters.union(b);
            } else if l.is_delta_position() {
                lights.point += 1;
            } else if l.is_delta_direction() {
                lights.directional += 1;
            } else {
                lights.environment += 1;
            }
        }
        let diagonal = |b: Bounds3| {
            let d = b.max - b.min;
            if d.is_finite() { d.length() } else { 0.0 }
        };
        let scene_diagonal = diagonal(scene.bounds);
        let emitter_extent = if lights.surface > 0 && scene_diagonal > 0.0 { diagonal(emitters) / scene_diagonal } else { 0.0 };
        let with_dirac = materials.dirac + materials.dirac_and_continuous;
        let with_continuous = materials.dirac_and_continuous + materials.glossy + materials.rough;
        // Three scattering vertices need four segments.
        let specular_chains = with_dirac > 0 && with_continuous > 0 && max_depth.allows(4);
        Self { materials, lights, emitter_extent, max_depth, specular_chains }
    }

    /// All lights are one compact emitting surface (see [`COMPACT_LIGHT`]).
    pub fn one_compact_light(&self) -> bool {
        let l = &self.lights;
        l.point + l.directional + l.environment == 0 && l.surface > 0 && self.emitter_extent < COMPACT_LIGHT
    }
}

/// A technique an estimator may leave out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Technique {
    /// VCM's vertex merging (photons, their grid and their MIS count).
    Merging,
    /// SPCBPT's light-source vertices in the cache (s = 1 through Γ).
    LightSourceBins,
    /// SPCBPT's trained Γ (and all its preprocessing): LVCBPT runs instead.
    GammaTraining,
}

impl Technique {
    /// The name the plan prints.
    pub fn name(self) -> &'static str {
        match self {
            Self::Merging => "vertex merging",
            Self::LightSourceBins => "light-source bins",
            Self::GammaTraining => "Γ training",
        }
    }
}

/// One technique kept or left out, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Decision {
    /// The technique.
    pub technique: Technique,
    /// Kept (`true`) or left out.
    pub kept: bool,
    /// The reason, in words.
    pub why: String,
    /// Bytes the technique holds for this film (estimated): saved when left out.
    pub bytes: u64,
}

/// The facts, the pilot's measurements (if one ran) and the decisions for one
/// estimator configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    /// What the scene description says.
    pub facts: SceneFacts,
    /// What the pilot measured.
    pub pilot: Option<PilotStats>,
    /// The configuration asked for.
    pub asked: EstimatorConfig,
    /// The configuration to render: `asked` with the left-out techniques removed.
    pub planned: EstimatorConfig,
    /// Each technique the asked estimator could leave out.
    pub decisions: Vec<Decision>,
}

impl Plan {
    /// Decide for `asked` on a scene with `facts` and, where one ran, `pilot`; `pixels`
    /// sizes the memory estimates.
    pub fn decide(facts: SceneFacts, pilot: Option<PilotStats>, asked: EstimatorConfig, pixels: u32) -> Self {
        let mut decisions = Vec::new();
        let mut planned = asked;
        let saved = |from: &EstimatorConfig, to: &EstimatorConfig| from.memory_estimate(pixels).bytes.saturating_sub(to.memory_estimate(pixels).bytes);
        match asked {
            EstimatorConfig::Merging(MergeMode::Vcm, c) if c.merging => {
                let mut without = c;
                without.merging = false;
                let without = EstimatorConfig::Merging(MergeMode::Vcm, without);
                let bytes = saved(&asked, &without);
                if facts.specular_chains {
                    decisions.push(Decision {
                        technique: Technique::Merging,
                        kept: true,
                        why:
                            "a specular–diffuse–specular chain is possible (Dirac and continuous materials, depth ≥ 4): only merging samples some of its paths"
                                .into(),
                        bytes,
                    });
                } else {
                    let why = if facts.materials.dirac + facts.materials.dirac_and_continuous == 0 {
                        "no material has a Dirac lobe, so every path has an edge a connection can sample"
                    } else if facts.materials.dirac_and_continuous + facts.materials.glossy + facts.materials.rough == 0 {
                        "every material is Dirac: no vertex to merge at"
                    } else {
                        "the depth allows fewer than three scattering vertices"
                    };
                    decisions.push(Decision { technique: Technique::Merging, kept: false, why: why.into(), bytes });
                    planned = without;
                }
            }
            EstimatorConfig::Spcbpt(c) => {
                let rarely = pilot.filter(|p| p.connections > 0).map(|p| p.occluded_share());
                match rarely {
                    // LVCBPT must be in the build (a core without the `lvcbpt` feature keeps SPCBPT).
                    Some(share) if share < RARELY_OCCLUDED && crate::estimators::EstimatorKind::Lvcbpt.is_compiled() => {
                        let lv = EstimatorConfig::Lvcbpt(crate::estimators::LvcbptConfig {
                            light_paths: c.light_paths,
                            connections: c.connections,
                            ..Default::default()
                        });
                        let mut why = String::new();
                        let _ = write!(
                            why,
                            "the pilot found {:.1} % of connections occluded (< {:.0} %): uniform connections (LVCBPT) instead",
                            100.0 * share,
                            100.0 * RARELY_OCCLUDED
                        );
                        decisions.push(Decision { technique: Technique::GammaTraining, kept: false, why, bytes: saved(&asked, &lv) });
                        planned = lv;
                    }
                    other => {
                        let mut why = String::new();
                        match other {
                            Some(share) => {
                                let _ = write!(why, "the pilot found {:.1} % of connections occluded", 100.0 * share);
                            }
                            None => why.push_str("no pilot measured occlusion"),
                        }
                        decisions.push(Decision { technique: Technique::GammaTraining, kept: true, why, bytes: 0 });
                        if c.light_source_share > 0.0 {
                            let mut no_bins = c;
                            no_bins.light_source_share = 0.0;
                            if facts.one_compact_light() {
                                let mut why = String::new();
                                let _ = write!(
                                    why,
                                    "one compact emitter (extent {:.3} of the scene): next-event estimation is the better s = 1",
                                    facts.emitter_extent
                                );
                                decisions.push(Decision { technique: Technique::LightSourceBins, kept: false, why, bytes: 0 });
                                planned = EstimatorConfig::Spcbpt(no_bins);
                            } else {
                                decisions.push(Decision {
                                    technique: Technique::LightSourceBins,
                                    kept: true,
                                    why: "emitters spread over the scene, or lights without a surface (the estimator drops the bins itself then)".into(),
                                    bytes: 0,
                                });
                            }
                        }
                    }
                }
            }
            _ => {}
        }
        Self { facts, pilot, asked, planned, decisions }
    }

    /// The plan in words, one line per item: [`Self::facts_lines`], then
    /// [`Self::decision_lines`].
    pub fn describe(&self) -> Vec<String> {
        let mut lines = self.facts_lines();
        lines.extend(self.decision_lines());
        lines
    }

    /// The facts and the pilot in words (the same for every estimator of a scene).
    pub fn facts_lines(&self) -> Vec<String> {
        let f = &self.facts;
        let m = &f.materials;
        let l = &f.lights;
        let mut lines = Vec::new();
        let mut s = String::new();
        let _ = write!(s, "materials: {} Dirac, {} Dirac + continuous, {} glossy, {} rough", m.dirac, m.dirac_and_continuous, m.glossy, m.rough);
        lines.push(s);
        let mut s = String::new();
        let _ = write!(
            s,
            "lights: {} surface (extent {:.3} of the scene), {} point/spot, {} directional, {} environment",
            l.surface, f.emitter_extent, l.point, l.directional, l.environment
        );
        lines.push(s);
        let mut s = String::new();
        let depth = if f.max_depth.0 < 0 { String::from("unbounded") } else { alloc::format!("{}", f.max_depth.0) };
        let _ = write!(s, "max depth {depth}; specular–diffuse–specular chains {}", if f.specular_chains { "possible" } else { "impossible" });
        lines.push(s);
        if let Some(p) = &self.pilot {
            let mut s = String::new();
            let _ = write!(
                s,
                "pilot: {} camera and light paths; emitters seen directly by {:.1} % of camera rays; {:.1} % of {} connections and {:.1} % of {} light samples occluded",
                p.samples,
                100.0 * p.emitter_seen_share(),
                100.0 * p.occluded_share(),
                p.connections,
                100.0 * p.light_sample_occluded_share(),
                p.light_samples
            );
            lines.push(s);
            if p.energy.iter().sum::<f64>() > 0.0 {
                let mut s = String::from("energy by technique:");
                for (name, share) in pilot::TECHNIQUES.iter().zip(p.technique_shares()) {
                    let _ = write!(s, " {name} {:.1} %,", 100.0 * share);
                }
                s.pop();
                let _ = write!(s, "; shadow rays {:?}", p.shadow_rays);
                lines.push(s);
                let mut s = String::from("energy by path length (segments):");
                for (k, share) in p.length_shares().iter().enumerate() {
                    let plus = if k + 1 == pilot::LENGTHS { "+" } else { "" };
                    let _ = write!(s, " {}{plus} {:.1} %,", k + 1, 100.0 * share);
                }
                s.pop();
                lines.push(s);
            }
        }
        lines
    }

    /// The decisions in words, and the estimator that renders where it changed.
    pub fn decision_lines(&self) -> Vec<String> {
        let mut lines = Vec::new();
        for d in &self.decisions {
            let mut s = String::new();
            let _ = write!(s, "{} {}: {} ({:.1} MiB)", if d.kept { "keep" } else { "leave out" }, d.technique.name(), d.why, d.bytes as f64 / 1_048_576.0);
            lines.push(s);
        }
        if self.planned != self.asked {
            let mut s = String::new();
            let _ = write!(s, "renders {} as planned", self.planned.kind().name());
            lines.push(s);
        }
        lines
    }
}
