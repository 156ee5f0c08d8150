//! The estimators' options as one table: each option's name (the command line's
//! `--long` flag without its dashes), its value's kind, its range in words, a help line,
//! the estimators it applies to, and a setter on [`EstimatorConfig`]; and a parser of
//! `name=value` text into a configuration. The C API's options string and any later host
//! (a Python package, the browser) read this table; the command line keeps its clap
//! flags, and a test of `ember-cli` checks them against it both ways.
//!
//! The ranges are the configurations' own: a value is parsed here by kind (a whole
//! number, a number, one of some names) and then checked by the configuration's
//! `validate`, which names the option in its [`ConfigError`]. A value is checked when it
//! is given, on the first estimator its option applies to, so an out-of-range value is
//! refused whatever estimator it is given for (as the command line refuses it); an
//! option that does not apply to the estimator being configured is accepted and leaves
//! its configuration as it is.

use alloc::string::String;
use core::fmt;

use crate::estimators::{ConfigError, EstimatorConfig, EstimatorKind, FilterReuse, KernelChoice};
use crate::merge::RadiusRule;

/// What an option's value is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueKind {
    /// A whole number, 0 to 4 294 967 295 (its range is the configuration's).
    Count,
    /// A number (its range is the configuration's; non-finite values are refused there).
    Number,
    /// One of these names.
    Choice(&'static [&'static str]),
}

/// An option's value, parsed by its [`ValueKind`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Count(u32),
    Number(f32),
    /// The index of the name in the option's [`ValueKind::Choice`].
    Choice(usize),
}

impl Value {
    fn count(self) -> u32 {
        match self {
            Self::Count(n) => n,
            Self::Number(x) => x as u32,
            Self::Choice(i) => i as u32,
        }
    }
    fn number(self) -> f32 {
        match self {
            Self::Number(x) => x,
            Self::Count(n) => n as f32,
            Self::Choice(i) => i as f32,
        }
    }
}

/// One estimator option.
#[derive(Clone, Copy, Debug)]
pub struct OptionSpec {
    /// As the command line spells it without the dashes (`light-paths`).
    pub name: &'static str,
    /// What its value is.
    pub value: ValueKind,
    /// The values `validate` accepts, in words (its [`ConfigError::allowed`]).
    pub range: &'static str,
    /// What it sets, with its default.
    pub help: &'static str,
    /// The estimators whose configuration it sets.
    pub applies: &'static [EstimatorKind],
    /// Options that set the same thing another way (the radius rules): at most one of a
    /// group may be given.
    pub group: Option<&'static str>,
    /// Set it on `config` where it applies (elsewhere nothing changes).
    pub set: fn(&mut EstimatorConfig, Value),
}

impl OptionSpec {
    /// Does this option set `kind`'s configuration?
    pub fn applies_to(&self, kind: EstimatorKind) -> bool {
        self.applies.contains(&kind)
    }

    /// `text` parsed as this option's value.
    pub fn parse_value(&self, text: &str) -> Result<Value, OptionError> {
        let invalid = |reason: &'static str| OptionError::Value { name: self.name, value: String::from(text), reason };
        match self.value {
            ValueKind::Count => text.trim().parse::<u32>().map(Value::Count).map_err(|_| invalid("not a whole number from 0 to 4294967295")),
            ValueKind::Number => text.trim().parse::<f32>().map(Value::Number).map_err(|_| invalid("not a number")),
            ValueKind::Choice(names) => names.iter().position(|n| *n == text.trim()).map(Value::Choice).ok_or_else(|| invalid("not one of the names allowed")),
        }
    }
}

use EstimatorKind as K;

const CACHED: &[EstimatorKind] = &[K::Lvcbpt, K::Spcbpt];
const SPCBPT: &[EstimatorKind] = &[K::Spcbpt];
const LIGHT_PATHS: &[EstimatorKind] = &[K::Lvcbpt, K::Spcbpt, K::Ppm, K::Bpm, K::Vcm];
const SEGMENTS: &[EstimatorKind] = &[K::Spt, K::Slt, K::Sbdpt];
const RADIUS: &[EstimatorKind] = &[K::Ppm, K::Bpm, K::Vcm, K::Spt, K::Slt, K::Sbdpt, K::Mvf, K::Phf, K::Bpf];
const ALPHA: &[EstimatorKind] = &[K::Ppm, K::Bpm, K::Vcm, K::Mvf, K::Phf, K::Bpf];
const FILTERS: &[EstimatorKind] = &[K::Mvf, K::Phf, K::Bpf];

