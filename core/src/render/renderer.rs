//! The estimators behind one value: [`Renderer`] dispatches the protocol to PT, LT,
//! BDPT (one phase per pass each, written here) and to LVCBPT, SPCBPT and the merging
//! estimators and the segment estimators (whose phases live in their modules).

use crate::geometry::RayQuery;
use crate::integrator::lvcbpt::Lvcbpt;
use crate::integrator::spcbpt::Spcbpt;
use crate::integrator::vcm::Vcm;
use crate::integrator::{RenderParams, bdpt, lt, pt};
use crate::scene::Scene;
use crate::segment::Segments;
use crate::segment::filter::{Bpf, Mvf, Phf};

use super::{ChunkOutput, ConfigError, Context, Cursor, EstimatorConfig, EstimatorKind, Film, FilterSide, Phase, Phased, Stage};

/// Pixels per chunk of a camera phase, light paths per chunk of a light phase.
pub const CHUNK: u32 = 1024;

/// Which of the one-phase estimators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Simple {
    Pt,
    Lt,
    Bdpt,
}

/// PT, LT and BDPT: one phase per pass over every pixel (PT, BDPT) or W·H light paths
/// (LT); BDPT and LT splat, scaled by 1/(W·H).
#[derive(Clone, Debug)]
pub struct OnePhase {
    which: Simple,
    params: RenderParams,
    pixels: u32,
    cursor: Cursor,
}

impl OnePhase {
    fn new(which: Simple, params: RenderParams, pixels: u32) -> Self {
        Self { which, params, pixels, cursor: Cursor::new(0, 1) }
    }
}

impl<Q: RayQuery + ?Sized> Phased<Q> for OnePhase {
    fn next_phase(&self) -> Option<Phase> {
        let Some(Stage::Pass(pass, 0)) = self.cursor.stage() else { return None };
        let name = if self.which == Simple::Lt { "light paths" } else { "camera" };
        Some(Phase { name, id: 0, pass: Some(pass), items: self.pixels, chunk: CHUNK, samples: true })
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
            Simple::Bdpt => {
                let (pixels, splats) = out.pixels_and_splats();
                bdpt::render_pixels(scene, tracer, params, pass, items, pixels, &mut |s| splats.push(s))
            }
            Simple::Lt => {
                let splats = &mut out.splats;
                lt::trace_paths(scene, tracer, params, pass, items, &mut |s| splats.push(s))
            }
        };
    }
    fn reduce(&mut self, _ctx: &Context<'_, Q>, _phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        for out in outputs.iter() {
            if self.which != Simple::Lt {
                film.set_camera_samples(out.items.clone(), &out.pixels);
            }
            film.push_splats(&out.splats);
        }
        if self.cursor.advance() {
            film.end_pass(1.0 / self.pixels.max(1) as f64);
        }
    }
}

/// Any of the core's estimators, configured for one scene.
#[derive(Debug)]
pub enum Renderer {
    /// PT, LT or BDPT.
    OnePhase(OnePhase),
    /// LVCBPT.
    Lvcbpt(Lvcbpt),
    /// SPCBPT (boxed: its model is large).
    Spcbpt(alloc::boxed::Box<Spcbpt>),
    /// PPM, BPM or VCM.
    Merging(alloc::boxed::Box<Vcm>),
    /// Segment PT, LT or BDPT.
    Segment(Segments),
    /// Multi-vertex path filtering.
    Filter(alloc::boxed::Box<Mvf>),
    /// Photon filtering.
    PhotonFilter(alloc::boxed::Box<Phf>),
    /// Bidirectional path filtering.
    BidirectionalFilter(alloc::boxed::Box<Bpf>),
}

impl Renderer {
    /// The estimator `config` names, for `scene`, with `params`. Allocates nothing
    /// large: setup happens in the setup phases.
    pub fn new(scene: &Scene, params: RenderParams, config: EstimatorConfig) -> Result<Self, ConfigError> {
        config.validate()?;
        let pixels = scene.camera.width() * scene.camera.height();
        Ok(match config {
            EstimatorConfig::Pt => Self::OnePhase(OnePhase::new(Simple::Pt, params, pixels)),
            EstimatorConfig::Lt => Self::OnePhase(OnePhase::new(Simple::Lt, params, pixels)),
            EstimatorConfig::Bdpt => Self::OnePhase(OnePhase::new(Simple::Bdpt, params, pixels)),
            EstimatorConfig::Lvcbpt(c) => Self::Lvcbpt(Lvcbpt::new(params, c, pixels)),
            EstimatorConfig::Spcbpt(c) => Self::Spcbpt(alloc::boxed::Box::new(Spcbpt::new(params, c, scene.camera.width(), scene.camera.height()))),
            EstimatorConfig::Merging(mode, c) => Self::Merging(alloc::boxed::Box::new(Vcm::new(params, mode, c, pixels))),
            EstimatorConfig::Segment(a, c) => Self::Segment(Segments::new(params, a, c, pixels)),
            EstimatorConfig::Filter(FilterSide::Camera, c) => Self::Filter(alloc::boxed::Box::new(Mvf::new(params, c, pixels))),
            EstimatorConfig::Filter(FilterSide::Light, c) => Self::PhotonFilter(alloc::boxed::Box::new(Phf::new(params, c, pixels))),
            EstimatorConfig::Filter(FilterSide::Both, c) => Self::BidirectionalFilter(alloc::boxed::Box::new(Bpf::new(params, c, pixels))),
        })
    }

