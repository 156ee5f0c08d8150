//! PT, LT and BDPT in the render protocol: one phase per pass over every pixel (PT,
//! BDPT; [`super::pt`], [`super::bdpt`]) or W·H light paths (LT, [`super::lt`]); BDPT's
//! t = 1 strategies and LT splat, scaled by 1/(W·H). (`PtMoment` is BDPT's samples with
//! PT's second-moment terms, [`super::bdpt::probe`].)

#[cfg(feature = "bdpt")]
use super::bdpt;
use super::{ChunkOutput, PhaseData, lt, pt};
use crate::camera::CameraPass;
use crate::geometry::RayQuery;
use crate::render::{Context, Cursor, Film, Phase, Phased, Stage, chunk_for};
use crate::transport::RenderParams;

/// Which of the one-phase estimators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Simple {
    Pt,
    Lt,
    #[cfg(feature = "bdpt")]
    Bdpt,
    #[cfg(feature = "bdpt")]
    PtMoment,
}

/// PT, LT and BDPT: one phase per pass over every pixel (PT, BDPT) or W·H light paths
/// (LT); BDPT and LT splat, scaled by 1/(W·H).
#[derive(Clone, Debug)]
pub struct OnePhase {
    pub(super) which: Simple,
    pub(super) params: RenderParams,
    pixels: u32,
    cursor: Cursor,
}

impl OnePhase {
    /// Which estimator this is (the second-moment probe is BDPT's samples).
    pub fn kind(&self) -> super::EstimatorKind {
        use super::EstimatorKind;
        match self.which {
            Simple::Pt => EstimatorKind::Pt,
            Simple::Lt => EstimatorKind::Lt,
            #[cfg(feature = "bdpt")]
            Simple::Bdpt | Simple::PtMoment => EstimatorKind::Bdpt,
        }
    }

    pub(super) fn new(which: Simple, params: RenderParams, pixels: u32) -> Self {
        Self { which, params, pixels, cursor: Cursor::new(0, 1) }
    }
}

impl<Q: RayQuery + ?Sized> Phased<Q> for OnePhase {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        let Some(Stage::Pass(pass, 0)) = self.cursor.stage() else { return None };
        let name = if self.which == Simple::Lt { "light paths" } else { "camera" };
        Some(Phase { name, id: 0, pass: Some(pass), items: self.pixels, chunk: chunk_for(self.pixels), samples: true })
    }
    fn start_pass(&mut self, pass: u32) {
        self.cursor.start_pass(pass);
    }
    fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput) {
        let (scene, tracer, params) = (ctx.scene, ctx.tracer, &self.params);
        let pass = phase.pass.unwrap_or(0);
        let items = out.items.clone();
        out.counters = match self.which {
            Simple::Pt => pt::render_pixels(scene, tracer, params, pass, items, out.pixel_buffer()),
            #[cfg(feature = "bdpt")]
            Simple::Bdpt => {
                let (pixels, splats) = out.pixels_and_splats();
                bdpt::render_pixels(scene, tracer, params, pass, items, pixels, &mut |s| splats.push(s))
            }
            #[cfg(feature = "bdpt")]
            Simple::PtMoment => {
                let (pixels, splats) = out.pixels_and_splats();
                bdpt::probe::render_pixels(scene, tracer, params, pass, items, pixels, &mut |s| splats.push(s))
            }
            Simple::Lt => {
                let splats = &mut out.splats;
                lt::trace_paths(scene, tracer, params, pass, items, &mut |s| splats.push(s))
            }
        };
    }
    fn reduce(&mut self, _ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        for out in outputs.iter() {
            if self.which != Simple::Lt {
                film.set_camera_samples(CameraPass { seed: self.params.seed, pass: phase.pass.unwrap_or(0) }, out.items.clone(), &out.pixels);
            }
            film.push_splats(&out.splats);
        }
        if self.cursor.advance() {
            film.end_pass(1.0 / self.pixels.max(1) as f64);
        }
    }
}
