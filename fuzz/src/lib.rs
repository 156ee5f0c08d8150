//! Shared pieces of the fuzz targets: a byte reader that turns libFuzzer's input into
//! bounded, finite numbers, a checker for "a minimum share of inputs produced a sample",
//! and the relative comparison the targets use.
//!
//! Inputs are decoded, not `arbitrary`-derived, so each byte has a stable meaning and the
//! committed seeds stay valid when a target grows: a target reads what it needs and an
//! exhausted input reads as zeros.

use core::sync::atomic::{AtomicU64, Ordering};

use glam::{Vec2, Vec3};

/// Reads numbers from fuzz input bytes; past the end every read yields zero bytes.
#[derive(Debug)]
pub struct Bytes<'a> {
    data: &'a [u8],
}

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Self { data }
    }

    pub fn u8(&mut self) -> u8 {
        match self.data.split_first() {
            Some((&b, rest)) => {
                self.data = rest;
                b
            }
            None => 0,
        }
    }

    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    /// A random number in [0, 1) with 24 bits, as the samplers produce.
    pub fn unit(&mut self) -> f32 {
        (self.u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    pub fn unit2(&mut self) -> Vec2 {
        Vec2::new(self.unit(), self.unit())
    }

    /// Any finite f32 (the raw bits; non-finite bit patterns map to 0).
    pub fn finite(&mut self) -> f32 {
        let v = f32::from_bits(self.u32());
        if v.is_finite() { v } else { 0.0 }
    }

    /// Log-uniform in [lo, hi] (both > 0).
    pub fn log_uniform(&mut self, lo: f32, hi: f32) -> f32 {
        let t = self.unit();
        (lo.ln() + t * (hi.ln() - lo.ln())).exp().clamp(lo, hi)
    }

    /// A unit direction: either from raw finite components (any direction f32 can
    /// normalise, including nearly tangent ones) or from spherical coordinates with
    /// cos θ drawn to reach grazing angles down to 1e-7 from the plane. `None` when the
    /// raw components have no direction.
    pub fn direction(&mut self) -> Option<Vec3> {
        if self.u8() & 1 == 0 {
            let v = Vec3::new(self.finite(), self.finite(), self.finite());
            // Scale to a sane magnitude first so length() cannot overflow.
            let m = v.abs().max_element();
            if !(m > 0.0) || !m.is_finite() {
                return None;
            }
            let w = (v / m).normalize();
            return w.is_finite().then_some(w);
        }
        let sign = if self.u8() & 1 == 0 { 1.0 } else { -1.0 };
        let cos_theta = match self.u8() % 3 {
            0 => self.unit(),
            1 => self.log_uniform(1e-7, 1.0),
            _ => 1.0 - self.log_uniform(1e-7, 1.0),
        };
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let phi = self.unit() * core::f32::consts::TAU;
        Some(Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), sign * cos_theta).normalize())
    }

    /// A point with |p| anywhere from 1e-4 to 1e5 (log-uniform scale, random direction).
    pub fn point(&mut self) -> Vec3 {
        let scale = self.log_uniform(1e-4, 1e5);
        let d = self.direction().unwrap_or(Vec3::X);
        d * scale
    }
}

/// Counts inputs that *should* produce a sample and those that did, and fails once
/// enough inputs have been seen if the share is below the floor, so a target cannot pass
/// by rejecting everything (or by a bug that makes `sample` always return `None`).
#[derive(Debug)]
pub struct ShareFloor {
    pub name: &'static str,
    pub floor: f64,
    pub after: u64,
    eligible: AtomicU64,
    produced: AtomicU64,
}

impl ShareFloor {
    pub const fn new(name: &'static str, floor: f64, after: u64) -> Self {
        Self { name, floor, after, eligible: AtomicU64::new(0), produced: AtomicU64::new(0) }
    }

    pub fn record(&self, produced: bool) {
        let n = self.eligible.fetch_add(1, Ordering::Relaxed) + 1;
        let k = self.produced.fetch_add(produced as u64, Ordering::Relaxed) + produced as u64;
        if n % self.after == 0 {
            let share = k as f64 / n as f64;
            assert!(share >= self.floor, "{}: only {k} of {n} eligible inputs produced a sample ({share:.3} < {})", self.name, self.floor);
        }
    }
}

/// |a − b| ≤ rel·max(|a|, |b|) + abs.
pub fn close(a: f32, b: f32, rel: f32, abs: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

pub fn finite_nonneg3(v: [f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite() && *c >= 0.0)
}
