//! One image across many machines (docs/distributed.md): pass ranges, scheduler task
//! indices, partial images and their merge.
//!
//! Passes are independent: every random number derives from (seed, pixel or path,
//! sample, dimension, pass), so passes A..B rendered anywhere are the passes A..B of a
//! whole render. The film's sums are exact integers ([`Film`]), so adding the parts'
//! sums in any order gives the whole render's sums bit for bit.
//!
//! # The partial image
//! An EXR file, one layer, the render's resolution:
//! - `R`, `G`, `B` (f32): the part's own mean, for a look at one task's output;
//! - `sum.R.w0` … `sum.R.w3` and the same for G and B (32-bit UINT, ZIP-compressed): the
//!   film's exact per-pixel sums, each a `u128` count of 2⁻⁶⁴ split into four 32-bit
//!   words, w0 the least significant. Mean = sum · 2⁻⁶⁴ / passes in f64 (what
//!   `Film::to_rgb_f32` computes);
//! - under a tent or gaussian pixel filter, also `wsum.R.w0` … `wsum.B.w3` and
//!   `wsum.W.w0` … `wsum.W.w3` (the same encoding): the camera samples' weighted sums
//!   Σ f L and Σ f (`Film::weighted_sums`), whose ratio that mean adds;
//! - the text attribute `ember.partial` ([`PartialHeader`]), one `key: value` per line:
//!   the format and program version, the scene's name and hash, the estimator and its
//!   configuration, the seed, the pass range held, the total, the quantum and the
//!   film's tallies.
//!
//! A task writes its part to a temporary name and renames it when complete, so a task
//! that dies leaves no file `merge` would accept, and a re-run writes the same bytes.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use ember_core::render::{Film, QUANTUM_BITS, Tallies};

use ember_formats::image_io::{self, ImageError, ImageErrorKind};

/// The partial-image format's name and version (its `format` field).
pub const FORMAT: &str = "ember partial film 1";
/// The EXR attribute (text) holding a partial image's header, one `key: value` per line.
pub const ATTRIBUTE: &str = "ember.partial";
/// The key of a text header's last line, FNV-1a 64 of every line before it: partial images
/// and model files (`crate::trained`) end their headers with it, so an edited header (a
/// part claiming other passes merged into a half-bright image) is refused.
const CHECKSUM_KEY: &str = "checksum";

/// Append the checksum line to `header` (`key: value` lines, each ending in `\n`).
pub fn sign_header(header: &mut String) {
    let sum = ember_core::fnv::fnv1a(header.as_bytes());
    header.push_str(&format!("{CHECKSUM_KEY}: {sum:016x}\n"));
}

/// Does `header` hold a checksum line ([`sign_header`]) matching every line before it?
pub fn header_is_signed(header: &str) -> bool {
    let Some(at) = header.find(&format!("\n{CHECKSUM_KEY}: ")) else { return false };
    let (signed, rest) = header.split_at(at + 1);
    let stored =
        rest.lines().next().and_then(|l| l.strip_prefix(CHECKSUM_KEY)).and_then(|l| l.strip_prefix(": ")).and_then(|c| u64::from_str_radix(c, 16).ok());
    stored == Some(ember_core::fnv::fnv1a(signed.as_bytes()))
}

/// Passes `start..end` (half-open).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct PassRange {
    pub start: u32,
    pub end: u32,
}

impl PassRange {
    /// `A..B` with A < B.
    pub fn parse(text: &str) -> Result<Self, String> {
        let (a, b) = text.split_once("..").ok_or_else(|| format!("'{text}' is not a range A..B (half-open: passes A to B-1)"))?;
        let num = |t: &str| t.trim().parse::<u32>().map_err(|_| format!("'{text}': '{t}' is not a pass index (0 to 4294967295)"));
        let (start, end) = (num(a)?, num(b)?);
        if start >= end {
            return Err(format!("'{text}' is empty: need A < B (passes A to B-1)"));
        }
        Ok(Self { start, end })
    }

    /// Number of passes.
    pub fn len(&self) -> u32 {
        self.end - self.start
    }

