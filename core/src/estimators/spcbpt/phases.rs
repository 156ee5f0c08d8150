//! SPCBPT's phases (the render protocol, [`crate::render`]): preprocessing (section 7)
//! as four setup phases, then four phases per pass.
//!
//! | stage | phase | items | reduction |
//! |---|---|---|---|
//! | setup 0 | `light features` | min(\|D\|, 200 000) light paths | κ_L fitted (surface subspaces; light-source bins from the share) |
//! | setup 1 | `dataset features` | \|D\| dataset samples | κ_E fitted; pixel-block brightness |
//! | setup 2 | `Q` | M' light paths | Q per light subspace (eq. 19) |
//! | setup 3 | `training set` | \|D\| dataset samples | records appended in order; Γ trained by Adam; D freed |
//! | pass 0 | `light paths` | M | paths and memos appended in order; subspace buckets and stage-2 tables (with reuse FIFOs) |
//! | pass 1 | `Γ tables` | N_S eye subspaces | stage-1 tables restricted to the pass's non-empty subspaces |
//! | pass 2 | `splats` | M | t = 1 splats staged |
//! | pass 3 | `camera` | W·H pixels | camera samples staged; pass committed with splat factor 1/M |
//!
//! Feature lists are capped at 200 000 entries (the first in index order), so the trees'
//! fitting cost does not grow with |D|.

use alloc::vec;
use alloc::vec::Vec;

use super::{Classifier, Model, PassCache, build_buckets, build_gamma_tables, light_source_bins, prepare, render_pixels, splat_light_paths, trace_light_paths};
use crate::camera::CameraPass;
use crate::estimators::SpcbptConfig;
use crate::estimators::{ChunkOutput, PhaseData};
use crate::geometry::RayQuery;
use crate::render::{Context, Cursor, Film, Phase, Phased, Stage};
use crate::subspace::{AdamParams, DecisionTree, LightSourceBins, SubpathFeature, SubspaceMatrix, TrainParams, TrainingSet};
use crate::transport::RenderParams;

/// Light paths and dataset samples per chunk.
const CHUNK: u32 = 1024;
/// Eye subspaces per chunk of the Γ-table phase.
const EYE_CHUNK: u32 = 64;
/// Most features a classifier side is fitted on.
const FIT_CAP: usize = 200_000;

/// What preprocessing did (hosts print it; phase times are the host's, which has a clock).
#[derive(Clone, Debug, Default)]
pub struct SpcbptReport {
    /// Mean training loss per epoch.
    pub losses: Vec<f64>,
    /// Adam's batch size (the configured batch, or smaller for a small D).
    pub batch: usize,
    /// Adam steps taken over all epochs.
    pub steps: usize,
    /// Paths in the training set D.
    pub dataset_paths: usize,
    /// Bytes D held (freed after training).
    pub dataset_bytes: usize,
    /// Bytes of the κ trees and light-source bins.
    pub tree_bytes: usize,
    /// Bytes of Γ.
    pub gamma_bytes: usize,
    /// Eye subspaces.
    pub n_eye: u32,
    /// Light subspaces (tree + bins).
    pub n_light: u32,
    /// Light subspaces that are light-source bins (0: s = 1 by NEE).
    pub light_source_bins: u32,
    /// Why light sources were not binned although a share was asked for.
    pub unbinned_because: Option<&'static str>,
}

/// Preprocessing state between setup phases.
#[derive(Clone, Debug, Default)]
struct Setup {
    light_tree: Option<(DecisionTree, u32)>,
    sources: Option<LightSourceBins>,
    classifier: Option<Classifier>,
    block_mean: Vec<f64>,
    q: Vec<f32>,
}

/// SPCBPT configured for one film: settings, the model (after setup) and the pass cache.
#[derive(Debug)]
pub struct Spcbpt {
    /// Settings shared by the estimators.
    pub params: RenderParams,
    /// The configuration it was built with.
    pub config: SpcbptConfig,
    /// M.
    pub light_paths: u32,
    /// |D|.
    pub dataset: u32,
    /// M'.
    pub q_paths: u32,
    /// N_S.
    pub subspaces: u32,
    width: u32,
    height: u32,
    setup: Setup,
    /// κ, Q, Γ: present once setup has run.
    pub model: Option<Model>,
    /// What preprocessing did.
    pub report: SpcbptReport,
    /// The current pass's light vertices, buckets, tables and reuse FIFOs.
    pub cache: PassCache,
    cursor: Cursor,
}

