//! What every estimator's configuration shares: [`ConfigError`], naming the field as
//! the command line spells it and its allowed range, the range checks that build it, and
//! the light-path count rule of the cached estimators.

use core::fmt;

use crate::merge::RadiusRule;

/// A configuration value outside its allowed range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConfigError {
    /// The field, as the command line spells its option (without dashes).
    pub field: &'static str,
    /// The value given.
    pub value: f64,
    /// The allowed range, in words.
    pub allowed: &'static str,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {} is outside its allowed range {}", self.field, self.value, self.allowed)
    }
}

impl core::error::Error for ConfigError {}

pub(crate) fn check_u32(field: &'static str, value: u32, range: core::ops::RangeInclusive<u32>, allowed: &'static str) -> Result<(), ConfigError> {
    if range.contains(&value) { Ok(()) } else { Err(ConfigError { field, value: value as f64, allowed }) }
}

pub(crate) fn check_f32(field: &'static str, value: f32, ok: bool, allowed: &'static str) -> Result<(), ConfigError> {
    if value.is_finite() && ok { Ok(()) } else { Err(ConfigError { field, value: value as f64, allowed }) }
}

/// Largest M: a pass's light paths are held in memory (about 1 KiB per path).
pub const MAX_LIGHT_PATHS: u32 = 4_000_000;
/// Largest |D| and M'.
pub const MAX_DATASET: u32 = 20_000_000;

/// M for a film of `pixels` pixels: `light_paths` where given, else min(100 000, W·H)
/// (at most one light path per pixel sample, as in BDPT).
pub(crate) fn light_paths_for(light_paths: Option<u32>, pixels: u32) -> u32 {
    light_paths.unwrap_or(pixels.clamp(1, 100_000))
}

/// A radius rule's value must be positive and finite; the error names the option.
pub(crate) fn check_radius(rule: RadiusRule) -> Result<(), ConfigError> {
    let r = rule.value();
    let field = match rule {
        RadiusRule::Footprints(_) => "radius-footprints",
        RadiusRule::SceneFraction(_) => "radius-scene",
        RadiusRule::Absolute(_) => "radius",
    };
    check_f32(field, r, r > 0.0 && r <= 1e30, "(0, 1e30]")
}