    /// No passes.
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }

    /// Share `index` of `total` passes split into `count` tasks: ⌊total/count⌋ passes
    /// each, the first total mod count tasks one more, in task order.
    pub fn of_task(index: u32, count: u32, total: u32) -> Result<Self, String> {
        if count == 0 || index >= count {
            return Err(format!("task index {index} is not below the task count {count}"));
        }
        if count > total {
            return Err(format!("{count} tasks cannot share {total} passes: give --spp at least the task count"));
        }
        let (base, extra) = (total / count, total % count);
        let start = index * base + index.min(extra);
        Ok(Self { start, end: start + base + u32::from(index < extra) })
    }
}

impl fmt::Display for PassRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}

/// A task's index and the task count, read from a scheduler's variables through `var`
/// (the process environment in the program, a map in tests): Slurm's array variables, or
/// Kubernetes' `JOB_COMPLETION_INDEX` with `count` from `--task-count`.
pub fn task_from_env(var: impl Fn(&str) -> Option<String>, count: Option<u32>) -> Result<(u32, u32), String> {
    let read = |name: &str| -> Result<Option<u32>, String> {
        match var(name) {
            None => Ok(None),
            Some(v) => v.trim().parse::<u32>().map(Some).map_err(|_| format!("{name}='{v}' is not a non-negative integer")),
        }
    };
    let slurm = read("SLURM_ARRAY_TASK_ID")?;
    let k8s = read("JOB_COMPLETION_INDEX")?;
    match (slurm, k8s) {
        (Some(_), Some(_)) => Err("both SLURM_ARRAY_TASK_ID and JOB_COMPLETION_INDEX are set: use --task-index and --task-count".into()),
        (Some(id), None) => {
            let min = read("SLURM_ARRAY_TASK_MIN")?.ok_or("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_MIN is not")?;
            let n = read("SLURM_ARRAY_TASK_COUNT")?.ok_or("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")?;
            if let Some(c) = count.filter(|&c| c != n) {
                return Err(format!("--task-count {c} disagrees with SLURM_ARRAY_TASK_COUNT={n}"));
            }
            let index = id.checked_sub(min).ok_or_else(|| format!("SLURM_ARRAY_TASK_ID={id} is below SLURM_ARRAY_TASK_MIN={min}"))?;
            // An array with a step (--array=0-15:4) has ids that are not min..min+count.
            if index >= n {
                return Err(format!(
                    "SLURM_ARRAY_TASK_ID={id} − SLURM_ARRAY_TASK_MIN={min} is not below SLURM_ARRAY_TASK_COUNT={n}: submit the array as --array=0-{}",
                    n.saturating_sub(1)
                ));
            }
            Ok((index, n))
        }
        (None, Some(index)) => {
            let n = count.ok_or("JOB_COMPLETION_INDEX is set: give the Job's completions as --task-count")?;
            Ok((index, n))
        }
        (None, None) => Err("--task-from-env: neither SLURM_ARRAY_TASK_ID (Slurm) nor JOB_COMPLETION_INDEX (Kubernetes) is set".into()),
    }
}

/// The first placeholder (`{task}`, `{passes}`) that `path` names, if any: what only a split
/// render fills in ([`expand_output`]).
pub fn placeholder(path: &Path) -> Option<&'static str> {
    let text = path.to_string_lossy();
    ["{task}", "{passes}"].into_iter().find(|p| text.contains(p))
}

/// `{task}` → the task index, `{passes}` → `A-B`, in an output path.
pub fn expand_output(path: &Path, range: PassRange, task: Option<u32>) -> Result<PathBuf, String> {
    let text = path.to_string_lossy();
    if text.contains("{task}") && task.is_none() {
        return Err(format!("output '{}' names {{task}} but the render is not one of a task array (--task-index, --task-from-env)", path.display()));
    }
    let out = text.replace("{passes}", &format!("{}-{}", range.start, range.end));
    Ok(PathBuf::from(match task {
        Some(t) => out.replace("{task}", &t.to_string()),
        None => out,
    }))
}

/// Where two configuration texts (`Debug` dumps such as `Spcbpt(SpcbptConfig { light_paths:
/// None, … }); max depth -1, …`) first differ: the two differing settings as people read
/// them (`("dataset Some(1000)", "dataset Some(2000)")`, `("max depth 3", "max depth -1")`),
/// instead of both dumps of several hundred characters.
pub fn first_difference(a: &str, b: &str) -> (String, String) {
    let split = |t: &str| -> Vec<String> { t.split([',', '{', '}', ';']).map(|p| p.trim().replacen(": ", " ", 1)).filter(|p| !p.is_empty()).collect() };
    let (pa, pb) = (split(a), split(b));
    match pa.iter().zip(&pb).find(|(x, y)| x != y) {
        Some((x, y)) => (x.clone(), y.clone()),
        None => (pa.get(pb.len()).cloned().unwrap_or_default(), pb.get(pa.len()).cloned().unwrap_or_default()),
    }
}