/// The names of `kernel`'s values, in [`KernelChoice`] order.
pub const KERNELS: &[&str] = &["dirac", "disk"];
/// The names of `filter-reuse`'s values, in [`FilterReuse`] order.
pub const FILTER_REUSES: &[&str] = &["every", "merges", "bridges"];

/// Set a field of SPCBPT's configuration.
macro_rules! spcbpt {
    ($field:ident, $v:ident => $value:expr) => {
        |c: &mut EstimatorConfig, $v: Value| {
            if let EstimatorConfig::Spcbpt(s) = c {
                s.$field = $value;
            }
        }
    };
}

/// Set a field of path filtering's configuration.
macro_rules! filter {
    ($field:ident, $v:ident => $value:expr) => {
        |c: &mut EstimatorConfig, $v: Value| {
            if let EstimatorConfig::Filter(_, f) = c {
                f.$field = $value;
            }
        }
    };
}

/// Set the radius rule of the merging, segment and filtering estimators.
fn set_radius(c: &mut EstimatorConfig, rule: RadiusRule) {
    match c {
        EstimatorConfig::Merging(_, m) => m.radius = rule,
        EstimatorConfig::Segment(_, s) => s.radius = rule,
        EstimatorConfig::Filter(_, f) => f.radius = rule,
        _ => {}
    }
}

fn option(
    name: &'static str,
    value: ValueKind,
    range: &'static str,
    help: &'static str,
    applies: &'static [EstimatorKind],
    set: fn(&mut EstimatorConfig, Value),
) -> OptionSpec {
    OptionSpec { name, value, range, help, applies, group: None, set }
}

