//! The segment estimators' phases (the render protocol, [`crate::render`]):
//!
//! | stage | phase | items | reduction |
//! |---|---|---|---|
//! | setup 0 | `footprint` | W·H pixels (none unless the disk kernel's radius is in pixel footprints) | mean footprint → r |
//! | pass 0 | `camera` (segment PT, segment BDPT) or `light paths` (segment LT, W·H paths) | W·H | camera samples staged, splats pushed (LT, BDPT's t = 1); pass committed with splat factor 1/(W·H) |

use super::{sbdpt, slt, spt};
use crate::camera::CameraPass;
use crate::estimators::{ChunkOutput, PhaseData};
use crate::estimators::{KernelChoice, SegmentAlgorithm, SegmentConfig};
use crate::geometry::RayQuery;
use crate::render::{Context, Cursor, Film, Phase, Phased, Stage};
use crate::segment::Kernel;
use crate::transport::RenderParams;

/// Items per chunk.
const CHUNK: u32 = 1024;

/// Segment PT, LT or BDPT configured for one film.
#[derive(Clone, Debug)]
pub struct Segments {
    /// Settings shared by the estimators.
    pub params: RenderParams,
    /// Which estimator.
    pub algorithm: SegmentAlgorithm,
    /// The configuration it was built with.
    pub config: SegmentConfig,
    /// The kernel, its radius resolved by the setup phase.
    pub kernel: Kernel,
    pixels: u32,
    cursor: Cursor,
}

impl Segments {
    /// The estimator for a film of `pixels` pixels.
    pub fn new(params: RenderParams, algorithm: SegmentAlgorithm, config: SegmentConfig, pixels: u32) -> Self {
        let kernel = match config.kernel {
            KernelChoice::Dirac => Kernel::Dirac,
            KernelChoice::Disk => Kernel::Disk { radius: 0.0 },
        };
        Self { params, algorithm, config, kernel, pixels, cursor: Cursor::new(1, 1) }
    }
}

/// The segment estimators' phase ids: the footprint (setup), then the pass's one phase (camera or light paths).
mod phase {
    pub const FOOTPRINT: u8 = 0;
    pub const PASS: u8 = 1;
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Segments {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        Some(match self.cursor.stage()? {
            Stage::Setup(_) => {
                let needs = !self.kernel.is_dirac() && self.config.radius.needs_footprint();
                Phase { name: "footprint", id: phase::FOOTPRINT, pass: None, items: if needs { self.pixels } else { 0 }, chunk: CHUNK, samples: false }
            }
            Stage::Pass(pass, _) => {
                let name = if self.algorithm == SegmentAlgorithm::LightTracing { "light paths" } else { "camera" };
                Phase { name, id: phase::PASS, pass: Some(pass), items: self.pixels, chunk: CHUNK, samples: true }
            }
        })
    }
    fn start_pass(&mut self, pass: u32) {
        self.cursor.start_pass(pass);
    }
    fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput) {
        let (scene, tracer, params) = (ctx.scene, ctx.tracer, &self.params);
        let items = out.items.clone();
        match (phase.id, phase.pass) {
            (phase::FOOTPRINT, _) => crate::estimators::map_footprint(scene, tracer, out),
            (phase::PASS, Some(pass)) => match self.algorithm {
                SegmentAlgorithm::PathTracing => {
                    out.counters = spt::render_pixels(scene, tracer, params, self.kernel, pass, items, out.pixel_buffer());
                }
                SegmentAlgorithm::LightTracing => {
                    let splats = &mut out.splats;
                    out.counters = slt::trace_paths(scene, tracer, params, self.kernel, pass, items, &mut |s| splats.push(s));
                }
                SegmentAlgorithm::Bidirectional => {
                    let (pixels, splats) = out.pixels_and_splats();
                    out.counters = sbdpt::render_pixels(scene, tracer, params, self.kernel, pass, items, pixels, &mut |s| splats.push(s));
                }
            },
            _ => {}
        }
    }
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        if phase.id == phase::FOOTPRINT {
            if let Kernel::Disk { radius } = &mut self.kernel {
                *radius = self.config.radius.initial_radius(ctx.scene, &crate::estimators::reduce_footprint(outputs));
            }
        } else {
            for out in outputs.iter() {
                if self.algorithm != SegmentAlgorithm::LightTracing {
                    film.set_camera_samples(CameraPass { seed: self.params.seed, pass: phase.pass.unwrap_or(0) }, out.items.clone(), &out.pixels);
                }
                film.push_splats(&out.splats);
            }
        }
        if self.cursor.advance() {
            film.end_pass(1.0 / self.pixels.max(1) as f64);
        }
    }
}