impl Spcbpt {
    /// SPCBPT for a `width × height` film (preprocessing runs in the setup phases).
    pub fn new(params: RenderParams, config: SpcbptConfig, width: u32, height: u32) -> Self {
        let pixels = width * height;
        let dataset = config.dataset_for(pixels);
        Self {
            params,
            config,
            light_paths: config.light_paths_for(pixels),
            dataset,
            q_paths: config.q_paths_for(pixels),
            subspaces: config.subspaces_for(pixels),
            width,
            height,
            setup: Setup::default(),
            model: None,
            report: SpcbptReport::default(),
            cache: PassCache::with_reuse(config.reuse),
            cursor: Cursor::new(4, 4),
        }
    }

    fn pixels(&self) -> u32 {
        self.width * self.height
    }

    /// M/(W·H): the light-tracing strategy's count per camera sample.
    fn light_tracing(&self) -> f64 {
        self.light_paths as f64 / self.pixels().max(1) as f64
    }

    /// Use a model trained before (`ember train`, [`Model::decode`]) instead of running
    /// the preprocessing: the setup phases are skipped. Refused once setup has begun, or
    /// when the model was trained for another number of connections N or subspaces.
    pub fn use_model(&mut self, model: Model) -> Result<(), &'static str> {
        if self.cursor != Cursor::new(4, 4) {
            return Err("the preprocessing has already begun");
        }
        if model.connections != self.config.connections {
            return Err("the model was trained for another number of connections");
        }
        if model.classifier.n_eye > self.subspaces || model.classifier.n_light_surface > self.subspaces {
            return Err("the model has more subspaces than this configuration");
        }
        let c = &model.classifier;
        self.report.n_eye = c.n_eye;
        self.report.n_light = c.n_light;
        self.report.light_source_bins = c.sources.as_ref().map_or(0, |b| b.bin_count());
        self.report.tree_bytes = c.size_bytes();
        self.report.gamma_bytes = model.gamma.size_bytes();
        self.model = Some(model);
        self.cursor = Cursor::new(0, 4);
        Ok(())
    }

    fn n_eye(&self) -> u32 {
        self.model.as_ref().map_or(0, |m| m.classifier.n_eye)
    }
}

/// SPCBPT's phase ids, named once: setup (κ_L's light features, the dataset's features,
/// Q, the training set), then per pass (light paths, stage-1 Γ tables, light-tracing
/// splats, camera).
mod phase {
    pub const LIGHT_FEATURES: u8 = 0;
    pub const DATASET_FEATURES: u8 = 1;
    pub const Q: u8 = 2;
    pub const TRAINING_SET: u8 = 3;
    pub const LIGHT_PATHS: u8 = 4;
    pub const GAMMA_TABLES: u8 = 5;
    pub const SPLATS: u8 = 6;
    pub const CAMERA: u8 = 7;
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Spcbpt {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        let setup = |name, id, items| Phase { name, id, pass: None, items, chunk: CHUNK, samples: false };
        let pass = |name, id, p, items, chunk, samples| Phase { name, id, pass: Some(p), items, chunk, samples };
        Some(match self.cursor.stage()? {
            Stage::Setup(0) => setup("light features", phase::LIGHT_FEATURES, self.dataset.min(FIT_CAP as u32)),
            Stage::Setup(1) => setup("dataset features", phase::DATASET_FEATURES, self.dataset),
            Stage::Setup(2) => setup("Q", phase::Q, self.q_paths),
            Stage::Setup(_) => setup("training set", phase::TRAINING_SET, self.dataset),
            Stage::Pass(p, 0) => pass("light paths", phase::LIGHT_PATHS, p, self.light_paths, CHUNK, true),
            Stage::Pass(p, 1) => pass("Γ tables", phase::GAMMA_TABLES, p, self.n_eye(), EYE_CHUNK, false),
            Stage::Pass(p, 2) => pass("splats", phase::SPLATS, p, self.light_paths, CHUNK, false),
            Stage::Pass(p, _) => pass("camera", phase::CAMERA, p, self.pixels(), CHUNK, true),
        })
    }

    fn start_pass(&mut self, pass: u32) {
        self.cursor.start_pass(pass);
    }

    /// With reuse, each pass's light-path phase pushes light vertices into FIFOs that
    /// later passes connect to: replaying that phase alone (its tracing and its
    /// reduction, no splats and no camera samples) rebuilds them exactly.
    fn replay_pass(&mut self, pass: u32) -> bool {
        if self.config.reuse == 0 {
            return false;
        }
        self.cursor.start_replay(pass, 1);
        true
    }

    fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput) {
        let (scene, tracer, params) = (ctx.scene, ctx.tracer, &self.params);
        let items = out.items.clone();
        let pass = phase.pass.unwrap_or(0);
        match phase.id {
            phase::LIGHT_FEATURES => {
                let (features, weights, _, _) = out.data.features();
                out.counters = prepare::light_features(scene, tracer, params, items, features, weights);
            }
            phase::DATASET_FEATURES => {
                let blocks_n = (self.width.div_ceil(prepare::BLOCK) * self.height.div_ceil(prepare::BLOCK)) as usize;
                let (features, weights, blocks, block_samples) = out.data.features();
                blocks.resize(blocks_n, 0.0);
                block_samples.resize(blocks_n, 0);
                out.counters = prepare::dataset_features(scene, tracer, params, items, features, weights, blocks, block_samples);
            }
            phase::Q => {
                let Some(classifier) = &self.setup.classifier else { return };
                let q = out.data.sums(classifier.n_light as usize);
                out.counters = prepare::accumulate_q(scene, tracer, params, classifier, items, q);
            }
            phase::TRAINING_SET => {
                let Some(classifier) = &self.setup.classifier else { return };
                let inputs = prepare::RecordInputs {
                    classifier,
                    q: &self.setup.q,
                    connections: self.config.connections,
                    light_tracing: self.light_tracing(),
                    block_mean: &self.setup.block_mean,
                };
                let set = out.data.training();
                out.counters = prepare::dataset_records(ctx, params, &inputs, items, set);
            }
            _ => {
                let Some(model) = &self.model else { return };
                match phase.id {
                    phase::LIGHT_PATHS => {
                        let (paths, memo) = out.data.light_paths();
                        out.counters = trace_light_paths(scene, tracer, params, model, pass, items, paths, memo);
                    }
                    phase::GAMMA_TABLES => {
                        let (tables, norms) = out.data.gamma_tables(out.items.len());
                        build_gamma_tables(model, &self.cache, items, tables, norms);
                    }
                    phase::SPLATS => {
                        let splats = &mut out.splats;
                        out.counters = splat_light_paths(scene, tracer, params, model, &self.cache, self.light_tracing(), pass, items, &mut |s| splats.push(s));
                    }
                    _ => {
                        out.counters = render_pixels(scene, tracer, params, model, &self.cache, self.light_paths, pass, items, out.pixel_buffer());
                    }
                }
            }
        }
    }

    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        let scene = ctx.scene;
        match phase.id {
            phase::LIGHT_FEATURES => {
                let (mut lf, mut lw): (Vec<SubpathFeature>, Vec<f32>) = (Vec::new(), Vec::new());
                for out in outputs.iter() {
                    if let PhaseData::Features { features, weights, .. } = &out.data {
                        lf.extend_from_slice(features);
                        lw.extend_from_slice(weights);
                    }
                }
                lf.truncate(FIT_CAP);
                lw.truncate(FIT_CAP);
                // Light-source bins take their share of N_S when the scene can use them.
                let subspaces = self.subspaces;
                let wanted = (crate::math::round(self.config.light_source_share * subspaces as f32) as u32).min(subspaces - 1);
                let probe = light_source_bins(scene, wanted, 0);
                let surface = subspaces - probe.as_ref().map_or(0, |b| b.bin_count()).min(subspaces - 1);
                let (tree, n_surface) = prepare::fit_side(&lf, &lw, surface as usize, self.config.k_d, self.params.seed ^ 0x11);
                self.setup.sources = match light_source_bins(scene, wanted, n_surface) {
                    Ok(bins) => Some(bins),
                    Err(why) => {
                        self.report.unbinned_because = (wanted > 0).then_some(why);
                        None
                    }
                };
                self.report.light_source_bins = self.setup.sources.as_ref().map_or(0, |b| b.bin_count());
                self.setup.light_tree = Some((tree, n_surface));
            }
            phase::DATASET_FEATURES => {
                let blocks_n = (self.width.div_ceil(prepare::BLOCK) * self.height.div_ceil(prepare::BLOCK)) as usize;
                let (mut ef, mut ew): (Vec<SubpathFeature>, Vec<f32>) = (Vec::new(), Vec::new());
                let (mut blocks, mut block_samples) = (vec![0.0f64; blocks_n], vec![0u32; blocks_n]);
                for out in outputs.iter() {
                    let PhaseData::Features { features, weights, blocks: b, block_samples: bs } = &out.data else { continue };
                    if ef.len() < FIT_CAP {
                        ef.extend_from_slice(features);
                        ew.extend_from_slice(weights);
                    }
                    for i in 0..blocks_n.min(b.len()) {
                        blocks[i] += b[i];
                        block_samples[i] += bs[i];
                    }
                }
                ef.truncate(FIT_CAP);
                ew.truncate(FIT_CAP);
                let (eye_tree, n_eye) = prepare::fit_side(&ef, &ew, self.subspaces as usize, self.config.k_d, self.params.seed ^ 0x22);
                self.setup.block_mean = blocks.iter().zip(&block_samples).map(|(s, &n)| if n > 0 { s / n as f64 } else { 0.0 }).collect();
                let Some((light_tree, n_surface)) = self.setup.light_tree.take() else { return };
                self.setup.classifier = Some(Classifier::new(eye_tree, n_eye, light_tree, n_surface, self.setup.sources.take()));
            }
            phase::Q => {
                let n_light = self.setup.classifier.as_ref().map_or(0, |c| c.n_light) as usize;
                let mut q = vec![0.0f64; n_light];
                for out in outputs.iter() {
                    if let PhaseData::Sums(part) = &out.data {
                        for (a, b) in q.iter_mut().zip(part) {
                            *a += b;
                        }
                    }
                }
                self.setup.q = q.iter().map(|v| (v / self.q_paths.max(1) as f64) as f32).collect();
            }
            phase::TRAINING_SET => {
                let mut set = TrainingSet::new();
                for out in outputs.iter_mut() {
                    if let PhaseData::Training(part) = &mut out.data {
                        set.append(part);
                        // The chunk's records are not needed again: free them with D.
                        *part = TrainingSet::new();
                    }
                }
                self.report.dataset_paths = set.len();
                self.report.dataset_bytes = set.size_bytes();
                let Some(classifier) = self.setup.classifier.take() else { return };
                let (nl, ne) = (classifier.n_light as usize, classifier.n_eye as usize);
                let mut theta = vec![0.0f32; nl * ne];
                let train = TrainParams {
                    adam: AdamParams { learning_rate: self.config.learning_rate, ..AdamParams::default() },
                    batch: self.config.batch_for(set.len()),
                    epochs: self.config.epochs,
                    mixture: self.config.mixture,
                    seed: self.params.seed ^ 0x33,
                };
                self.report.batch = train.batch;
                self.report.steps = set.len().div_ceil(train.batch) * train.epochs as usize;
                self.report.losses = crate::subspace::train(&set, &mut theta, nl, ne, &train);
                drop(set); // D is freed once Γ is trained.
                let gamma = SubspaceMatrix::from_theta(&theta, nl, ne, self.config.mixture);
                self.report.tree_bytes = classifier.size_bytes();
                self.report.gamma_bytes = gamma.size_bytes();
                self.report.n_eye = classifier.n_eye;
                self.report.n_light = classifier.n_light;
                let q = core::mem::take(&mut self.setup.q);
                self.setup = Setup::default();
                self.model = Some(Model { classifier, q, gamma, connections: self.config.connections });
            }
            phase::LIGHT_PATHS => {
                let cache = &mut self.cache;
                cache.paths.clear();
                cache.memo.clear();
                for out in outputs.iter() {
                    if let PhaseData::LightPaths { paths, memo } = &out.data {
                        cache.paths.append(paths);
                        cache.memo.extend_from_slice(memo);
                    }
                }
                if let Some(model) = &self.model {
                    build_buckets(scene, model, cache);
                }
            }
            phase::GAMMA_TABLES => {
                self.cache.gamma_tables.clear();
                self.cache.gamma_norm.clear();
                for out in outputs.iter_mut() {
                    if let PhaseData::GammaTables { tables, norms } = &mut out.data {
                        self.cache.gamma_tables.append(tables);
                        self.cache.gamma_norm.extend_from_slice(norms);
                    }
                }
            }
            phase::SPLATS => {
                for out in outputs.iter() {
                    film.push_splats(&out.splats);
                }
            }
            _ => {
                for out in outputs.iter() {
                    film.set_camera_samples(CameraPass { seed: self.params.seed, pass: phase.pass.unwrap_or(0) }, out.items.clone(), &out.pixels);
                }
            }
        }
        if self.cursor.advance() {
            film.end_pass(1.0 / self.light_paths.max(1) as f64);
        }
    }
}