/// Every estimator option, in the command line's order.
pub fn all() -> [OptionSpec; 23] {
    use ValueKind::{Choice, Count, Number};
    let radius = |name, set, help| OptionSpec { group: Some("the radius"), ..option(name, Number, "(0, 1e30]", help, RADIUS, set) };
    [
        option("light-paths", Count, "1..=4000000", "light paths per pass, M [default: min(100000, W·H); PPM, BPM, VCM: N_L = W·H]", LIGHT_PATHS, |c, v| {
            match c {
                EstimatorConfig::Lvcbpt(l) => l.light_paths = Some(v.count()),
                EstimatorConfig::Spcbpt(s) => s.light_paths = Some(v.count()),
                EstimatorConfig::Merging(_, m) => m.light_paths = Some(v.count()),
                _ => {}
            }
        }),
        option("connections", Count, "1..=1000", "connections per camera vertex, N [default: 3]", CACHED, |c, v| match c {
            EstimatorConfig::Lvcbpt(l) => l.connections = v.count(),
            EstimatorConfig::Spcbpt(s) => s.connections = v.count(),
            _ => {}
        }),
        option("dataset", Count, "1..=20000000", "SPCBPT: training paths, |D| [default: min(1000000, 16·W·H)]", SPCBPT, spcbpt!(dataset, v => Some(v.count()))),
        option(
            "subspaces",
            Count,
            "2..=4096",
            "SPCBPT: subspaces per side, N_S [default: min(1000, ⌊√(W·H)⌋), at least 16]",
            SPCBPT,
            spcbpt!(subspaces, v => Some(v.count())),
        ),
        option("learning-rate", Number, "(0, 10]", "SPCBPT: Adam learning rate α [default: 0.1]", SPCBPT, spcbpt!(learning_rate, v => v.number())),
        option("batch", Count, "1..=10000000", "SPCBPT: Adam mini-batch size at most [default: 10000]", SPCBPT, spcbpt!(batch, v => v.count())),
        option("steps", Count, "0..=1000000", "SPCBPT: Adam steps at least; 0: batch as given [default: 200]", SPCBPT, spcbpt!(steps, v => v.count())),
        option("epochs", Count, "0..=1000", "SPCBPT: training epochs [default: 2]", SPCBPT, spcbpt!(epochs, v => v.count())),
        option(
            "mixture",
            Number,
            "[0, 1]",
            "SPCBPT: weight of the uniform distribution mixed into Γ [default: 0.1]",
            SPCBPT,
            spcbpt!(mixture, v => v.number()),
        ),
        option(
            "reuse",
            Count,
            "0..=100000",
            "SPCBPT: light vertices retained per subspace across passes, M0 [default: 200]",
            SPCBPT,
            spcbpt!(reuse, v => v.count()),
        ),
        option(
            "k-d",
            Number,
            "[0, 1000]",
            "SPCBPT: weight of the normal/direction terms in the classification distance [default: 0.05]",
            SPCBPT,
            spcbpt!(k_d, v => v.number()),
        ),
        option(
            "light-source-share",
            Number,
            "[0, 1)",
            "SPCBPT: share of the light subspaces given to positions on the lights; 0 keeps NEE [default: 0.2]",
            SPCBPT,
            spcbpt!(light_source_share, v => v.number()),
        ),
        option(
            "q-paths",
            Count,
            "1..=20000000",
            "SPCBPT: light paths estimating Q per light subspace, M' [default: min(2000000, 2·W·H)]",
            SPCBPT,
            spcbpt!(q_paths, v => Some(v.count())),
        ),
        option("kernel", Choice(KERNELS), "dirac, disk", "SPT/SLT/SBDPT: the kernel joining consecutive segments [default: dirac]", SEGMENTS, |c, v| {
            if let EstimatorConfig::Segment(_, s) = c {
                s.kernel = if v.count() == 1 { KernelChoice::Disk } else { KernelChoice::Dirac };
            }
        }),
        radius(
            "radius",
            |c, v| set_radius(c, RadiusRule::Absolute(v.number())),
            "initial merging radius r₀ in scene units; SPT/SLT/SBDPT: the disk kernel's radius [default: 4 pixel footprints]",
        ),
        radius("radius-footprints", |c, v| set_radius(c, RadiusRule::Footprints(v.number())), "r₀ as a multiple of the mean pixel footprint [default: 4]"),
        radius(
            "radius-scene",
            |c, v| set_radius(c, RadiusRule::SceneFraction(v.number())),
            "r₀ as a fraction of the scene's bounding-sphere radius (SmallVCM's 0.003)",
        ),
        option("alpha", Number, "(0, 1]", "radius reduction α: r_i = r₀ (i + 1)^((α − 1)/2); 1 keeps r fixed [default: 0.67]", ALPHA, |c, v| match c {
            EstimatorConfig::Merging(_, m) => m.alpha = v.number(),
            EstimatorConfig::Filter(_, f) => f.alpha = v.number(),
            _ => {}
        }),
        option(
            "max-segments",
            Count,
            "1 to 64",
            "MVF/PhF/BPF: segments per path at most [default: the scene's max_depth; 16 where it is unbounded]",
            FILTERS,
            filter!(max_segments, v => Some(v.count())),
        ),
        option("beta", Number, "0 to 16", "BPF: light paths per camera path, β [default: 0.25]", FILTERS, filter!(beta, v => v.number())),
        option(
            "filter-reuse",
            Choice(FILTER_REUSES),
            "every, merges, bridges",
            "BPF: which segment paths its junctions form [default: every]",
            FILTERS,
            filter!(reuse, v => match v.count() {
                1 => FilterReuse::Merges,
                2 => FilterReuse::Bridges,
                _ => FilterReuse::Every,
            }),
        ),
        option(
            "glossy-alpha",
            Number,
            "0 to 1",
            "MVF/PhF/BPF: nodes on materials of roughness below this get a smaller kernel; 0: every node the pass's [default: 0.05]",
            FILTERS,
            filter!(glossy_alpha, v => v.number()),
        ),
        option(
            "neighbours",
            Count,
            "1 to 4096",
            "MVF/PhF/BPF: the mean nodes per kernel a pass keeps at most, lowering its radius where nodes crowd [default: 64]",
            FILTERS,
            filter!(neighbours, v => v.count()),
        ),
    ]
}