/// What a partial image says about itself. Parts merge only when everything but `passes`
/// and `tallies` is equal.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PartialHeader {
    /// [`ember_host::program_version`] of the program that wrote it.
    pub program: String,
    /// The scene's name (its file) and the hash of what was built from it.
    pub scene: String,
    pub scene_hash: u64,
    pub estimator: String,
    /// The estimator's configuration and the shared settings (depth, heuristic), as text.
    pub config: String,
    pub seed: u64,
    pub width: u32,
    pub height: u32,
    /// The passes the file holds.
    pub passes: PassRange,
    /// The passes of the whole render.
    pub total: u32,
    pub tallies: Tallies,
}

/// What a partial image identifies its render by (set by the renderer).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderIdentity {
    pub scene: String,
    pub scene_hash: u64,
    pub estimator: String,
    pub config: String,
    pub seed: u64,
}

/// The fields two parts of one render must share, by name, in the order they are
/// checked and reported. Not the scene's name: another machine may hold the same scene
/// at another path; its hash decides.
fn identity_fields(h: &PartialHeader) -> [(&'static str, String); 7] {
    [
        ("program version", h.program.clone()),
        ("estimator", h.estimator.clone()),
        ("resolution", format!("{}x{}", h.width, h.height)),
        ("total passes", h.total.to_string()),
        ("seed", h.seed.to_string()),
        ("configuration", h.config.clone()),
        ("scene hash", format!("{:016x}", h.scene_hash)),
    ]
}

fn text(value: &str) -> exr::prelude::Text {
    exr::prelude::Text::from_slice_unchecked(value.as_bytes())
}

/// Write `film` (holding exactly `header.passes`) as a partial image, atomically.
pub fn write_partial(path: &Path, header: &PartialHeader, film: &Film) -> Result<(), ImageError> {
    use exr::prelude::*;
    let (w, h) = (film.width() as usize, film.height() as usize);
    let mean = film.to_rgb_f32();
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::with_capacity(15);
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        channels.push(AnyChannel::new(*name, FlatSamples::F32(mean.iter().map(|p| p[c]).collect())));
        for word in 0..4 {
            let samples = film.exact_sums().iter().map(|p| (p[c] >> (32 * word)) as u32).collect();
            channels.push(AnyChannel::new(format!("sum.{name}.w{word}").as_str(), FlatSamples::U32(samples)));
        }
    }
    // A wide filter's camera samples: Σ f L per channel and Σ f.
    let weighted = film.weighted_sums();
    if !weighted.is_empty() {
        for (c, name) in ["R", "G", "B", "W"].iter().enumerate() {
            for word in 0..4 {
                let samples = weighted.iter().map(|p| ((if c < 3 { p.value[c] } else { p.weight }) >> (32 * word)) as u32).collect();
                channels.push(AnyChannel::new(format!("wsum.{name}.w{word}").as_str(), FlatSamples::U32(samples)));
            }
        }
    }
    // One attribute holding every field, one `key: value` line each: the crate stores
    // attributes in a hash map written in a per-process random order, and a part must
    // have the same bytes every time it is rendered.
    let t = header.tallies;
    let fields = [
        ("format", FORMAT.to_string()),
        ("program", header.program.clone()),
        ("scene", header.scene.clone()),
        ("scene_hash", format!("{:016x}", header.scene_hash)),
        ("estimator", header.estimator.clone()),
        ("config", header.config.clone()),
        ("seed", header.seed.to_string()),
        ("passes", header.passes.to_string()),
        ("total", header.total.to_string()),
        ("quantum_bits", QUANTUM_BITS.to_string()),
        ("tallies", format!("{} {} {}", t.discarded, t.splats_outside, t.saturated)),
    ];
    let mut lines: String = fields.iter().map(|(k, v)| format!("{k}: {}\n", v.replace('\n', " "))).collect();
    sign_header(&mut lines);
    let mut attributes = LayerAttributes::default();
    attributes.other.insert(text(ATTRIBUTE), AttributeValue::Text(text(&lines)));
    let encoding = Encoding { compression: Compression::ZIP16, ..Encoding::default() };
    let layer = Layer::new((w, h), attributes, encoding, AnyChannels::sort(channels.into()));
    let image = Image::from_layer(layer);
    image_io::write_atomically(
        path,
        |temp| image.write().non_parallel().to_file(temp).map_err(|e| ImageError::new(path, ImageErrorKind::Exr(e))),
        |e| ImageError::new(path, ImageErrorKind::Io(e)),
    )
}

