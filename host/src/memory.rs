//! The memory check before large allocations: the core estimates what an estimator will
//! hold ([`ember_core::estimators::MemoryEstimate`]); a render whose estimate exceeds the
//! memory available (the smaller of the kernel's MemAvailable and the cgroup's remaining
//! limit, or `--memory-limit`) is refused with what to lower, instead of aborting with
//! "memory allocation failed" in the middle of its setup.

use std::fs;

use ember_core::camera::PerspectiveCamera;
use ember_core::estimators::{EstimatorConfig, FILM_BYTES_PER_PIXEL, MemoryEstimate};

/// What `config` would hold for a film of `camera`'s size: its estimate, with the bytes
/// at least the film's own.
pub fn need(camera: &PerspectiveCamera, config: &EstimatorConfig) -> (u64, MemoryEstimate) {
    let pixels = camera.width() as u64 * camera.height() as u64;
    let estimate = config.memory_estimate(pixels.min(u32::MAX as u64) as u32);
    (estimate.bytes.max(pixels * FILM_BYTES_PER_PIXEL), estimate)
}

/// Bytes the process may still allocate: min(MemAvailable, cgroup limit − usage), or
/// `None` where neither can be read (then nothing is refused).
pub fn available_bytes() -> Option<u64> {
    let meminfo = fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines().find(|l| l.starts_with("MemAvailable:")).and_then(|l| l.split_whitespace().nth(1)).and_then(|kb| kb.parse::<u64>().ok()).map(|kb| kb * 1024)
    });
    let read = |p: &str| fs::read_to_string(p).ok().and_then(|t| t.trim().parse::<u64>().ok());
    // cgroup v2, then v1 ("max" or an absurd v1 default parse as no limit).
    let cgroup = match (read("/sys/fs/cgroup/memory.max"), read("/sys/fs/cgroup/memory.current")) {
        (Some(max), Some(cur)) => Some(max.saturating_sub(cur)),
        _ => match (read("/sys/fs/cgroup/memory/memory.limit_in_bytes"), read("/sys/fs/cgroup/memory/memory.usage_in_bytes")) {
            (Some(max), Some(cur)) if max < (1u64 << 60) => Some(max.saturating_sub(cur)),
            _ => None,
        },
    };
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// `--memory-limit`: a byte count with an optional binary suffix (K, M, G, T, also
/// written KiB, MiB, GiB, TiB), e.g. `512M`, `2GiB`, `1.5G`.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
    let (number, suffix) = t.split_at(split);
    let scale: u64 = match suffix.trim().to_ascii_uppercase().trim_end_matches("IB").trim_end_matches('B') {
        "" => 1,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        "T" => 1 << 40,
        _ => return Err(format!("'{text}' is not a size: a number with an optional K, M, G or T suffix")),
    };
    let v: f64 = number.parse().map_err(|_| format!("'{text}' is not a size: a number with an optional K, M, G or T suffix"))?;
    let bytes = v * scale as f64;
    match bytes {
        b if b < 1.0 => Err(format!("memory limit '{text}' must be at least 1 byte")),
        // (`99999999999T` was told it "must be at least 1 byte".)
        b if b >= 1.8e19 => Err(format!("memory limit '{text}' is more than any machine has: at most 16 EiB ({}T)", u64::MAX >> 40)),
        b => Ok(b as u64),
    }
}

/// `12345678` → `"11.8 MiB"`.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    match b {
        b if b >= (1u64 << 30) as f64 => format!("{:.1} GiB", b / (1u64 << 30) as f64),
        b if b >= (1u64 << 20) as f64 => format!("{:.1} MiB", b / (1u64 << 20) as f64),
        b => format!("{:.1} KiB", b / 1024.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_suffixes() {
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("2GiB"), Ok(2 << 30));
        assert_eq!(parse_size("1.5G"), Ok(3 << 29));
        assert_eq!(parse_size("4096"), Ok(4096));
        assert!(parse_size("0").is_err());
        assert!(parse_size("nan").is_err());
        assert!(parse_size("12Q").is_err());
        assert!(parse_size("99999999999T").unwrap_err().contains("at most 16 EiB"));
        assert!(available_bytes().is_none_or(|b| b > 0));
    }
}