/// The option named `name`.
pub fn find(name: &str) -> Option<OptionSpec> {
    all().into_iter().find(|o| o.name == name)
}

/// Why options were refused.
#[derive(Clone, Debug, PartialEq)]
pub enum OptionError {
    /// A word of the text is not `name=value`.
    Form(String),
    /// No option has this name.
    Unknown(String),
    /// The value is not of the option's kind.
    Value { name: &'static str, value: String, reason: &'static str },
    /// The option was given twice.
    Twice(&'static str),
    /// Two options of a group (they set the same thing) were given.
    Conflict { first: &'static str, second: &'static str, group: &'static str },
    /// The configuration refused a value (the field is the option's name).
    Range(EstimatorKind, ConfigError),
}

impl fmt::Display for OptionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Form(word) => write!(f, "option '{word}' is not name=value"),
            Self::Unknown(name) => {
                write!(f, "no estimator option '{name}' (options: ")?;
                for (i, o) in all().iter().enumerate() {
                    write!(f, "{}{}", if i > 0 { ", " } else { "" }, o.name)?;
                }
                f.write_str(")")
            }
            Self::Value { name, value, reason } => {
                write!(f, "invalid value '{value}' for '{name}': {reason}")?;
                match find(name).map(|o| o.value) {
                    Some(ValueKind::Choice(names)) => write!(f, " ({})", names.join(", ")),
                    _ => Ok(()),
                }
            }
            Self::Twice(name) => write!(f, "option '{name}' is given twice"),
            Self::Conflict { first, second, group } => write!(f, "options '{first}' and '{second}' both set {group}: give one"),
            Self::Range(kind, e) => write!(f, "{} {e}", kind.name()),
        }
    }
}

impl core::error::Error for OptionError {}

/// The words of an options text: `name=value` pairs separated by whitespace.
pub fn pairs(text: &str) -> impl Iterator<Item = Result<(&str, &str), OptionError>> {
    text.split_whitespace().map(|word| word.split_once('=').ok_or_else(|| OptionError::Form(String::from(word))))
}

/// An estimator's configuration being set option by option.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    config: EstimatorConfig,
    /// Bit i: the option `all()[i]` was given.
    given: u32,
}

impl Options {
    /// `kind`'s default configuration, no option given yet.
    pub fn new(kind: EstimatorKind) -> Self {
        Self { config: kind.default_config(), given: 0 }
    }

    /// Set option `name` to `value` (text): refused when the name is unknown, the value is
    /// not of its kind or out of its range, or the option (or another of its group) was
    /// given before.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), OptionError> {
        let table = all();
        let index = table.iter().position(|o| o.name == name).ok_or_else(|| OptionError::Unknown(String::from(name)))?;
        let spec = table[index];
        if self.given & (1 << index) != 0 {
            return Err(OptionError::Twice(spec.name));
        }
        if let Some(group) = spec.group
            && let Some((_, first)) = table.iter().enumerate().find(|(i, o)| self.given & (1 << i) != 0 && o.group == Some(group))
        {
            return Err(OptionError::Conflict { first: first.name, second: spec.name, group });
        }
        let parsed = spec.parse_value(value)?;
        // Check the value alone: on this estimator where the option applies, else on the
        // first estimator it applies to.
        let own = self.config.kind();
        if let Some(kind) = if spec.applies_to(own) { Some(own) } else { spec.applies.first().copied() } {
            let mut alone = kind.default_config();
            (spec.set)(&mut alone, parsed);
            alone.validate().map_err(|e| OptionError::Range(kind, e))?;
        }
        (spec.set)(&mut self.config, parsed);
        self.given |= 1 << index;
        Ok(())
    }

    /// Was option `name` given?
    pub fn is_given(&self, name: &str) -> bool {
        all().iter().position(|o| o.name == name).is_some_and(|i| self.given & (1 << i) != 0)
    }

    /// The configuration, validated.
    pub fn finish(self) -> Result<EstimatorConfig, OptionError> {
        self.config.validate().map_err(|e| OptionError::Range(self.config.kind(), e))?;
        Ok(self.config)
    }
}

