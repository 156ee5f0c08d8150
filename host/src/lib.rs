//! `ember-host`: what every host with `std` shares around the `no_std` core — the
//! ray queries ([`accel`]: BVH over triangles, exact spheres, the core's `RayQuery`), the
//! render protocol on threads ([`driver`]), interrupts ([`interrupt`]), the memory check
//! ([`memory`]), scene preparation that reads no files ([`scene`]), the steps from a
//! configuration to a renderer every host takes ([`setup`]: the plan, the memory check,
//! the radius check) and the program's version ([`program_version`]).
//!
//! What code here may do: threads, clocks and signal handlers (in [`driver`],
//! [`interrupt`] and [`setup`] only, behind the default cargo feature `threads`: without it the crate
//! compiles for `wasm32-unknown-unknown`, and the browser's module traces with its
//! [`accel`]), and reading `/proc`. What it may not: read or write scene and image files
//! (that is `ember-formats`), parse command lines (`ember-cli`), or print — a library
//! host (the C API) prints nothing, so progress goes through [`driver::Progress`], which
//! the command line implements. `unsafe` appears in two modules only:
//! `accel/isa.rs` (the calls into the traversal compiled for AVX2 and AVX-512, made only
//! on a machine that has them) and `accel/embree/ffi.rs` (our bindings to Embree, behind
//! the off-by-default feature `embree`).

pub mod accel;
#[cfg(feature = "threads")]
pub mod driver;
#[cfg(feature = "threads")]
pub mod interrupt;
pub mod memory;
pub mod scene;
#[cfg(feature = "threads")]
pub mod setup;

/// This program's version and build: parts of a split render and exported films from
/// different builds are never merged, since any code change may change the passes' bits.
pub fn program_version() -> String {
    format!("ember {} ({})", env!("CARGO_PKG_VERSION"), env!("EMBER_BUILD"))
}
