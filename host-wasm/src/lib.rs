//! ember in the browser: every estimator of the core, driven through the core's render
//! protocol ([`ember_core::render`]) on Web Workers, over the CLI's own ray queries
//! ([`Accel`]: ember-host's BVH4 and exact spheres, built without a clock), compiled to `wasm32-unknown-unknown` and driven by a static page (`host-wasm/www/`)
//! through plain C exports. No wasm-bindgen, no imports: the module needs nothing from
//! JavaScript, and JavaScript reads the results straight out of the module's linear
//! memory.
//!
//! # Protocol
//! Every instance (the page's and one per worker) calls
//! `ember_setup(scene, estimator, width, height, max_depth, seed_hi, seed_lo, role)`
//! (role 1 for the page's instance, which holds the film; 0 for a worker). Scene and
//! estimator are indices into [`SCENES`] and [`EstimatorKind::ALL`], listed by
//! `ember_text`. Then, pass by pass ([`session`] has the why):
//! 1. `ember_start_pass(p)` on every instance; then, while `ember_next_phase()` returns 1
//!    on the page's instance, every instance takes the same phase (its `ember_phase_*`
//!    numbers must agree, else the page stops with an error);
//! 2. workers run `ember_map(chunk)` for the chunks the page hands them and send back the
//!    two parts (`ember_part_ptr/len(0 film | 1 state)`) as transferable buffers;
//! 3. the page's instance receives both parts of every chunk, each worker every chunk's
//!    state part (`ember_input(len)` for the bytes, then `ember_receive(chunk, part)`),
//!    and each calls `ember_reduce()` (1 when a pass was committed).
//!
//! Errors: a negative [`Failure`] code, and `ember_text(TEXT_ERROR, 0)` says what.
//!
//! Random numbers derive from (seed, index, pass) only and every reduction takes the
//! chunks in index order, so neither the worker count nor which worker maps which chunk
//! changes the image; and the hierarchy, its build and the primitive tests are the
//! CLI's code (ember-host without its `threads` feature), so the hits are too.

#[cfg(not(target_arch = "wasm32"))]
pub mod compare;
pub mod session;
#[cfg(test)]
mod tests;

use core::cell::RefCell;

use ember_core::estimators::EstimatorKind;
use ember_core::render::wire::Part;
use ember_core::scene::{SceneBuilder, builtin, builtin_glass};

pub use ember_host::accel::Accel;
pub use session::{Failure, Role, Session};

/// The built-in scenes the page offers, by the index it passes to `ember_setup`.
pub const SCENES: [&str; 2] = ["cornell-box", builtin_glass::GLASS_SPHERES];

/// The scene builder for a [`SCENES`] index.
pub fn builtin_scene(index: u32, width: u32, height: u32) -> Option<SceneBuilder> {
    match index {
        0 => Some(builtin::cornell_box(width, height)),
        1 => Some(builtin_glass::glass_spheres(width, height)),
        _ => None,
    }
}

/// `ember_text` subjects.
pub const TEXT_SCENE: u32 = 0;
pub const TEXT_ESTIMATOR: u32 = 1;
pub const TEXT_SUMMARY: u32 = 2;
/// An estimator's default configuration, as the core prints it.
pub const TEXT_CONFIG: u32 = 3;
/// The last error's message.
pub const TEXT_ERROR: u32 = 4;
/// The current phase's name.
pub const TEXT_PHASE: u32 = 5;

/// The text `ember_text(what, i)` returns; `None` for an unknown subject or index.
pub fn text(what: u32, i: u32, session: Option<&Session>, error: &str) -> Option<String> {
    let kind = || EstimatorKind::from_index(i);
    match what {
        TEXT_SCENE => SCENES.get(i as usize).map(|s| s.to_string()),
        TEXT_ESTIMATOR => kind().map(|k| k.name().to_string()),
        TEXT_SUMMARY => kind().map(|k| k.summary().to_string()),
        TEXT_CONFIG => kind().map(|k| format!("{:?}", k.default_config())),
        TEXT_ERROR => Some(error.to_string()),
        TEXT_PHASE => session.and_then(|s| s.phase()).map(|p| p.name.to_string()),
        _ => None,
    }
}

/// The module's state: one session (wasm32 is single-threaded; one instance per worker),
/// the last error and the text buffer.
#[derive(Debug, Default)]
struct Module {
    session: Option<Session>,
    error: String,
    text: String,
}

thread_local! {
    static MODULE: RefCell<Module> = RefCell::new(Module::default());
}

/// Run `f` on the session; a failure's message is kept for `ember_text(TEXT_ERROR)`.
fn with_session(f: impl FnOnce(&mut Session) -> Result<i32, (Failure, String)>) -> i32 {
    MODULE.with_borrow_mut(|m| {
        let result = match m.session.as_mut() {
            Some(s) => f(s),
            None => Err((Failure::NotReady, "no ember_setup yet".into())),
        };
        result.unwrap_or_else(|(code, message)| {
            m.error = message;
            -(code as i32)
        })
    })
}

fn read<T>(default: T, f: impl FnOnce(&Session) -> T) -> T {
    MODULE.with_borrow(|m| m.session.as_ref().map_or(default, f))
}

fn part(p: u32) -> Part {
    if p == 0 { Part::Film } else { Part::State }
}

// The exports below need `#[unsafe(no_mangle)]` so the page can call them by name; the
// attribute is the only unsafe thing in this crate (it trusts no other symbol has the
// same name, and every name carries the `ember_` prefix).

/// Number of built-in scenes.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_scene_count() -> u32 {
    SCENES.len() as u32
}

