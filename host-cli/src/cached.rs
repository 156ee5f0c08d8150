//! The cache-based estimators (LVCBPT, SPCBPT) on the CLI host: per-pass light tracing
//! and cache building in parallel over fixed chunks of light paths (merged in chunk
//! order, so images do not depend on the thread count), then the camera pass reading
//! the pass's cache.

use std::sync::RwLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::ops::Range;

use rayon::prelude::*;

use ember_core::Rgb;
use ember_core::integrator::lvcbpt::{self, CacheEntry, LightPaths, PassInputs, StrategyCounts};
use ember_core::integrator::{Counters, RenderParams};
use ember_core::scene::Scene;

use crate::accel::Accel;
use crate::cli::CacheArgs;
use crate::driver::{PassStats, Splat};

/// Light paths per parallel work item (fixed: the merge order must not depend on threads).
pub const LIGHT_CHUNK: u32 = 1024;

fn mib(bytes: usize) -> f64 {
    bytes as f64 / 1_048_576.0
}

fn stats(c: Counters, samples: usize) -> PassStats {
    PassStats { rays: c.rays, samples: samples as u64 }
}

/// Chunks of `0..n`.
pub fn chunks(n: u32, chunk: u32) -> Vec<Range<u32>> {
    (0..n.div_ceil(chunk)).map(|c| c * chunk..((c + 1) * chunk).min(n)).collect()
}

/// LVCBPT's state: settings and the current pass's light paths and cache.
#[derive(Debug)]
pub struct LvcbptHost {
    pub light_paths: u32,
    pub connections: u32,
    pub counts: StrategyCounts,
    pass: RwLock<(LightPaths, Vec<CacheEntry>)>,
    /// The cache sizes are printed once, after the first pass.
    reported: AtomicBool,
}

impl LvcbptHost {
    /// Measure c̄ (mean cacheable vertices per light path) on 16 384 preprocessing paths.
    pub fn new(scene: &Scene, accel: &Accel, params: &RenderParams, args: &CacheArgs) -> Self {
        let pixels = scene.camera.width() * scene.camera.height();
        let light_paths = args.light_paths_for(pixels);
        let probe = 16_384u32;
        let cacheable: u64 = chunks(probe, LIGHT_CHUNK).into_par_iter().map(|r| lvcbpt::count_cacheable(scene, accel, params, r).0).sum();
        let mean = cacheable as f64 / probe as f64;
        let counts = StrategyCounts::new(light_paths, args.connections, pixels, mean);
        Self { light_paths, connections: args.connections, counts, pass: RwLock::new((LightPaths::new(), Vec::new())), reported: AtomicBool::new(false) }
    }

    /// Trace the pass's M light paths (t = 1 splats to `splat`, to be scaled by 1/M) and
    /// build its cache.
    pub fn prepare_pass(&self, scene: &Scene, accel: &Accel, params: &RenderParams, pass: u32, splat: &mut dyn FnMut(Splat)) -> PassStats {
        let parts: Vec<(LightPaths, Vec<Splat>, Counters)> = chunks(self.light_paths, LIGHT_CHUNK)
            .into_par_iter()
            .with_max_len(1)
            .map(|r| {
                let (mut paths, mut splats) = (LightPaths::new(), Vec::new());
                let c = lvcbpt::trace_light_paths(scene, accel, params, &self.counts, pass, r, &mut paths, &mut |s| splats.push(s));
                (paths, splats, c)
            })
            .collect();
        let mut guard = self.pass.write().unwrap_or_else(|e| e.into_inner());
        let (paths, cache) = &mut *guard;
        paths.clear();
        cache.clear();
        let mut counters = Counters::default();
        for (p, splats, c) in &parts {
            paths.append(p);
            for s in splats {
                splat(*s);
            }
            counters += *c;
        }
        lvcbpt::build_cache(scene, paths, cache);
        if !self.reported.swap(true, Ordering::Relaxed) {
            let (p, c) = (paths.size_bytes(), cache.capacity() * std::mem::size_of::<CacheEntry>());
            eprintln!("lvcbpt     memory per pass: light paths {:.1} MiB, cache {:.1} MiB ({} vertices)", mib(p), mib(c), cache.len());
        }
        stats(counters, self.light_paths as usize)
    }

