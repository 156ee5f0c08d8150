//! The instruction set the BVH4's traversal runs with, chosen at run time (issue 52).
//!
//! # Why
//! The traversal (the BVH4, `Wide`: slab tests of four boxes, watertight tests of four
//! triangles) is written once, on glam's 4-lane `Vec4`. Compiled for the x86-64
//! baseline, that is SSE2: two-operand instructions, so every operation that keeps its
//! input costs a register copy first. The same source compiled with AVX2 (or AVX-512)
//! enabled gets three-operand VEX (EVEX) encodings and BMI's bit scans for the child
//! masks: on PT's queries of the suite's Cornell box, 10.5 % fewer instructions per
//! closest hit and 12 % fewer per occlusion test (callgrind, docs/performance.md). The
//! binary must still run on any x86-64, so the wider instruction sets are compiled into
//! extra copies of the two traversal functions and picked per machine.
//!
//! # Same bits on every instruction set
//! Each copy is the same Rust inlined under a `#[target_feature]` function: the same
//! IEEE operations in the same order, lane by lane. Rust never fuses a multiply and an
//! add unless asked (`mul_add`), and none of the traversal's reductions may be
//! reassociated, so enabling AVX2 or AVX-512 changes the encoding, not a result: every
//! copy returns the same hit, distance and barycentrics bit for bit (checked in
//! `wide`'s tests on every instruction set the machine offers, and by
//! `host-cli/tests/simd_widths.rs` on whole images). So an image does not depend on the
//! machine's instruction set, nor on `--simd`.
//!
//! # Choosing
//! [`Isa::best`] is AVX2 where the machine has it (AVX-512 measured no faster for
//! these 4-lane kernels), else its widest set; `ember render --simd NAME` or the
//! environment variable `EMBER_SIMD=NAME` force one ([`Isa::select`]: the option wins);
//! a name the machine does not offer, or no name we know, is refused with the list of
//! what it offers. The names: `scalar` (no SIMD: targets without a vector unit glam
//! uses), `sse` (x86-64's baseline, SSE2), `avx2`, `avx512` (F, VL, BW, DQ), `neon`
//! (AArch64's baseline) and `simd128` (wasm32 built with it).
//!
//! # Lanes
//! Whatever the set, the kernels are four lanes wide: a node's four children, a leaf's
//! four triangles. The path loop still walks one path at a time (`transport::lanes` at
//! width 1), so the wider registers are not yet filled with more paths; that is the
//! next step of docs/lanes.md.
//!
//! # `unsafe`
//! Calling a `#[target_feature]` function is `unsafe`: it is undefined behaviour on a
//! machine without the feature. This module holds the only such calls, and an [`Isa`]
//! reaches them only through [`Isa::best`], [`Isa::select`] or `Wide::set_isa`, each
//! of which admits only a set [`Isa::offered`] detected on this machine.
#![allow(unsafe_code)]

use core::fmt;

use obvhs::ray::Ray as BvhRay;

use super::triangle::WatertightRay;

/// Lanes of the traversal kernels on every set: a node's children, a leaf's triangles.
pub const KERNEL_LANES: usize = 4;

/// An instruction set for the traversal kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Isa {
    /// No SIMD unit: glam's scalar fallback.
    Scalar,
    /// SSE2, x86-64's baseline.
    Sse,
    /// AVX2 with BMI1/2, LZCNT and POPCNT (no FMA: nothing here fuses).
    Avx2,
    /// AVX-512 F, VL, BW and DQ, with AVX2's set.
    Avx512,
    /// AArch64's Advanced SIMD.
    Neon,
    /// WebAssembly's 128-bit SIMD.
    Simd128,
}

/// Every name, in the order [`Isa::offered`] lists them.
const ALL: [Isa; 6] = [Isa::Scalar, Isa::Sse, Isa::Avx2, Isa::Avx512, Isa::Neon, Isa::Simd128];

/// A name that is not an instruction set, or one this machine lacks.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IsaError {
    pub message: String,
}

impl fmt::Display for IsaError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for IsaError {}

