//! The core's only `unsafe`: SIMD instructions chosen by the build or by the host.
//!
//! Two things live here, both calls the compiler cannot prove safe on its own:
//!
//! - **SSE2's square roots** as intrinsics ([`sqrt`], [`sqrt_f64`]), where the build
//!   enables SSE2 (every x86-64 target with floating-point registers). LLVM knows the
//!   intrinsic as a square root and vectorises it in a loop over lanes; `libm`'s is the
//!   same instruction behind inline assembly, which no loop can vectorise.
//! - **Lane kernels compiled for a wider instruction set** ([`kernel!`]). The lane phases of
//!   the estimators (`estimators::pt_lanes`) are plain loops over lanes of paths, which
//!   LLVM turns into SIMD for whatever the function they are compiled in enables. The
//!   build's baseline on x86-64 is SSE2 (four f32 lanes, no 64-bit multiply); a kernel
//!   defined with [`kernel!`] is compiled a second and third time inside functions that
//!   enable AVX2 or AVX-512, and calls the copy for the [`Level`] the host chose.
//!
//! # Same bits at every level
//! A level changes how many lanes one instruction advances and how it is encoded,
//! never a result: Rust never fuses a multiply and an add (no FMA is enabled either),
//! nothing here may be reassociated, and the elementary functions are the core's own
//! ([`super::elementary`]), so every lane gets the scalar code's bits at every level.
//!
//! # Why a level is safe to hold
//! Code compiled for AVX-512 is undefined behaviour on a machine without it. A [`Level`]
//! other than [`Level::BASELINE`] can only be made by [`Level::assume`], which is
//! `unsafe`: its caller (the host, which detects the machine's features with `std`)
//! promises the machine has the set. Everything else here follows from that promise.
#![allow(unsafe_code)]

/// The instruction set the lane kernels run with. The default is the build's baseline.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Level(Set);

/// The sets [`Level`] can name.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Set {
    /// Whatever the build targets (SSE2 on x86-64, NEON on AArch64, scalar on thumbv7em;
    /// `simd128` in the browser when built with it).
    #[default]
    Baseline,
    /// x86-64 AVX2 with BMI1/2, LZCNT and POPCNT (no FMA).
    Avx2,
    /// x86-64 AVX-512 F, VL, BW and DQ, with AVX2's set.
    Avx512,
}

impl Level {
    /// The build's baseline: safe everywhere.
    pub const BASELINE: Level = Level(Set::Baseline);

    /// The level for `set`.
    ///
    /// # Safety
    /// The machine the program runs on must offer `set` (the host checks with
    /// `is_x86_feature_detected!`; `ember_host::accel::Isa` does). [`Set::Avx2`] and
    /// [`Set::Avx512`] off x86-64 fall back to the baseline.
    pub const unsafe fn assume(set: Set) -> Level {
        Level(set)
    }

    /// The set.
    pub fn set(self) -> Set {
        self.0
    }

    /// Paths the lane loop keeps in flight for lane kernels at this level: 16 where AVX2
    /// or AVX-512 run them, else 1 (one path at a time, unless the tracer asks for more).
    /// Measured on the suite, one thread (docs/lanes.md): with PT's kernels on AVX-512, 16
    /// paths ran the Cornell box 1.12× and window_env 1.15× as fast as one at a time; on
    /// SSE2's four narrow lanes the batch cost more than it saved (0.88×).
    pub fn paths_in_flight(self) -> usize {
        match self.0 {
            Set::Avx2 | Set::Avx512 => 16,
            Set::Baseline => 1,
        }
    }

    /// Its name as `--simd` takes it: `avx2`, `avx512`, or the build's baseline (`sse` on
    /// x86-64, `neon` on AArch64, `simd128` on wasm32 built with it, else `scalar`).
    pub fn name(self) -> &'static str {
        match self.0 {
            Set::Avx2 => "avx2",
            Set::Avx512 => "avx512",
            Set::Baseline if cfg!(target_arch = "x86_64") => "sse",
            Set::Baseline if cfg!(target_arch = "aarch64") => "neon",
            Set::Baseline if cfg!(all(target_arch = "wasm32", target_feature = "simd128")) => "simd128",
            Set::Baseline => "scalar",
        }
    }
}

/// Define a lane kernel: a function compiled for the baseline and, on x86-64, again for
/// AVX2 and AVX-512, taking a [`Level`] first and calling the copy for it.
///
/// ```ignore
/// simd::kernel! {
///     /// What it does.
///     fn scale(level, xs: &mut [f32; 16], k: f32) {
///         for x in xs.iter_mut() { *x *= k; }
///     }
/// }
/// scale(params.simd, &mut xs, 2.0);
/// ```
///
/// Each copy is a function of its own whose parameters are the kernel's, so the
/// compiler knows that a `&mut` array does not overlap the others and vectorises loops
/// over them; a closure passed to a generic runner reached them through its captures,
/// and its loops stayed scalar ("too many memory checks"). The `unsafe` the expansion
/// contains is this module's: calling the copy for a level, which only
/// [`Level::assume`] can make.
#[macro_export]
macro_rules! lane_kernel {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($level:ident $(, $arg:ident: $ty:ty)* $(,)?) $body:block) => {
        $(#[$meta])*
        #[inline]
        $vis fn $name($level: $crate::math::simd::Level $(, $arg: $ty)*) {
            #[inline(always)]
            fn body($($arg: $ty),*) $body
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
            fn avx2($($arg: $ty),*) {
                body($($arg),*)
            }
            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq,avx2,bmi1,bmi2,lzcnt,popcnt")]
            fn avx512($($arg: $ty),*) {
                body($($arg),*)
            }
            match $level.set() {
                // SAFETY: a level other than the baseline was made by `Level::assume`,
                // whose caller promised that the machine offers its set.
                #[cfg(target_arch = "x86_64")]
                $crate::math::simd::Set::Avx512 => {
                    #[allow(unsafe_code)]
                    unsafe {
                        avx512($($arg),*)
                    }
                }
                // SAFETY: as above.
                #[cfg(target_arch = "x86_64")]
                $crate::math::simd::Set::Avx2 => {
                    #[allow(unsafe_code)]
                    unsafe {
                        avx2($($arg),*)
                    }
                }
                _ => body($($arg),*),
            }
        }
    };
}
pub use lane_kernel as kernel;

/// √x, correctly rounded, through SSE2's `sqrtss` (see the module notes).
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
#[inline(always)]
pub(super) fn sqrt(x: f32) -> f32 {
    use core::arch::x86_64::{_mm_cvtss_f32, _mm_set_ss, _mm_sqrt_ss};
    // SAFETY: the build enables SSE2 (the cfg), so the CPU has it; the intrinsics read
    // and write only their register arguments.
    unsafe { _mm_cvtss_f32(_mm_sqrt_ss(_mm_set_ss(x))) }
}

/// [`sqrt`] in f64 (`sqrtsd`).
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
#[inline(always)]
pub(super) fn sqrt_f64(x: f64) -> f64 {
    use core::arch::x86_64::{_mm_cvtsd_f64, _mm_set_sd, _mm_sqrt_sd};
    // SAFETY: as for `sqrt`.
    unsafe { _mm_cvtsd_f64(_mm_sqrt_sd(_mm_set_sd(x), _mm_set_sd(x))) }
}