    /// Which estimator this is.
    pub fn kind(&self) -> EstimatorKind {
        match self {
            Self::OnePhase(o) => match o.which {
                Simple::Pt => EstimatorKind::Pt,
                Simple::Lt => EstimatorKind::Lt,
                Simple::Bdpt => EstimatorKind::Bdpt,
            },
            Self::Lvcbpt(_) => EstimatorKind::Lvcbpt,
            Self::Spcbpt(_) => EstimatorKind::Spcbpt,
            Self::Merging(m) => EstimatorConfig::Merging(m.mode, m.config).kind(),
            Self::Segment(s) => EstimatorConfig::Segment(s.algorithm, s.config).kind(),
            Self::Filter(_) => EstimatorKind::Mvf,
            Self::PhotonFilter(_) => EstimatorKind::Phf,
            Self::BidirectionalFilter(_) => EstimatorKind::Bpf,
        }
    }

    /// The settings shared by the estimators.
    pub fn params(&self) -> &RenderParams {
        match self {
            Self::OnePhase(o) => &o.params,
            Self::Lvcbpt(l) => &l.params,
            Self::Spcbpt(s) => &s.params,
            Self::Merging(m) => &m.params,
            Self::Segment(s) => &s.params,
            Self::Filter(f) => &f.params,
            Self::PhotonFilter(f) => &f.params,
            Self::BidirectionalFilter(f) => &f.params,
        }
    }
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Renderer {
    fn next_phase(&self) -> Option<Phase> {
        match self {
            Self::OnePhase(o) => Phased::<Q>::next_phase(o),
            Self::Lvcbpt(l) => Phased::<Q>::next_phase(l),
            Self::Spcbpt(s) => Phased::<Q>::next_phase(&**s),
            Self::Merging(m) => Phased::<Q>::next_phase(&**m),
            Self::Segment(s) => Phased::<Q>::next_phase(s),
            Self::Filter(f) => Phased::<Q>::next_phase(&**f),
            Self::PhotonFilter(f) => Phased::<Q>::next_phase(&**f),
            Self::BidirectionalFilter(f) => Phased::<Q>::next_phase(&**f),
        }
    }
    fn start_pass(&mut self, pass: u32) {
        match self {
            Self::OnePhase(o) => Phased::<Q>::start_pass(o, pass),
            Self::Lvcbpt(l) => Phased::<Q>::start_pass(l, pass),
            Self::Spcbpt(s) => Phased::<Q>::start_pass(&mut **s, pass),
            Self::Merging(m) => Phased::<Q>::start_pass(&mut **m, pass),
            Self::Segment(s) => Phased::<Q>::start_pass(s, pass),
            Self::Filter(f) => Phased::<Q>::start_pass(&mut **f, pass),
            Self::PhotonFilter(f) => Phased::<Q>::start_pass(&mut **f, pass),
            Self::BidirectionalFilter(f) => Phased::<Q>::start_pass(&mut **f, pass),
        }
    }
    fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput) {
        match self {
            Self::OnePhase(o) => o.map(ctx, phase, out),
            Self::Lvcbpt(l) => l.map(ctx, phase, out),
            Self::Spcbpt(s) => s.map(ctx, phase, out),
            Self::Merging(m) => m.map(ctx, phase, out),
            Self::Segment(s) => s.map(ctx, phase, out),
            Self::Filter(f) => f.map(ctx, phase, out),
            Self::PhotonFilter(f) => f.map(ctx, phase, out),
            Self::BidirectionalFilter(f) => f.map(ctx, phase, out),
        }
    }
    fn replay_pass(&mut self, pass: u32) -> bool {
        match self {
            Self::Spcbpt(s) => Phased::<Q>::replay_pass(&mut **s, pass),
            _ => false,
        }
    }
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        match self {
            Self::OnePhase(o) => o.reduce(ctx, phase, outputs, film),
            Self::Lvcbpt(l) => l.reduce(ctx, phase, outputs, film),
            Self::Spcbpt(s) => s.reduce(ctx, phase, outputs, film),
            Self::Merging(m) => m.reduce(ctx, phase, outputs, film),
            Self::Segment(s) => s.reduce(ctx, phase, outputs, film),
            Self::Filter(f) => f.reduce(ctx, phase, outputs, film),
            Self::PhotonFilter(f) => f.reduce(ctx, phase, outputs, film),
            Self::BidirectionalFilter(f) => f.reduce(ctx, phase, outputs, film),
        }
    }
}