impl Isa {
    /// The name `--simd` and `EMBER_SIMD` take.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Sse => "sse",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
            Isa::Neon => "neon",
            Isa::Simd128 => "simd128",
        }
    }

    /// Lanes of the traversal kernels (a node's children, a leaf's triangles).
    pub fn lanes(self) -> usize {
        KERNEL_LANES
    }

    /// True if this machine runs code compiled for the set.
    pub fn is_available(self) -> bool {
        match self {
            // The set glam's lanes compile to when the target has no vector unit.
            Isa::Scalar => !cfg!(any(target_arch = "x86_64", target_arch = "aarch64", all(target_arch = "wasm32", target_feature = "simd128"))),
            Isa::Sse => cfg!(target_arch = "x86_64"),
            Isa::Avx2 => detect_avx2(),
            Isa::Avx512 => detect_avx512(),
            Isa::Neon => cfg!(target_arch = "aarch64"),
            Isa::Simd128 => cfg!(all(target_arch = "wasm32", target_feature = "simd128")),
        }
    }

    /// The sets this machine runs, narrowest first.
    pub fn offered() -> Vec<Isa> {
        ALL.into_iter().filter(|i| i.is_available()).collect()
    }

    /// The set used unless one is asked for: AVX2 where the machine has it, else its
    /// widest. AVX-512 comes after AVX2: the kernels are four lanes wide, so it only
    /// changes their encoding, and on the lent 16-core Xeon it was 0.96× AVX2's PT and
    /// 0.97× its LT samples/s (docs/performance.md); it stays selectable.
    pub fn best() -> Isa {
        const PREFERENCE: [Isa; 6] = [Isa::Avx2, Isa::Avx512, Isa::Sse, Isa::Neon, Isa::Simd128, Isa::Scalar];
        PREFERENCE.into_iter().find(|i| i.is_available()).expect("every target offers its baseline")
    }

    /// The set named `name`, if this machine runs it.
    pub fn from_name(name: &str) -> Result<Isa, IsaError> {
        let offered = || Self::offered().iter().map(|i| i.name()).collect::<Vec<_>>().join(", ");
        let Some(isa) = ALL.into_iter().find(|i| i.name() == name) else {
            let all = ALL.map(Isa::name).join(", ");
            return Err(IsaError { message: format!("unknown SIMD instruction set '{name}' (names: {all}; this machine offers {})", offered()) });
        };
        if !isa.is_available() {
            return Err(IsaError { message: format!("this machine does not offer the SIMD instruction set '{name}' (it offers {})", offered()) });
        }
        Ok(isa)
    }

    /// The set to use: `option` (`--simd`) if given, else `env` (`EMBER_SIMD`) if given
    /// and not empty, else [`Isa::best`]. Errors name where the refused name came from.
    pub fn select(option: Option<&str>, env: Option<&str>) -> Result<Isa, IsaError> {
        fn tagged(source: &'static str) -> impl Fn(IsaError) -> IsaError {
            move |e| IsaError { message: format!("{source}: {}", e.message) }
        }
        match (option, env.filter(|e| !e.is_empty())) {
            (Some(name), _) => Self::from_name(name).map_err(tagged("--simd")),
            (None, Some(name)) => Self::from_name(name).map_err(tagged("EMBER_SIMD")),
            (None, None) => Ok(Self::best()),
        }
    }

    /// The level the core's lane kernels (PT's shading over lanes of paths,
    /// `ember_core::math::simd`) run with for this set: AVX2 and AVX-512 where the machine
    /// offers them, the build's baseline for every other set.
    pub fn shading_level(self) -> ember_core::math::simd::Level {
        use ember_core::math::simd::{Level, Set};
        match self {
            // SAFETY: `is_available` detected the set on this machine.
            Isa::Avx2 if self.is_available() => unsafe { Level::assume(Set::Avx2) },
            // SAFETY: as above.
            Isa::Avx512 if self.is_available() => unsafe { Level::assume(Set::Avx512) },
            _ => Level::BASELINE,
        }
    }

    /// The set the lane kernels use unless one is asked for: the widest. Unlike the
    /// traversal's four-lane kernels ([`Isa::best`]), they fill whatever the registers
    /// hold: PT on the Cornell box ran 1.12× as fast with its lanes on AVX-512 as on
    /// AVX2 (docs/lanes.md).
    pub fn best_for_shading() -> Isa {
        const PREFERENCE: [Isa; 6] = [Isa::Avx512, Isa::Avx2, Isa::Sse, Isa::Neon, Isa::Simd128, Isa::Scalar];
        PREFERENCE.into_iter().find(|i| i.is_available()).expect("every target offers its baseline")
    }

    /// The lane kernels' level: the set `option` (`--simd`) or else `env` (`EMBER_SIMD`)
    /// names, as [`Isa::select`] (so a forced set applies to queries and shading alike),
    /// else [`Isa::best_for_shading`]'s.
    pub fn select_shading(option: Option<&str>, env: Option<&str>) -> Result<ember_core::math::simd::Level, IsaError> {
        let forced = option.is_some() || env.is_some_and(|e| !e.is_empty());
        let isa = if forced { Self::select(option, env)? } else { Self::best_for_shading() };
        Ok(isa.shading_level())
    }

    /// [`Isa::select_shading`] with the environment's `EMBER_SIMD`.
    pub fn select_shading_with_env(option: Option<&str>) -> Result<ember_core::math::simd::Level, IsaError> {
        let env = std::env::var("EMBER_SIMD").ok();
        Self::select_shading(option, env.as_deref())
    }

    /// [`Isa::select`] with the environment's `EMBER_SIMD` (what every host reads).
    pub fn select_with_env(option: Option<&str>) -> Result<Isa, IsaError> {
        let env = std::env::var("EMBER_SIMD").ok();
        Self::select(option, env.as_deref())
    }
}

impl fmt::Display for Isa {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(target_arch = "x86_64")]
fn detect_avx2() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("bmi1")
        && std::arch::is_x86_feature_detected!("bmi2")
        && std::arch::is_x86_feature_detected!("lzcnt")
        && std::arch::is_x86_feature_detected!("popcnt")
}