/// Read a partial image: its header and its film. A file that is not a partial image,
/// or whose header or channels are damaged, is an error naming the file and the problem.
pub fn read_partial(path: &Path) -> Result<(PartialHeader, Film), String> {
    let bytes = ember_formats::files::read_bounded(path, ember_formats::files::MAX_INPUT_BYTES).map_err(|e| format!("{}: {e}", path.display()))?;
    read_partial_from_bytes(path, &bytes)
}

/// [`read_partial`] on bytes in memory, errors naming `name` (the fuzz target's entry
/// point). Never panics on malformed input.
pub fn read_partial_from_bytes(name: &Path, bytes: &[u8]) -> Result<(PartialHeader, Film), String> {
    let image = image_io::read_exr_any_from_bytes(name, bytes).map_err(|e| e.to_string())?;
    partial_from_image(name, &image)
}

/// A partial image's header alone (the file's EXR header, not its pixels): what
/// `merge` checks before it reads any film.
pub fn read_partial_header(path: &Path) -> Result<PartialHeader, String> {
    ember_formats::files::open_regular(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| format!("{}: {e}", path.display()))?;
    let header = meta.headers.first().ok_or_else(|| format!("{}: no image layer", path.display()))?;
    header_from(path, &header.own_attributes, header.layer_size)
}

/// The [`PartialHeader`] in a layer's attributes, for a layer of `size`.
fn header_from(path: &Path, attributes: &exr::meta::header::LayerAttributes, size: exr::math::Vec2<usize>) -> Result<PartialHeader, String> {
    use exr::prelude::AttributeValue;
    let name = path.display();
    let header_text = match attributes.other.get(&text(ATTRIBUTE)) {
        Some(AttributeValue::Text(t)) => String::from_utf8_lossy(t.bytes()).into_owned(),
        _ => return Err(format!("{name} is not a partial image (no {ATTRIBUTE} attribute): merge takes the files `render --passes` or `--task-index` writes")),
    };
    let fields: BTreeMap<String, String> = header_text.lines().filter_map(|l| l.split_once(": ").map(|(k, v)| (k.to_string(), v.to_string()))).collect();
    let get = |key: &str| -> Result<String, String> { fields.get(key).cloned().ok_or_else(|| format!("{name}: no {key} in its {ATTRIBUTE} attribute")) };
    match get("format") {
        Ok(f) if f == FORMAT => {}
        Ok(f) => return Err(format!("{name}: partial-image format '{f}', this program reads '{FORMAT}'")),
        Err(e) => return Err(e),
    }
    if !header_is_signed(&header_text) {
        return Err(format!("{name}: its {ATTRIBUTE} header does not match its checksum: the header was edited or the file is damaged"));
    }
    let number = |key: &str| -> Result<u64, String> { get(key)?.parse::<u64>().map_err(|_| format!("{name}: {key} is not a number")) };
    let passes = PassRange::parse(&get("passes")?).map_err(|e| format!("{name}: passes {e}"))?;
    let total = u32::try_from(number("total")?).map_err(|_| format!("{name}: total is too large"))?;
    if passes.end > total {
        return Err(format!("{name}: passes {passes} reach past its total of {total}"));
    }
    if number("quantum_bits")? != QUANTUM_BITS as u64 {
        return Err(format!("{name}: sums in units of 2^-{}, this program's are 2^-{QUANTUM_BITS}", get("quantum_bits")?));
    }
    let tallies: Vec<u64> = get("tallies")?.split(' ').map(|v| v.parse::<u64>()).collect::<Result<_, _>>().map_err(|_| format!("{name}: damaged tallies"))?;
    let [discarded, splats_outside, saturated] = tallies[..] else { return Err(format!("{name}: damaged tallies")) };
    let scene_hash = u64::from_str_radix(&get("scene_hash")?, 16).map_err(|_| format!("{name}: damaged scene_hash"))?;
    let (width, height) = (u32::try_from(size.width()), u32::try_from(size.height()));
    let (Ok(width), Ok(height)) = (width, height) else { return Err(format!("{name}: a {}x{} image", size.width(), size.height())) };
    Ok(PartialHeader {
        program: get("program")?,
        scene: get("scene")?,
        scene_hash,
        estimator: get("estimator")?,
        config: get("config")?,
        seed: number("seed")?,
        width,
        height,
        passes,
        total,
        tallies: Tallies { discarded, splats_outside, saturated },
    })
}