    pub fn camera_pass(&self, scene: &Scene, accel: &Accel, params: &RenderParams, pass: u32, pixels: Range<u32>, out: &mut [Rgb]) -> PassStats {
        let guard = self.pass.read().unwrap_or_else(|e| e.into_inner());
        let (paths, cache) = &*guard;
        let inputs = PassInputs { paths, cache, light_paths: self.light_paths, connections: self.connections, counts: self.counts };
        let n = pixels.len();
        stats(lvcbpt::render_pixels(scene, accel, params, &inputs, pass, pixels, out), n)
    }

    /// Bytes held by the pass's light paths and cache.
    pub fn size_bytes(&self) -> usize {
        let guard = self.pass.read().unwrap_or_else(|e| e.into_inner());
        guard.0.size_bytes() + guard.1.capacity() * std::mem::size_of::<CacheEntry>()
    }
}

/// SPCBPT's model (built once, before rendering) and the current pass's cache.
#[derive(Debug)]
pub struct SpcbptHost {
    pub light_paths: u32,
    pub model: spcbpt::Model,
    pub report: SpcbptReport,
    pass: RwLock<spcbpt::PassCache>,
    /// The cache sizes are printed once, after the first pass.
    reported: AtomicBool,
}

/// What preprocessing did (printed by the host, kept for tools).
#[derive(Clone, Debug, Default)]
pub struct SpcbptReport {
    pub seconds: f64,
    pub phases: Vec<(&'static str, f64)>,
    pub losses: Vec<f64>,
    pub dataset_paths: usize,
    pub dataset_bytes: usize,
    pub tree_bytes: usize,
    pub gamma_bytes: usize,
    pub n_eye: u32,
    pub n_light: u32,
    /// Light subspaces that are light-source bins (0: s = 1 by NEE).
    pub light_source_bins: u32,
}

use ember_core::integrator::spcbpt::{self, prepare};
use ember_core::spcbpt::{AdamParams, TrainParams, TrainingSet};

impl SpcbptHost {
    /// Preprocessing: κ_L, the dataset's eye features, κ_E, Q, the training set, Γ.
    pub fn new(scene: &Scene, accel: &Accel, params: &RenderParams, args: &CacheArgs) -> Self {
        let start = std::time::Instant::now();
        let mut report = SpcbptReport::default();
        let mut lap = std::time::Instant::now();
        let mut phase = |name: &'static str, report: &mut SpcbptReport| {
            report.phases.push((name, lap.elapsed().as_secs_f64()));
            lap = std::time::Instant::now();
        };
        let (w, h) = (scene.camera.width(), scene.camera.height());
        let pixels = w * h;
        let light_paths = args.light_paths_for(pixels);
        let dataset = args.dataset_for(pixels);
        let q_paths = args.q_paths_for(pixels);
        let light_tracing = light_paths as f64 / pixels.max(1) as f64;
        const FIT_CAP: usize = 200_000;

        // κ_L from the vertices of light paths (as many as dataset samples, capped).
        let light_probe = dataset.min(FIT_CAP as u32);
        let parts: Vec<_> = chunks(light_probe, LIGHT_CHUNK).into_par_iter().map(|r| {
            let (mut f, mut wt) = (Vec::new(), Vec::new());
            prepare::light_features(scene, accel, params, r, &mut f, &mut wt);
            (f, wt)
        }).collect();
        let (mut lf, mut lw) = (Vec::new(), Vec::new());
        for (f, wt) in parts {
            lf.extend(f);
            lw.extend(wt);
        }
        lf.truncate(FIT_CAP);
        lw.truncate(FIT_CAP);
        // Light-source bins take their share of N_S when the scene can use them.
        let subspaces = args.subspaces_for(dataset);
        let wanted = ((args.light_source_share * subspaces as f32).round() as u32).min(subspaces - 1);
        let probe = spcbpt::light_source_bins(scene, wanted, 0);
        let surface_subspaces = subspaces - probe.as_ref().map_or(0, |b| b.bin_count()).min(subspaces - 1);
        let (light_tree, n_light_surface) = prepare::fit_side(&lf, &lw, surface_subspaces as usize, args.k_d, params.seed ^ 0x11);
        let sources = match spcbpt::light_source_bins(scene, wanted, n_light_surface) {
            Ok(bins) => Some(bins),
            Err(why) => {
                if wanted > 0 {
                    eprintln!("spcbpt     light sources not binned ({why}): s = 1 is next-event estimation");
                }
                None
            }
        };
        report.light_source_bins = sources.as_ref().map_or(0, |b| b.bin_count());
        drop((lf, lw));
        phase("light classification", &mut report);

