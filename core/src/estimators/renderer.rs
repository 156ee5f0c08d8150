//! The estimators behind one value: [`Renderer`] dispatches the render protocol to each
//! estimator of the registry ([`super::EstimatorKind`]): PT, LT and BDPT
//! ([`super::one_phase`]), LVCBPT, SPCBPT, the merging estimators, the segment estimators
//! and the filters (whose phases live in their homes).
//!
//! Each estimator's variant exists only where its cargo feature is on (docs/features.md);
//! [`Renderer::new`] refuses the others with [`RendererError::NotCompiled`].

use alloc::boxed::Box;
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

/// Writes [`Renderer`], one boxed variant per estimator family (behind the family's cargo
/// feature), with its kind, its parameters and the protocol dispatched to the family's
/// own `Phased` implementation, from one row per family.
macro_rules! families {
    ($(
        $(#[doc = $doc:literal])*
        $variant:ident($family:ty) $(if $feature:literal)?, |$e:ident| $kind:expr;
    )*) => {
        /// Any of the core's estimators, configured for one scene.
        #[derive(Debug)]
        pub enum Renderer {
            $($(#[doc = $doc])* $(#[cfg(feature = $feature)])? $variant(Box<$family>),)*
        }

        impl Renderer {
            /// Which estimator this is.
            pub fn kind(&self) -> EstimatorKind {
                match self {
                    $($(#[cfg(feature = $feature)])? Self::$variant($e) => $kind,)*
                }
            }

            /// The settings shared by the estimators.
            pub fn params(&self) -> &RenderParams {
                match self {
                    $($(#[cfg(feature = $feature)])? Self::$variant(e) => &e.params,)*
                }
            }
        }

        impl<Q: RayQuery + ?Sized> Phased<Q> for Renderer {
            type Data = PhaseData;
            fn next_phase(&self) -> Option<Phase> {
                match self {
                    $($(#[cfg(feature = $feature)])? Self::$variant(e) => Phased::<Q>::next_phase(&**e),)*
                }
            }
            fn start_pass(&mut self, pass: u32) {
                match self {
                    $($(#[cfg(feature = $feature)])? Self::$variant(e) => Phased::<Q>::start_pass(&mut **e, pass),)*
                }
            }
            fn map(&self, ctx: &Context<'_, Q>, phase: &Phase, out: &mut ChunkOutput) {
                match self {
                    $($(#[cfg(feature = $feature)])? Self::$variant(e) => e.map(ctx, phase, out),)*
                }
            }
            fn replay_pass(&mut self, pass: u32) -> bool {
                match self {
                    $($(#[cfg(feature = $feature)])? Self::$variant(e) => Phased::<Q>::replay_pass(&mut **e, pass),)*
                }
            }
            fn reduce(&mut self, ctx: &Context<'_, Q>, phase: &Phase, outputs: &mut [ChunkOutput], film: &mut Film) {
                match self {
                    $($(#[cfg(feature = $feature)])? Self::$variant(e) => e.reduce(ctx, phase, outputs, film),)*
                }
            }
        }
    };
}

families! {
    /// PT, LT or BDPT.
    OnePhase(OnePhase), |o| o.kind();
    /// LVCBPT.
    Lvcbpt(Lvcbpt) if "lvcbpt", |_l| EstimatorKind::Lvcbpt;
    /// SPCBPT.
    Spcbpt(Spcbpt) if "spcbpt", |_s| EstimatorKind::Spcbpt;
    /// PPM, BPM or VCM.
    Merging(Vcm) if "merging", |m| EstimatorConfig::Merging(m.mode, m.config).kind();
    /// Segment PT, LT or BDPT.
    Segment(Segments) if "segments", |s| EstimatorConfig::Segment(s.algorithm, s.config).kind();
    /// Multi-vertex path filtering.
    Filter(Mvf) if "filtering", |_f| EstimatorKind::Mvf;
    /// Photon filtering.
    PhotonFilter(Phf) if "filtering", |_f| EstimatorKind::Phf;
    /// Bidirectional path filtering.
    BidirectionalFilter(Bpf) if "filtering", |_f| EstimatorKind::Bpf;
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
    /// Bidirectional path filtering with bridge segments in a scene with an absorbing
    /// medium: a bridge does not carry the medium's transmittance (docs/scene-features.md).
    BridgesInMedium,
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
            Self::BridgesInMedium => {
                write!(f, "bpf's bridge segments do not carry an absorbing medium's transmittance: render this scene without bridges")
            }
        }
    }
}

impl core::error::Error for RendererError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Config(e) => Some(e),
            Self::NotCompiled { .. } | Self::BridgesInMedium => None,
        }
    }
}

impl Renderer {
    /// The estimator `config` names, for `scene`, with `params`. Allocates nothing
    /// large: setup happens in the setup phases. Refuses a configuration out of range
    /// ([`RendererError::Config`]) and an estimator this build leaves out
    /// ([`RendererError::NotCompiled`], checked after the ranges), and BPF's bridges
    /// in a scene with an absorbing medium ([`RendererError::BridgesInMedium`]).
    pub fn new(scene: &Scene, params: RenderParams, config: EstimatorConfig) -> Result<Self, RendererError> {
        config.validate()?;
        #[cfg(feature = "filtering")]
        if let EstimatorConfig::Filter(FilterSide::Both, c) = config
            && c.bridges()
            && !scene.interiors.is_empty()
        {
            return Err(RendererError::BridgesInMedium);
        }
        let pixels = scene.camera.width() * scene.camera.height();
        Ok(match config {
            EstimatorConfig::Pt => Self::OnePhase(Box::new(OnePhase::new(Simple::Pt, params, pixels))),
            EstimatorConfig::Lt => Self::OnePhase(Box::new(OnePhase::new(Simple::Lt, params, pixels))),
            #[cfg(feature = "bdpt")]
            EstimatorConfig::Bdpt => Self::OnePhase(Box::new(OnePhase::new(Simple::Bdpt, params, pixels))),
            #[cfg(feature = "bdpt")]
            EstimatorConfig::PtMoment => Self::OnePhase(Box::new(OnePhase::new(Simple::PtMoment, params, pixels))),
            #[cfg(feature = "lvcbpt")]
            EstimatorConfig::Lvcbpt(c) => Self::Lvcbpt(Box::new(Lvcbpt::new(params, c, pixels))),
            #[cfg(feature = "spcbpt")]
            EstimatorConfig::Spcbpt(c) => Self::Spcbpt(Box::new(Spcbpt::new(params, c, scene.camera.width(), scene.camera.height()))),
            #[cfg(feature = "merging")]
            EstimatorConfig::Merging(mode, c) => Self::Merging(Box::new(Vcm::new(params, mode, c, pixels))),
            #[cfg(feature = "segments")]
            EstimatorConfig::Segment(a, c) => Self::Segment(Box::new(Segments::new(params, a, c, pixels))),
            #[cfg(feature = "filtering")]
            EstimatorConfig::Filter(FilterSide::Camera, c) => Self::Filter(Box::new(Mvf::new(params, c, pixels))),
            #[cfg(feature = "filtering")]
            EstimatorConfig::Filter(FilterSide::Light, c) => Self::PhotonFilter(Box::new(Phf::new(params, c, pixels))),
            #[cfg(feature = "filtering")]
            EstimatorConfig::Filter(FilterSide::Both, c) => Self::BidirectionalFilter(Box::new(Bpf::new(params, c, pixels))),
            #[cfg(not(all(feature = "bdpt", feature = "lvcbpt", feature = "spcbpt", feature = "merging", feature = "segments", feature = "filtering")))]
            other => {
                let estimator = other.kind();
                return Err(RendererError::NotCompiled { estimator, feature: estimator.cargo_feature().unwrap_or("default") });
            }
        })
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
