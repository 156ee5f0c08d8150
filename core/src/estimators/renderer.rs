//! The estimators behind one value: [`Renderer`] dispatches the render protocol to each
//! estimator of the registry ([`super::EstimatorKind`]): PT, LT and BDPT
//! ([`super::one_phase`]), LVCBPT, SPCBPT, the merging estimators, the segment estimators
//! and the filters (whose phases live in their homes).
//!
//! Each estimator's variant exists only where its cargo feature is on (docs/features.md);
//! [`Renderer::new`] refuses the others with [`RendererError::NotCompiled`].

use core::fmt;

#[cfg(feature = "filtering")]
use super::FilterSide;
#[cfg(feature = "filtering")]
use super::filter::{Bpf, Mvf, Phf};
#[cfg(feature = "lvcbpt")]
use super::lvcbpt::Lvcbpt;
use super::one_phase::{OnePhase, Simple};
#[cfg(feature = "segments")]
use super::segment::Segments;
#[cfg(feature = "spcbpt")]
use super::spcbpt::Spcbpt;
#[cfg(feature = "merging")]
use super::vcm::Vcm;
use super::{ChunkOutput, EstimatorConfig, EstimatorKind, PhaseData};
use crate::geometry::RayQuery;
use crate::render::{Context, Film, Phase, Phased};
use crate::scene::Scene;
use crate::transport::RenderParams;
use crate::transport::config::ConfigError;

/// Any of the core's estimators, configured for one scene.
#[derive(Debug)]
pub enum Renderer {
    /// PT, LT or BDPT.
    OnePhase(OnePhase),
    /// LVCBPT.
    #[cfg(feature = "lvcbpt")]
    Lvcbpt(Lvcbpt),
    /// SPCBPT (boxed: its model is large).
    #[cfg(feature = "spcbpt")]
    Spcbpt(alloc::boxed::Box<Spcbpt>),
    /// PPM, BPM or VCM.
    #[cfg(feature = "merging")]
    Merging(alloc::boxed::Box<Vcm>),
    /// Segment PT, LT or BDPT.
    #[cfg(feature = "segments")]
    Segment(Segments),
    /// Multi-vertex path filtering.
    #[cfg(feature = "filtering")]
    Filter(alloc::boxed::Box<Mvf>),
    /// Photon filtering.
    #[cfg(feature = "filtering")]
    PhotonFilter(alloc::boxed::Box<Phf>),
    /// Bidirectional path filtering.
    #[cfg(feature = "filtering")]
    BidirectionalFilter(alloc::boxed::Box<Bpf>),
}

/// Why [`Renderer::new`] refused a configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RendererError {
    /// A value outside its range.
    Config(ConfigError),
    /// The estimator's code is not in this build of `ember-core`: its cargo feature is
    /// off ([`EstimatorKind::is_compiled`]).
    NotCompiled {
        /// The estimator asked for.
        estimator: EstimatorKind,
        /// The cargo feature of `ember-core` that compiles it.
        feature: &'static str,
    },
}

impl From<ConfigError> for RendererError {
    fn from(e: ConfigError) -> Self {
        Self::Config(e)
    }
}

impl fmt::Display for RendererError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Config(e) => e.fmt(f),
            Self::NotCompiled { estimator, feature } => {
                write!(f, "{estimator} is not compiled into this build: enable the cargo feature `{feature}` of ember-core")
            }
        }
    }
}

impl core::error::Error for RendererError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Config(e) => Some(e),
            Self::NotCompiled { .. } => None,
        }
    }
}

impl Renderer {
    /// The estimator `config` names, for `scene`, with `params`. Allocates nothing
    /// large: setup happens in the setup phases. Refuses a configuration out of range
    /// ([`RendererError::Config`]) and an estimator this build leaves out
    /// ([`RendererError::NotCompiled`], checked after the ranges).
    pub fn new(scene: &Scene, params: RenderParams, config: EstimatorConfig) -> Result<Self, RendererError> {
        config.validate()?;
        let pixels = scene.camera.width() * scene.camera.height();
        Ok(match config {
            EstimatorConfig::Pt => Self::OnePhase(OnePhase::new(Simple::Pt, params, pixels)),
            EstimatorConfig::Lt => Self::OnePhase(OnePhase::new(Simple::Lt, params, pixels)),
            #[cfg(feature = "bdpt")]
            EstimatorConfig::Bdpt => Self::OnePhase(OnePhase::new(Simple::Bdpt, params, pixels)),
            #[cfg(feature = "bdpt")]
            EstimatorConfig::PtMoment => Self::OnePhase(OnePhase::new(Simple::PtMoment, params, pixels)),
            #[cfg(feature = "lvcbpt")]
            EstimatorConfig::Lvcbpt(c) => Self::Lvcbpt(Lvcbpt::new(params, c, pixels)),
            #[cfg(feature = "spcbpt")]
            EstimatorConfig::Spcbpt(c) => Self::Spcbpt(alloc::boxed::Box::new(Spcbpt::new(params, c, scene.camera.width(), scene.camera.height()))),
            #[cfg(feature = "merging")]
            EstimatorConfig::Merging(mode, c) => Self::Merging(alloc::boxed::Box::new(Vcm::new(params, mode, c, pixels))),
            #[cfg(feature = "segments")]
            EstimatorConfig::Segment(a, c) => Self::Segment(Segments::new(params, a, c, pixels)),
            #[cfg(feature = "filtering")]
            EstimatorConfig::Filter(FilterSide::Camera, c) => Self::Filter(alloc::boxed::Box::new(Mvf::new(params, c, pixels))),
            #[cfg(feature = "filtering")]
            EstimatorConfig::Filter(FilterSide::Light, c) => Self::PhotonFilter(alloc::boxed::Box::new(Phf::new(params, c, pixels))),
            #[cfg(feature = "filtering")]
            EstimatorConfig::Filter(FilterSide::Both, c) => Self::BidirectionalFilter(alloc::boxed::Box::new(Bpf::new(params, c, pixels))),
            #[cfg(not(all(feature = "bdpt", feature = "lvcbpt", feature = "spcbpt", feature = "merging", feature = "segments", feature = "filtering")))]
            other => {
                let estimator = other.kind();
                return Err(RendererError::NotCompiled { estimator, feature: estimator.cargo_feature().unwrap_or("default") });
            }
        })
    }

