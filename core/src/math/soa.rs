//! Lanes of paths in structure-of-arrays form: one array per component, indexed by lane.
//!
//! The lane loop (`transport::lanes`) keeps up to [`LANES`] paths in flight. Code that
//! shades them together stores each quantity as a [`Lane`] of floats (or a [`Vec3s`] of
//! three), and writes each phase as a loop over the lanes whose body is the scalar
//! arithmetic of one lane: straight-line code, with `if`s that pick between two values
//! already computed (selects) rather than branches. The compiler then runs the loop over
//! SIMD registers, and every lane gets the bits the scalar code gives it (Rust never
//! fuses a multiply and an add, and each lane does the same operations in the same
//! order).

use crate::math::Vec3;
use crate::spectrum::Rgb;

/// Paths in flight per batch of the lane loop.
pub const LANES: usize = 32;

/// One float per lane.
pub type Lane = [f32; LANES];

/// A vector (or an RGB triple) per lane, one array per component.
#[derive(Clone, Copy, Debug)]
pub struct Vec3s {
    pub x: Lane,
    pub y: Lane,
    pub z: Lane,
}

impl Vec3s {
    pub const ZERO: Self = Self { x: [0.0; LANES], y: [0.0; LANES], z: [0.0; LANES] };

    /// Lane `i`'s vector.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    #[inline(always)]
    pub fn set(&mut self, i: usize, v: Vec3) {
        self.x[i] = v.x;
        self.y[i] = v.y;
        self.z[i] = v.z;
    }

    /// Lane `i` read as a colour.
    #[inline(always)]
    pub fn rgb(&self, i: usize) -> Rgb {
        Rgb::new(self.x[i], self.y[i], self.z[i])
    }

    #[inline(always)]
    pub fn set_rgb(&mut self, i: usize, c: Rgb) {
        self.x[i] = c.r;
        self.y[i] = c.g;
        self.z[i] = c.b;
    }
}

/// A BSDF sample per lane that continues a path: the next direction (world), the
/// throughput f |cos| c / p, p, and whether there is one.
#[derive(Clone, Copy, Debug)]
pub struct BounceLanes {
    pub wi: Vec3s,
    pub throughput: Vec3s,
    pub pdf: Lane,
    pub ok: [bool; LANES],
}

impl BounceLanes {
    pub const ZERO: Self = Self { wi: Vec3s::ZERO, throughput: Vec3s::ZERO, pdf: [0.0; LANES], ok: [false; LANES] };

    /// Lane `i`'s sample: its throughput, direction and p, if there is one.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Option<(Rgb, Vec3, f32)> {
        self.ok[i].then(|| (self.throughput.rgb(i), self.wi.get(i), self.pdf[i]))
    }

    #[inline(always)]
    pub fn set(&mut self, i: usize, wi: Vec3, throughput: Rgb, pdf: f32, ok: bool) {
        self.wi.set(i, wi);
        self.throughput.set_rgb(i, throughput);
        self.pdf[i] = pdf;
        self.ok[i] = ok;
    }
}

/// `a` where `c`, else `b`, component by component: a select in every lane, where an
/// `if` over whole vectors may compile to a branch and keep the loop scalar.
#[inline(always)]
pub fn select3(c: bool, a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(if c { a.x } else { b.x }, if c { a.y } else { b.y }, if c { a.z } else { b.z })
}

/// [`select3`] for colours.
#[inline(always)]
pub fn select_rgb(c: bool, a: Rgb, b: Rgb) -> Rgb {
    Rgb::new(if c { a.r } else { b.r }, if c { a.g } else { b.g }, if c { a.b } else { b.b })
}

/// SIMD groups of lanes.
pub const GROUP: usize = 8;

/// `n` lanes rounded up to whole groups of [`GROUP`]: the phases run that many, so that
/// their loops have a length known at compile time ([`over_lanes`]); the lanes past `n`
/// compute on stale values that nothing reads.
#[inline(always)]
pub fn whole_groups(n: usize) -> usize {
    n.next_multiple_of(GROUP).min(LANES)
}

/// Run `$body` for lanes `$i` in `0..$groups` (a multiple of [`GROUP`]), in a loop of
/// constant length, which the compiler runs over SIMD registers (a loop of run-time
/// length stayed scalar). A macro, not a function taking a closure: a closure reaches
/// the phase's arrays through its captures, which hides from the compiler that they do
/// not overlap, and the loop stayed scalar too.
macro_rules! over_lanes {
    ($groups:expr, |$i:ident| $body:block) => {
        match $groups {
            0 => {}
            8 => for $i in 0..8 $body,
            16 => for $i in 0..16 $body,
            24 => for $i in 0..24 $body,
            _ => for $i in 0..$crate::math::soa::LANES $body,
        }
    };
}

pub(crate) use over_lanes;