fn partial_from_image(path: &Path, image: &exr::image::FlatImage) -> Result<(PartialHeader, Film), String> {
    use exr::prelude::FlatSamples;
    let name = path.display();
    let layer = image.layer_data.first().ok_or_else(|| format!("{name}: no image layer"))?;
    let size = layer.size;
    let header = header_from(path, &layer.attributes, size)?;
    let (width, height) = (header.width, header.height);
    let passes = header.passes;
    let pixels = size.width() * size.height();
    let mut sums = vec![[0u128; 3]; pixels];
    for (c, ch) in ["R", "G", "B"].iter().enumerate() {
        for word in 0..4 {
            let channel_name = format!("sum.{ch}.w{word}");
            let channel = layer.channel_data.list.iter().find(|x| x.name == text(&channel_name)).ok_or_else(|| format!("{name}: no channel {channel_name}"))?;
            let FlatSamples::U32(values) = &channel.sample_data else { return Err(format!("{name}: channel {channel_name} is not UINT")) };
            if values.len() != pixels {
                return Err(format!("{name}: channel {channel_name} holds {} samples for {pixels} pixels", values.len()));
            }
            for (s, &v) in sums.iter_mut().zip(values) {
                s[c] |= (v as u128) << (32 * word);
            }
        }
    }
    // A wide filter's weighted sums, where the part has them.
    let mut weighted = Vec::new();
    if layer.channel_data.list.iter().any(|x| x.name == text("wsum.W.w0")) {
        weighted = vec![ember_core::render::WeightedSum::default(); pixels];
        for (c, ch) in ["R", "G", "B", "W"].iter().enumerate() {
            for word in 0..4 {
                let channel_name = format!("wsum.{ch}.w{word}");
                let channel =
                    layer.channel_data.list.iter().find(|x| x.name == text(&channel_name)).ok_or_else(|| format!("{name}: no channel {channel_name}"))?;
                let FlatSamples::U32(values) = &channel.sample_data else { return Err(format!("{name}: channel {channel_name} is not UINT")) };
                if values.len() != pixels {
                    return Err(format!("{name}: channel {channel_name} holds {} samples for {pixels} pixels", values.len()));
                }
                for (s, &v) in weighted.iter_mut().zip(values) {
                    let sum = if c < 3 { &mut s.value[c] } else { &mut s.weight };
                    *sum |= (v as u128) << (32 * word);
                }
            }
        }
    }
    let film =
        Film::from_exact(width, height, sums, passes.len(), header.tallies).and_then(|f| f.with_weighted_sums(weighted)).map_err(|e| format!("{name}: {e}"))?;
    // The R, G, B channels are the film's mean (`write_partial` stores exactly
    // `to_rgb_f32`): sums over another number of passes than the header's give another mean.
    let mean = film.to_rgb_f32();
    for (c, ch) in ["R", "G", "B"].iter().enumerate() {
        let channel = layer.channel_data.list.iter().find(|x| x.name == text(ch)).ok_or_else(|| format!("{name}: no channel {ch}"))?;
        let FlatSamples::F32(values) = &channel.sample_data else { return Err(format!("{name}: channel {ch} is not FLOAT")) };
        if values.len() != pixels || values.iter().zip(&mean).any(|(v, m)| v.to_bits() != m[c].to_bits()) {
            return Err(format!("{name}: its {ch} channel is not the mean of its sums over its {} passes: the file was edited or is damaged", passes.len()));
        }
    }
    Ok((header, film))
}

/// Why parts do not merge: every problem found, each naming its files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MergeError(pub Vec<String>);

impl fmt::Display for MergeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "the parts do not make one image:")?;
        for p in &self.0 {
            write!(f, "\n  {p}")?;
        }
        Ok(())
    }
}