#[cfg(target_arch = "x86_64")]
fn detect_avx512() -> bool {
    detect_avx2()
        && std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512vl")
        && std::arch::is_x86_feature_detected!("avx512bw")
        && std::arch::is_x86_feature_detected!("avx512dq")
}

#[cfg(not(target_arch = "x86_64"))]
fn detect_avx2() -> bool {
    false
}

#[cfg(not(target_arch = "x86_64"))]
fn detect_avx512() -> bool {
    false
}

/// A traversal written once, which this module compiles for each instruction set: the
/// BVH4 (`wide`) implements it with its baseline functions, inlined here into each copy.
pub(super) trait Kernels {
    /// The set its queries run with: one this machine offers (the only way a set gets
    /// here is through [`Isa::from_name`], [`Isa::select`] or [`Isa::best`]).
    fn isa(&self) -> Isa;
    /// Closest hit in (0, ray.tmax), to be inlined (`#[inline(always)]`).
    fn closest_inline(&self, ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])>;
    /// Any hit in (0, ray.tmax), to be inlined (`#[inline(always)]`).
    fn occluded_inline(&self, ray: &BvhRay, wt: &WatertightRay) -> bool;
}

/// Closest hit through the copy compiled for `k`'s set.
#[inline]
pub(super) fn closest<K: Kernels>(k: &K, ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])> {
    match k.isa() {
        // SAFETY: `Kernels::isa` is a set this machine offers (see the module notes).
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => unsafe { x86::closest_avx512(k, ray, wt) },
        // SAFETY: as above.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { x86::closest_avx2(k, ray, wt) },
        _ => k.closest_inline(ray, wt),
    }
}

/// Occlusion through the copy compiled for `k`'s set.
#[inline]
pub(super) fn occluded<K: Kernels>(k: &K, ray: &BvhRay, wt: &WatertightRay) -> bool {
    match k.isa() {
        // SAFETY: `Kernels::isa` is a set this machine offers (see the module notes).
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => unsafe { x86::occluded_avx512(k, ray, wt) },
        // SAFETY: as above.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { x86::occluded_avx2(k, ray, wt) },
        _ => k.occluded_inline(ray, wt),
    }
}

/// The copies: the baseline traversal inlined under each set's features.
#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::*;

    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    pub(super) fn closest_avx2<K: Kernels>(k: &K, ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])> {
        k.closest_inline(ray, wt)
    }

    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    pub(super) fn occluded_avx2<K: Kernels>(k: &K, ray: &BvhRay, wt: &WatertightRay) -> bool {
        k.occluded_inline(ray, wt)
    }

    #[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq,avx2,bmi1,bmi2,lzcnt,popcnt")]
    pub(super) fn closest_avx512<K: Kernels>(k: &K, ray: &BvhRay, wt: &WatertightRay) -> Option<(usize, f32, [f32; 3])> {
        k.closest_inline(ray, wt)
    }

    #[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq,avx2,bmi1,bmi2,lzcnt,popcnt")]
    pub(super) fn occluded_avx512<K: Kernels>(k: &K, ray: &BvhRay, wt: &WatertightRay) -> bool {
        k.occluded_inline(ray, wt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_the_baseline_is_offered() {
        for isa in ALL {
            assert_eq!(ALL.into_iter().find(|i| i.name() == isa.name()), Some(isa));
        }
        let offered = Isa::offered();
        assert!(!offered.is_empty());
        assert!(offered.contains(&Isa::best()));
        if offered.contains(&Isa::Avx2) {
            assert_eq!(Isa::best(), Isa::Avx2);
        }
        #[cfg(target_arch = "x86_64")]
        assert_eq!(offered[0], Isa::Sse);
        for isa in &offered {
            assert_eq!(Isa::from_name(isa.name()).as_ref(), Ok(isa));
        }
    }

    #[test]
    fn unknown_and_missing_sets_are_refused_with_what_is_offered() {
        let e = Isa::from_name("avx1024").unwrap_err();
        assert!(e.message.contains("unknown SIMD instruction set 'avx1024'") && e.message.contains("this machine offers"), "{e}");
        // A set of another architecture is never offered.
        #[cfg(target_arch = "x86_64")]
        {
            let e = Isa::from_name("neon").unwrap_err();
            assert!(e.message.contains("does not offer the SIMD instruction set 'neon'") && e.message.contains("sse"), "{e}");
        }
        // The option wins over the environment; each error names its source.
        assert_eq!(Isa::select(None, None), Ok(Isa::best()));
        assert_eq!(Isa::select(None, Some("")), Ok(Isa::best()));
        let base = Isa::offered()[0];
        assert_eq!(Isa::select(Some(base.name()), Some("bogus")), Ok(base));
        assert!(Isa::select(None, Some("bogus")).unwrap_err().message.starts_with("EMBER_SIMD: unknown"));
        assert!(Isa::select(Some("bogus"), None).unwrap_err().message.starts_with("--simd: unknown"));
    }
}