/// `kind`'s configuration with the options of `text` (`name=value`, whitespace between).
pub fn parse(kind: EstimatorKind, text: &str) -> Result<EstimatorConfig, OptionError> {
    let mut options = Options::new(kind);
    for pair in pairs(text) {
        let (name, value) = pair?;
        options.set(name, value)?;
    }
    options.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimators::{FilterConfig, MergingConfig};
    use alloc::string::ToString;

    /// Every option's range is what its configuration's `validate` says for a value
    /// outside it, under the option's own name: the table repeats no range of its own.
    #[test]
    fn ranges_are_the_configurations_own() {
        for spec in all() {
            let bad = match spec.value {
                ValueKind::Choice(_) => continue,
                // Past every range, or below one that starts above 0.
                ValueKind::Count if spec.name == "subspaces" || spec.name == "max-segments" => "4294967295",
                ValueKind::Count => ["0", "4294967295"].into_iter().find(|v| parse(spec.applies[0], &alloc::format!("{}={v}", spec.name)).is_err()).unwrap(),
                ValueKind::Number => "-1",
            };
            match parse(spec.applies[0], &alloc::format!("{}={bad}", spec.name)) {
                Err(OptionError::Range(_, e)) => assert_eq!((e.field, e.allowed), (spec.name, spec.range), "{}", spec.name),
                other => panic!("{} = {bad}: {other:?}", spec.name),
            }
        }
    }

    #[test]
    fn names_are_unique_and_fit_the_mask() {
        let table = all();
        assert!(table.len() <= 32);
        for (i, a) in table.iter().enumerate() {
            assert!(table[i + 1..].iter().all(|b| b.name != a.name), "{}", a.name);
            assert!(!a.applies.is_empty(), "{}", a.name);
        }
    }

    #[test]
    fn text_sets_the_configuration() {
        let c = parse(K::Bpf, "beta=1 filter-reuse=bridges radius-scene=0.01 max-segments=8").unwrap();
        let want =
            FilterConfig { beta: 1.0, reuse: FilterReuse::Bridges, radius: RadiusRule::SceneFraction(0.01), max_segments: Some(8), ..FilterConfig::DEFAULT };
        assert_eq!(c, EstimatorConfig::Filter(crate::estimators::FilterSide::Both, want));
        let c = parse(K::Vcm, "light-paths=7 alpha=1 subspaces=64").unwrap();
        assert_eq!(
            c,
            EstimatorConfig::Merging(crate::estimators::MergeMode::Vcm, MergingConfig { light_paths: Some(7), alpha: 1.0, ..MergingConfig::DEFAULT })
        );
        assert_eq!(parse(K::Pt, "").unwrap(), EstimatorConfig::Pt);
    }

    #[test]
    fn refusals_name_what_is_wrong() {
        let e = |kind, text| parse(kind, text).unwrap_err().to_string();
        assert_eq!(e(K::Pt, "reuse"), "option 'reuse' is not name=value");
        assert!(e(K::Spcbpt, "spp=4").starts_with("no estimator option 'spp' (options: light-paths, "));
        assert!(e(K::Spcbpt, "subspaces=many").contains("'many'"));
        assert!(e(K::Spt, "kernel=box").ends_with("(dirac, disk)"));
        assert_eq!(e(K::Spcbpt, "reuse=1 reuse=2"), "option 'reuse' is given twice");
        assert_eq!(e(K::Ppm, "radius=1 radius-scene=0.1"), "options 'radius' and 'radius-scene' both set the radius: give one");
        assert_eq!(e(K::Bpf, "beta=-1"), "bpf beta = -1 is outside its allowed range 0 to 16");
        // Checked whatever the estimator, as the command line checks it.
        assert!(e(K::Pt, "subspaces=1").contains("subspaces = 1"));
    }
}