/// The first identity field (all but the total) in which two headers differ, in words:
/// what `--resume` checks, so an image continues only the render it came from.
pub fn identity_mismatch(image: &PartialHeader, this: &PartialHeader) -> Option<String> {
    identity_fields(image).into_iter().zip(identity_fields(this)).filter(|((field, _), _)| *field != "total passes").find(|((_, a), (_, b))| a != b).map(
        |((field, a), (_, b))| match field {
            "configuration" => {
                let (a, b) = first_difference(&a, &b);
                format!("it has configuration {a}, this render {b}")
            }
            "scene hash" => format!("it is of another scene ({}; this render's is {})", image.scene, this.scene),
            _ => format!("it has {field} {a}, this render {b}"),
        },
    )
}

/// What a merge must cover.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cover {
    /// Every pass of the render: the final image.
    All,
    /// One contiguous range, from the first part's start to the last part's end: a
    /// partial image again, for merging in stages.
    Contiguous,
}

/// Check that `parts` (path, header) belong to one render and cover `cover` exactly once;
/// the range they cover. Problems: a part differing from the first in any identity field
/// (the program version included), overlapping ranges, and missing ranges.
pub fn check_parts(parts: &[(PathBuf, PartialHeader)], cover: Cover) -> Result<PassRange, MergeError> {
    let mut problems = Vec::new();
    let Some((first_path, first)) = parts.first() else { return Err(MergeError(vec!["no parts given".into()])) };
    let reference = identity_fields(first);
    for (path, h) in &parts[1..] {
        for ((field, want), (_, got)) in reference.iter().zip(identity_fields(h)) {
            if *want != got && *field == "configuration" {
                let (theirs, ours) = first_difference(&got, want);
                problems.push(format!("'{}' has configuration {theirs}, but '{}' has {ours}", path.display(), first_path.display()));
            } else if *want != got {
                let scenes = if *field == "scene hash" { format!(" (scenes {} and {})", h.scene, first.scene) } else { String::new() };
                problems.push(format!("'{}' has {field} {got}, but '{}' has {want}{scenes}", path.display(), first_path.display()));
            }
        }
    }
    if !problems.is_empty() {
        return Err(MergeError(problems));
    }
    let mut by_start: Vec<(PassRange, &Path)> = parts.iter().map(|(p, h)| (h.passes, p.as_path())).collect();
    by_start.sort();
    let want = match cover {
        Cover::All => PassRange { start: 0, end: first.total },
        Cover::Contiguous => PassRange { start: by_start[0].0.start, end: by_start.iter().map(|(r, _)| r.end).max().unwrap_or(0) },
    };
    let mut covered = want.start;
    let mut last: Option<(PassRange, &Path)> = None;
    for &(r, path) in &by_start {
        if r.start > covered {
            problems.push(format!("passes {}..{} of {} are missing", covered, r.start, first.total));
        }
        if let Some((lr, lp)) = last.filter(|(lr, _)| r.start < lr.end) {
            problems.push(format!("passes {r} of '{}' overlap passes {lr} of '{}'", path.display(), lp.display()));
        }
        if last.is_none_or(|(lr, _)| r.end > lr.end) {
            last = Some((r, path));
        }
        covered = covered.max(r.end);
    }
    if covered < want.end {
        problems.push(format!("passes {}..{} of {} are missing", covered, want.end, first.total));
    }
    if problems.is_empty() { Ok(want) } else { Err(MergeError(problems)) }
}

/// Read, check and merge `paths` to cover `cover`: the merged header (the range
/// covered, tallies summed) and its film. The headers are read and checked first,
/// without any pixels; then the films are read one at a time and added, so memory holds
/// two films however many parts there are.
pub fn merge_parts(paths: &[PathBuf], cover: Cover) -> Result<(PartialHeader, Film), String> {
    let mut headers = Vec::with_capacity(paths.len());
    for path in paths {
        headers.push((path.clone(), read_partial_header(path)?));
    }
    let covered = check_parts(&headers, cover).map_err(|e| e.to_string())?;
    let mut whole: Option<Film> = None;
    for (path, checked) in &headers {
        let (header, film) = read_partial(path)?;
        if header != *checked {
            return Err(format!("{} changed while the parts were merged", path.display()));
        }
        match &mut whole {
            None => whole = Some(film),
            Some(w) => w.merge(&film).map_err(|e| e.to_string())?,
        }
    }
    let film = whole.ok_or("no parts given")?;
    let mut header = headers.swap_remove(0).1;
    header.passes = covered;
    header.tallies = film.tallies();
    Ok((header, film))
}

#[cfg(test)]
mod tests;