    /// Which estimator this is.
    pub fn kind(&self) -> EstimatorKind {
        match self {
            Self::OnePhase(o) => match o.which {
                Simple::Pt => EstimatorKind::Pt,
                Simple::Lt => EstimatorKind::Lt,
                #[cfg(feature = "bdpt")]
                Simple::Bdpt | Simple::PtMoment => EstimatorKind::Bdpt,
            },
            #[cfg(feature = "lvcbpt")]
            Self::Lvcbpt(_) => EstimatorKind::Lvcbpt,
            #[cfg(feature = "spcbpt")]
            Self::Spcbpt(_) => EstimatorKind::Spcbpt,
            #[cfg(feature = "merging")]
            Self::Merging(m) => EstimatorConfig::Merging(m.mode, m.config).kind(),
            #[cfg(feature = "segments")]
            Self::Segment(s) => EstimatorConfig::Segment(s.algorithm, s.config).kind(),
            #[cfg(feature = "filtering")]
            Self::Filter(_) => EstimatorKind::Mvf,
            #[cfg(feature = "filtering")]
            Self::PhotonFilter(_) => EstimatorKind::Phf,
            #[cfg(feature = "filtering")]
            Self::BidirectionalFilter(_) => EstimatorKind::Bpf,
        }
    }

    /// The settings shared by the estimators.
    pub fn params(&self) -> &RenderParams {
        match self {
            Self::OnePhase(o) => &o.params,
            #[cfg(feature = "lvcbpt")]
            Self::Lvcbpt(l) => &l.params,
            #[cfg(feature = "spcbpt")]
            Self::Spcbpt(s) => &s.params,
            #[cfg(feature = "merging")]
            Self::Merging(m) => &m.params,
            #[cfg(feature = "segments")]
            Self::Segment(s) => &s.params,
            #[cfg(feature = "filtering")]
            Self::Filter(f) => &f.params,
            #[cfg(feature = "filtering")]
            Self::PhotonFilter(f) => &f.params,
            #[cfg(feature = "filtering")]
            Self::BidirectionalFilter(f) => &f.params,
        }
    }
}

