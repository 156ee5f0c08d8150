//! Ctrl-C: the first asks the render to stop after the pass in progress (the image of the
//! completed passes is then written), the second exits at once.
//!
//! The flag is a static so that the driver can poll it between passes without the
//! handler owning anything; only `ember`'s `main` path installs the handler, so library
//! users and tests never see a process-wide signal handler they did not ask for.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);
static PRESSES: AtomicU32 = AtomicU32::new(0);
static INSTALLED: OnceLock<Result<(), String>> = OnceLock::new();

/// Exit status after an interruption (128 + SIGINT, as shells report it).
pub const EXIT_CODE: u8 = 130;

/// The flag the driver polls between passes.
pub fn flag() -> &'static AtomicBool {
    &REQUESTED
}

/// Install the handler (once per process). A failure to install is returned as text
/// (the render still runs; Ctrl-C then ends it the default way).
pub fn install() -> Result<(), String> {
    INSTALLED
        .get_or_init(|| {
            ctrlc::set_handler(|| {
                if PRESSES.fetch_add(1, Ordering::SeqCst) == 0 {
                    REQUESTED.store(true, Ordering::SeqCst);
                    eprintln!("\ninterrupt: finishing the pass in progress, then writing the image of the completed passes (Ctrl-C again to quit at once)");
                } else {
                    eprintln!("\ninterrupt: quitting; nothing written");
                    std::process::exit(EXIT_CODE as i32);
                }
            })
            .map_err(|e| format!("cannot handle Ctrl-C: {e}"))
        })
        .clone()
}