/// Number of estimators (the core's list).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_estimator_count() -> u32 {
    EstimatorKind::ALL.len() as u32
}

/// 1 if estimator `i` of the core's list is compiled into this module, else 0 (the
/// module's cargo features choose the core's estimator families, docs/features.md; the
/// list and its indices are the same in every build).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_estimator_compiled(i: u32) -> u32 {
    EstimatorKind::from_index(i).is_some_and(EstimatorKind::is_compiled) as u32
}

/// Put text `what` (a `TEXT_*` subject) of item `i` in the text buffer; its length in
/// bytes (UTF-8), or −1 for an unknown subject or index. `ember_text_ptr` gives its
/// address.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_text(what: u32, i: u32) -> i32 {
    MODULE.with_borrow_mut(|m| match text(what, i, m.session.as_ref(), &m.error) {
        Some(t) => {
            m.text = t;
            m.text.len() as i32
        }
        None => -1,
    })
}

/// Address of the text buffer.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_text_ptr() -> usize {
    MODULE.with_borrow(|m| m.text.as_ptr() as usize)
}

/// Build scene `scene` for estimator `estimator`; `role` 1 for the page's instance (it
/// holds the film), 0 for a worker. 0 on success, −[`Failure`] otherwise.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_setup(scene: u32, estimator: u32, width: u32, height: u32, max_depth: i32, seed_hi: u32, seed_lo: u32, role: u32) -> i32 {
    let seed = (u64::from(seed_hi) << 32) | u64::from(seed_lo);
    let role = if role == 1 { Role::Page } else { Role::Worker };
    MODULE.with_borrow_mut(|m| match Session::new(scene, estimator, width, height, max_depth, seed, role) {
        Ok(s) => {
            m.session = Some(s);
            0
        }
        Err((code, message)) => {
            m.session = None;
            m.error = message;
            -(code as i32)
        }
    })
}

/// Triangles in the ray-query structure (for the page's status line).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_triangle_count() -> u32 {
    read(0, |s| s.accel.triangle_count() as u32)
}

/// Queue pass `pass`.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_start_pass(pass: u32) -> i32 {
    with_session(|s| {
        s.start_pass(pass);
        Ok(0)
    })
}

/// Take the next phase: 1 if one is pending, 0 if not.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_next_phase() -> i32 {
    with_session(|s| Ok(i32::from(s.next_phase().is_some())))
}

/// The current phase's id (stable across passes), or −1 without one.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_phase_id() -> i32 {
    read(-1, |s| s.phase().map_or(-1, |p| i32::from(p.id)))
}

/// The current phase's pass, or −1 for a setup phase (or without a phase).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_phase_pass() -> f64 {
    read(-1.0, |s| s.phase().and_then(|p| p.pass).map_or(-1.0, f64::from))
}

/// Items the current phase maps.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_phase_items() -> u32 {
    read(0, |s| s.phase().map_or(0, |p| p.items))
}

/// Chunks of the current phase.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_phase_chunks() -> u32 {
    read(0, |s| s.phase().map_or(0, |p| p.chunk_count() as u32))
}

/// 1 when the current phase's items count as samples (camera samples, light paths).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_phase_samples() -> u32 {
    read(0, |s| s.phase().map_or(0, |p| u32::from(p.samples)))
}

/// Map chunk `chunk` of the current phase; its parts are then at `ember_part_ptr`.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_map(chunk: u32) -> i32 {
    with_session(|s| s.map(chunk).map(|()| 0))
}

/// Address of the last map's part `p` (0 film, 1 state).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_part_ptr(p: u32) -> usize {
    read(0, |s| match part(p) {
        Part::Film => s.film_bytes.as_ptr() as usize,
        Part::State => s.state_bytes.as_ptr() as usize,
    })
}

/// Length in bytes of the last map's part `p`.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_part_len(p: u32) -> u32 {
    read(0, |s| match part(p) {
        Part::Film => s.film_bytes.len() as u32,
        Part::State => s.state_bytes.len() as u32,
    })
}

/// Rays traced by the last map (f64: exact up to 2⁵³).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_map_rays() -> f64 {
    read(0.0, |s| s.last_rays as f64)
}

/// The input buffer, `len` bytes, for a part before `ember_receive`; 0 without setup.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_input(len: u32) -> usize {
    MODULE.with_borrow_mut(|m| {
        m.session.as_mut().map_or(0, |s| {
            s.input.clear();
            s.input.resize(len as usize, 0);
            s.input.as_ptr() as usize
        })
    })
}

/// Take the input buffer as part `p` (0 film, 1 state) of chunk `chunk`'s output.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_receive(chunk: u32, p: u32) -> i32 {
    with_session(|s| s.receive(chunk, part(p)).map(|()| 0))
}

/// Reduce the current phase: 1 when that committed a pass, 0 otherwise.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_reduce() -> i32 {
    with_session(|s| s.reduce().map(i32::from))
}

/// Address of the film's mean image (3 × f32 per pixel, row 0 at the top); 0 without
/// setup.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_image() -> usize {
    MODULE.with_borrow_mut(|m| m.session.as_mut().map_or(0, |s| s.image().as_ptr() as usize))
}

/// Passes committed to the film.
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_passes() -> u32 {
    read(0, |s| s.film.passes())
}

/// Camera samples and splats the film discarded (NaN, infinite or negative).
#[allow(unsafe_code)]
#[unsafe(no_mangle)]
pub extern "C" fn ember_film_discarded() -> f64 {
    read(0.0, |s| s.film.discarded() as f64)
}