        // Dataset pass 1: eye features and block brightness.
        let blocks_n = (w.div_ceil(prepare::BLOCK) * h.div_ceil(prepare::BLOCK)) as usize;
        let parts: Vec<_> = chunks(dataset, LIGHT_CHUNK).into_par_iter().map(|r| {
            let (mut f, mut wt) = (Vec::new(), Vec::new());
            let (mut b, mut bs) = (vec![0.0f64; blocks_n], vec![0u32; blocks_n]);
            prepare::dataset_features(scene, accel, params, r, &mut f, &mut wt, &mut b, &mut bs);
            (f, wt, b, bs)
        }).collect();
        let (mut ef, mut ew) = (Vec::new(), Vec::new());
        let (mut blocks, mut block_samples) = (vec![0.0f64; blocks_n], vec![0u32; blocks_n]);
        for (f, wt, b, bs) in parts {
            if ef.len() < FIT_CAP {
                ef.extend(f);
                ew.extend(wt);
            }
            for i in 0..blocks_n {
                blocks[i] += b[i];
                block_samples[i] += bs[i];
            }
        }
        ef.truncate(FIT_CAP);
        ew.truncate(FIT_CAP);
        let (eye_tree, n_eye) = prepare::fit_side(&ef, &ew, subspaces as usize, args.k_d, params.seed ^ 0x22);
        drop((ef, ew));
        let block_mean: Vec<f64> = blocks.iter().zip(&block_samples).map(|(s, &n)| if n > 0 { s / n as f64 } else { 0.0 }).collect();
        let classifier = spcbpt::Classifier::new(eye_tree, n_eye, light_tree, n_light_surface, sources);
        let n_light = classifier.n_light;
        phase("eye classification (dataset pass 1)", &mut report);

        // Q (eq. 19) over M' light paths.
        let parts: Vec<Vec<f64>> = chunks(q_paths, LIGHT_CHUNK).into_par_iter().map(|r| {
            let mut q = vec![0.0f64; n_light as usize];
            prepare::accumulate_q(scene, accel, params, &classifier, r, &mut q);
            q
        }).collect();
        let mut q = vec![0.0f64; n_light as usize];
        for part in parts {
            for (a, b) in q.iter_mut().zip(part) {
                *a += b;
            }
        }
        let q: Vec<f32> = q.iter().map(|v| (v / q_paths as f64) as f32).collect();
        phase("Q", &mut report);

        // Dataset pass 2: the training set.
        let parts: Vec<TrainingSet> = chunks(dataset, LIGHT_CHUNK).into_par_iter().map(|r| {
            let mut set = TrainingSet::new();
            prepare::dataset_records(scene, accel, params, &classifier, &q, args.connections, light_tracing, &block_mean, r, &mut set);
            set
        }).collect();
        let mut set = TrainingSet::new();
        for p in &parts {
            set.append(p);
        }
        drop(parts);
        report.dataset_paths = set.len();
        report.dataset_bytes = set.size_bytes();
        phase("training set (dataset pass 2)", &mut report);

        // Γ by Adam.
        let (nl, ne) = (n_light as usize, n_eye as usize);
        let mut theta = vec![0.0f32; nl * ne];
        let train = TrainParams {
            adam: AdamParams { learning_rate: args.learning_rate, ..AdamParams::default() },
            batch: args.batch.max(1),
            epochs: args.epochs,
            mixture: args.mixture,
            seed: params.seed ^ 0x33,
        };
        report.losses = ember_core::spcbpt::train(&set, &mut theta, nl, ne, &train);
        drop(set); // D is freed once Γ is trained.
        let gamma = ember_core::spcbpt::SubspaceMatrix::from_theta(&theta, nl, ne, args.mixture);
        phase("training", &mut report);

