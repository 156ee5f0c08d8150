//! Path filtering's configuration (MVF, PhF, BPF; compiled in every build).

use crate::merge::RadiusRule;
use crate::transport::config::{ConfigError, check_f32, check_radius};

/// Which sub-paths path filtering filters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterSide {
    /// Camera paths: multi-vertex path filtering ([`crate::estimators::filter::Mvf`]).
    Camera,
    /// Light paths: photon filtering ([`crate::estimators::filter::Phf`]).
    Light,
    /// Both: bidirectional path filtering ([`crate::estimators::filter::Bpf`]).
    Both,
}

/// Path filtering's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterConfig {
    /// How the initial kernel radius r₀ is chosen (default: 4 pixel footprints, the
    /// segment paper's heuristic).
    pub radius: RadiusRule,
    /// Kernel reduction α ∈ (0, 1]: r_i = r₀ (i + 1)^((α − 1)/2) (default 0.67).
    pub alpha: f32,
    /// Segments per path at most [default: the scene's max_depth; 16 where it is
    /// unbounded]. Each costs one propagation sweep.
    pub max_segments: Option<u32>,
    /// Bidirectional filtering: light paths per camera path, β ∈ [0, 16] (default 0.25,
    /// the segment paper's; it used 1 on its caustic scene). 0 traces none: MVF's
    /// segments with BPF's weights.
    pub beta: f32,
    /// Bidirectional filtering: which segment paths a junction forms (default: every).
    pub reuse: FilterReuse,
    /// Nodes on a material of microfacet roughness α below this get a kernel α / this
    /// times the pass's (`estimators::filter::nodes::scale_kernels`); 0 gives every node
    /// the pass's kernel. In [0, 1] (default 0.05).
    pub glossy_alpha: f32,
    /// The neighbour budget: where nodes crowd (a caustic, a spot light's pool) a pass
    /// lowers its radius until the mean kernel holds at most this many nodes, since rows
    /// cost O(Σ n²). The radius still shrinks to zero over passes, so the estimators stay
    /// consistent. 1 to 4096 (default 64).
    pub neighbours: u32,
}

/// Which segments bidirectional filtering's junctions reuse.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterReuse {
    /// Every segment whose start lies in the junction's kernel: the paper's estimator.
    Every,
    /// Bidirectional photon mapping's segment paths only: a camera junction reuses its
    /// own continuation and light sample and the light segments in its kernel (a merge),
    /// a light junction its own path. The reduction to BPM (recursive MMIS over BPM's
    /// techniques), for testing and for measuring what the filtering adds.
    Merges,
    /// Every segment in a kernel, and bridge segments: each camera node joins a light
    /// node of the pass by a shadow ray, the bridge reused like a light segment (the
    /// segment paper's §6.4 and Fig. 7).
    Bridges,
}

/// Largest β.
pub const MAX_FILTER_BETA: f32 = 16.0;

/// Segments per path where neither max_depth nor `--max-segments` bounds them.
pub const DEFAULT_FILTER_SEGMENTS: u32 = 16;
/// Largest `--max-segments` (one propagation phase each).
pub const MAX_FILTER_SEGMENTS: u32 = 64;
/// Largest `--neighbours`.
pub const MAX_FILTER_NEIGHBOURS: u32 = 4096;

impl FilterConfig {
    /// The defaults.
    pub const DEFAULT: Self =
        Self { radius: RadiusRule::DEFAULT, alpha: 0.67, max_segments: None, beta: 0.25, reuse: FilterReuse::Every, glossy_alpha: 0.05, neighbours: 64 };

    /// Light paths per pass for a film of `pixels` pixels: round(β · pixels), at least one
    /// where β > 0.
    pub fn light_paths(&self, pixels: u32) -> u32 {
        if !(self.beta > 0.0) {
            return 0;
        }
        (libm::round(self.beta as f64 * pixels as f64) as u32).max(1)
    }

    /// Are bridge segments traced?
    pub fn bridges(&self) -> bool {
        self.reuse == FilterReuse::Bridges && self.beta > 0.0
    }

    /// Segments per path under `max_depth`.
    pub fn segments(&self, max_depth: crate::transport::MaxDepth) -> u32 {
        let cap = self.max_segments.unwrap_or(if max_depth.0 < 0 { DEFAULT_FILTER_SEGMENTS } else { MAX_FILTER_SEGMENTS });
        max_depth.capped(cap.min(MAX_FILTER_SEGMENTS))
    }

    /// Check every field against its range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_radius(self.radius)?;
        check_f32("alpha", self.alpha, self.alpha > 0.0 && self.alpha <= 1.0, "(0, 1]")?;
        check_f32("beta", self.beta, self.beta >= 0.0 && self.beta <= MAX_FILTER_BETA, "0 to 16")?;
        check_f32("glossy-alpha", self.glossy_alpha, (0.0..=1.0).contains(&self.glossy_alpha), "0 to 1")?;
        if !(1..=MAX_FILTER_NEIGHBOURS).contains(&self.neighbours) {
            return Err(ConfigError { field: "neighbours", value: self.neighbours as f64, allowed: "1 to 4096" });
        }
        match self.max_segments {
            Some(n) if !(1..=MAX_FILTER_SEGMENTS).contains(&n) => Err(ConfigError { field: "max-segments", value: n as f64, allowed: "1 to 64" }),
            _ => Ok(()),
        }
    }
}

impl Default for FilterConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}