impl<Q: RayQuery + ?Sized> Phased<Q> for Renderer {
    type Data = PhaseData;
    fn next_phase(&self) -> Option<Phase> {
        match self {
            Self::OnePhase(o) => Phased::<Q>::next_phase(o),
            #[cfg(feature = "lvcbpt")]
            Self::Lvcbpt(l) => Phased::<Q>::next_phase(l),
            #[cfg(feature = "spcbpt")]
            Self::Spcbpt(s) => Phased::<Q>::next_phase(&**s),
            #[cfg(feature = "merging")]
            Self::Merging(m) => Phased::<Q>::next_phase(&**m),
            #[cfg(feature = "segments")]
            Self::Segment(s) => Phased::<Q>::next_phase(s),
            #[cfg(feature = "filtering")]
            Self::Filter(f) => Phased::<Q>::next_phase(&**f),
            #[cfg(feature = "filtering")]
            Self::PhotonFilter(f) => Phased::<Q>::next_phase(&**f),
            #[cfg(feature = "filtering")]
            Self::BidirectionalFilter(f) => Phased::<Q>::next_phase(&**f),
        }
    }
    fn start_pass(&mut self, pass: u32) {
        match self {
            Self::OnePhase(o) => Phased::<Q>::start_pass(o, pass),
            #[cfg(feature = "lvcbpt")]
            Self::Lvcbpt(l) => Phased::<Q>::start_pass(l, pass),
            #[cfg(feature = "spcbpt")]
            Self::Spcbpt(s) => Phased::<Q>::start_pass(&mut **s, pass),
            #[cfg(feature = "merging")]
            Self::Merging(m) => Phased::<Q>::start_pass(&mut **m, pass),
            #[cfg(feature = "segments")]
            Self::Segment(s) => Phased::<Q>::start_pass(s, pass),
            #[cfg(feature = "filtering")]
            Self::Filter(f) => Phased::<Q>::start_pass(&mut **f, pass),
            #[cfg(feature = "filtering")]
            Self::PhotonFilter(f) => Phased::<Q>::start_pass(&mut **f, pass),
            #[cfg(feature = "filtering")]
            Self::BidirectionalFilter(f) => Phased::<Q>::start_pass(&mut **f, pass),
        }
    }
    fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput) {
        match self {
            Self::OnePhase(o) => o.map(ctx, phase, out),
            #[cfg(feature = "lvcbpt")]
            Self::Lvcbpt(l) => l.map(ctx, phase, out),
            #[cfg(feature = "spcbpt")]
            Self::Spcbpt(s) => s.map(ctx, phase, out),
            #[cfg(feature = "merging")]
            Self::Merging(m) => m.map(ctx, phase, out),
            #[cfg(feature = "segments")]
            Self::Segment(s) => s.map(ctx, phase, out),
            #[cfg(feature = "filtering")]
            Self::Filter(f) => f.map(ctx, phase, out),
            #[cfg(feature = "filtering")]
            Self::PhotonFilter(f) => f.map(ctx, phase, out),
            #[cfg(feature = "filtering")]
            Self::BidirectionalFilter(f) => f.map(ctx, phase, out),
        }
    }
    fn replay_pass(&mut self, pass: u32) -> bool {
        // Only SPCBPT carries state from pass to pass.
        #[cfg(feature = "spcbpt")]
        if let Self::Spcbpt(s) = self {
            return Phased::<Q>::replay_pass(&mut **s, pass);
        }
        let _ = pass;
        false
    }
    fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
        match self {
            Self::OnePhase(o) => o.reduce(ctx, phase, outputs, film),
            #[cfg(feature = "lvcbpt")]
            Self::Lvcbpt(l) => l.reduce(ctx, phase, outputs, film),
            #[cfg(feature = "spcbpt")]
            Self::Spcbpt(s) => s.reduce(ctx, phase, outputs, film),
            #[cfg(feature = "merging")]
            Self::Merging(m) => m.reduce(ctx, phase, outputs, film),
            #[cfg(feature = "segments")]
            Self::Segment(s) => s.reduce(ctx, phase, outputs, film),
            #[cfg(feature = "filtering")]
            Self::Filter(f) => f.reduce(ctx, phase, outputs, film),
            #[cfg(feature = "filtering")]
            Self::PhotonFilter(f) => f.reduce(ctx, phase, outputs, film),
            #[cfg(feature = "filtering")]
            Self::BidirectionalFilter(f) => f.reduce(ctx, phase, outputs, film),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[cfg(not(feature = "merging"))]
    use crate::estimators::{MergeMode, MergingConfig};
    use crate::scene::builtin;

    /// In every build, whatever its features: an estimator is constructed exactly when it
    /// is compiled, and a refusal names the estimator and the feature that compiles it.
    #[test]
    fn renderer_new_follows_is_compiled() {
        let (scene, _, _) = builtin::cornell_box(4, 4).build().expect("builds");
        for kind in EstimatorKind::ALL {
            match Renderer::new(&scene, RenderParams::default(), kind.default_config()) {
                Ok(r) => {
                    assert!(kind.is_compiled(), "{kind} constructed but reported absent");
                    assert_eq!(r.kind(), kind);
                }
                Err(e) => {
                    assert!(!kind.is_compiled(), "{kind} refused in a build that holds it: {e}");
                    let feature = kind.cargo_feature().expect("PT and LT are always compiled");
                    assert_eq!(e, RendererError::NotCompiled { estimator: kind, feature });
                }
            }
        }
    }

    /// A build without `merging` (`cargo test -p ember-core --no-default-features --lib`)
    /// refuses PPM with the typed error, whose message says what to enable.
    #[cfg(not(feature = "merging"))]
    #[test]
    fn ppm_is_refused_without_the_merging_feature() {
        let (scene, _, _) = builtin::cornell_box(4, 4).build().expect("builds");
        assert!(!EstimatorKind::Ppm.is_compiled());
        let e = Renderer::new(&scene, RenderParams::default(), EstimatorKind::Ppm.default_config()).unwrap_err();
        assert_eq!(e, RendererError::NotCompiled { estimator: EstimatorKind::Ppm, feature: "merging" });
        assert_eq!(alloc::format!("{e}"), "ppm is not compiled into this build: enable the cargo feature `merging` of ember-core");
        // A value out of range is still reported as such, before the missing feature.
        let bad = EstimatorConfig::Merging(MergeMode::Ppm, MergingConfig { alpha: 0.0, ..MergingConfig::DEFAULT });
        assert!(matches!(Renderer::new(&scene, RenderParams::default(), bad), Err(RendererError::Config(ConfigError { field: "alpha", .. }))));
        assert!(Renderer::new(&scene, RenderParams::default(), EstimatorKind::Pt.default_config()).is_ok());
    }
}