        report.tree_bytes = classifier.size_bytes();
        report.gamma_bytes = gamma.size_bytes();
        report.n_eye = n_eye;
        report.n_light = n_light;
        report.seconds = start.elapsed().as_secs_f64();
        let model = spcbpt::Model { classifier, q, gamma, connections: args.connections };
        Self { light_paths, model, report, pass: RwLock::new(spcbpt::PassCache::with_reuse(args.reuse)), reported: AtomicBool::new(false) }
    }

    pub fn prepare_pass(&self, scene: &Scene, accel: &Accel, params: &RenderParams, pass: u32, splat: &mut dyn FnMut(Splat)) -> PassStats {
        let parts: Vec<(LightPaths, Vec<spcbpt::PrefixMemo>, Counters)> = chunks(self.light_paths, LIGHT_CHUNK)
            .into_par_iter()
            .with_max_len(1)
            .map(|r| {
                let (mut paths, mut memo) = (LightPaths::new(), Vec::new());
                let c = spcbpt::trace_light_paths(scene, accel, params, &self.model, pass, r, &mut paths, &mut memo);
                (paths, memo, c)
            })
            .collect();
        let mut guard = self.pass.write().unwrap_or_else(|e| e.into_inner());
        let cache = &mut *guard;
        cache.paths.clear();
        cache.memo.clear();
        let mut counters = Counters::default();
        for (p, m, c) in &parts {
            cache.paths.append(p);
            cache.memo.extend_from_slice(m);
            counters += *c;
        }
        drop(parts);
        spcbpt::build_buckets(scene, &self.model, cache);
        let n_eye = self.model.classifier.n_eye;
        let mut tables = vec![None; n_eye as usize];
        let mut norms = vec![0.0f32; n_eye as usize];
        const EYE_CHUNK: usize = 64;
        tables.par_chunks_mut(EYE_CHUNK).zip(norms.par_chunks_mut(EYE_CHUNK)).enumerate().for_each(|(c, (t, n))| {
            let start = (c * EYE_CHUNK) as u32;
            spcbpt::build_gamma_tables(&self.model, cache, start..start + t.len() as u32, t, n);
        });
        cache.gamma_tables = tables;
        cache.gamma_norm = norms;
        if !self.reported.swap(true, Ordering::Relaxed) {
            let (total, paths, retained) = (cache.size_bytes(), cache.paths.size_bytes(), cache.retained.size_bytes());
            let kept: usize = cache.retained.fifos.iter().map(|f| f.len()).sum();
            eprintln!(
                "spcbpt     memory after the first pass: light paths {:.1} MiB, buckets + stage tables {:.1} MiB, reuse FIFOs {:.1} MiB ({kept} vertices, at most M0 = {} × {} subspaces)",
                mib(paths), mib(total - paths - retained), mib(retained), cache.retained.capacity, self.model.classifier.n_light
            );
        }
        let cache = &*cache;
        let light_tracing = self.light_paths as f64 / (scene.camera.width() * scene.camera.height()).max(1) as f64;
        let splats: Vec<(Vec<Splat>, Counters)> = chunks(self.light_paths, LIGHT_CHUNK)
            .into_par_iter()
            .with_max_len(1)
            .map(|r| {
                let mut out = Vec::new();
                let c = spcbpt::splat_light_paths(scene, accel, params, &self.model, cache, light_tracing, r, &mut |s| out.push(s));
                (out, c)
            })
            .collect();
        for (list, c) in splats {
            for s in list {
                splat(s);
            }
            counters += c;
        }
        stats(counters, self.light_paths as usize)
    }

    pub fn camera_pass(&self, scene: &Scene, accel: &Accel, params: &RenderParams, pass: u32, pixels: Range<u32>, out: &mut [Rgb]) -> PassStats {
        let guard = self.pass.read().unwrap_or_else(|e| e.into_inner());
        let n = pixels.len();
        stats(spcbpt::render_pixels(scene, accel, params, &self.model, &guard, self.light_paths, pass, pixels, out), n)
    }

    /// Bytes of the pass cache (light paths, buckets, both stages' tables).
    pub fn cache_bytes(&self) -> usize {
        self.pass.read().unwrap_or_else(|e| e.into_inner()).size_bytes()
    }
}
