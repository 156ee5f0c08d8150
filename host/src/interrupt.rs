//! Signals that stop a render: Ctrl-C (SIGINT), and the termination signals a scheduler,
//! a container runtime or a closing terminal sends (SIGTERM, SIGHUP).
//!
//! - **SIGINT**: the first asks the render to stop after the pass in progress (the image
//!   of the completed passes is then written); a second one quits at once, writing
//!   nothing. SIGINTs within [`REPEAT_WINDOW`] of the first count as one: GNU `timeout -s
//!   INT` signals the child and then its process group, so one Ctrl-C arrived twice
//!   within microseconds and lost the image.
//! - **SIGTERM, SIGHUP**: the completed passes are written at once, atomically, and the
//!   process exits with 128 + the signal. The pass in progress is finished only if it
//!   ends within [`TERMINATE_GRACE`] (a scheduler's grace period may be shorter than a
//!   pass: Slurm's KillWait and Kubernetes' default are 30 s); otherwise it is abandoned
//!   ([`abandon_pass`], polled by the driver before each chunk). Repeats never abort the
//!   write. With no pass completed there is nothing to keep, and the process exits at once.
//!
//! The state is static so that the driver can poll it without the handler owning
//! anything; only `ember`'s `render` path installs the handler (a thread reading the
//! signals through signal-hook's self-pipe, so what it does is ordinary code, not a
//! signal handler), so library users and tests never see a process-wide handler they did
//! not ask for.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicU32, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};

static REQUESTED: AtomicBool = AtomicBool::new(false);
/// The first signal's number (0: none yet).
static FIRST: AtomicU8 = AtomicU8::new(0);
/// Milliseconds after [`epoch`] of the first signal.
static FIRST_AT_MS: AtomicU64 = AtomicU64::new(0);
/// Passes committed so far (set by the driver through [`note_passes`]).
static COMMITTED: AtomicU32 = AtomicU32::new(0);
static INSTALLED: OnceLock<Result<(), String>> = OnceLock::new();

/// Exit status after Ctrl-C (128 + SIGINT, as shells report it).
pub const EXIT_CODE: u8 = 130;
/// Signals this soon after the first SIGINT are the same Ctrl-C.
pub const REPEAT_WINDOW: Duration = Duration::from_millis(100);
/// After SIGTERM or SIGHUP, how long the pass in progress may still take to end.
pub const TERMINATE_GRACE: Duration = Duration::from_secs(2);

fn epoch() -> Instant {
    static EPOCH: OnceLock<Instant> = OnceLock::new();
    *EPOCH.get_or_init(Instant::now)
}

fn now_ms() -> u64 {
    epoch().elapsed().as_millis() as u64
}

/// The flag the driver polls between passes.
pub fn flag() -> &'static AtomicBool {
    &REQUESTED
}

/// Should the pass in progress be abandoned? True once [`TERMINATE_GRACE`] has passed
/// since a SIGTERM or SIGHUP; never for SIGINT (its pass is always finished).
pub fn abandon_pass() -> bool {
    let first = FIRST.load(Ordering::SeqCst) as i32;
    (first == SIGTERM || first == SIGHUP) && now_ms().saturating_sub(FIRST_AT_MS.load(Ordering::SeqCst)) >= TERMINATE_GRACE.as_millis() as u64
}

/// The driver reports the passes committed so far (a termination signal with none
/// exits at once).
pub fn note_passes(passes: u32) {
    COMMITTED.store(passes, Ordering::SeqCst);
}

/// The exit status for the signal that stopped the render: 128 + its number.
pub fn exit_code() -> u8 {
    match FIRST.load(Ordering::SeqCst) {
        0 => EXIT_CODE,
        s => 128 + s,
    }
}

/// The name of the signal that stopped the render, for messages.
pub fn signal_name() -> &'static str {
    match FIRST.load(Ordering::SeqCst) as i32 {
        SIGTERM => "SIGTERM",
        SIGHUP => "SIGHUP",
        _ => "Ctrl-C",
    }
}

/// What to do with one signal, given the first one's number and how long ago it came
/// (`None`: this is the first). Pure, so the rules are tested without signals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Record it as the first and stop after the pass in progress.
    Stop,
    /// Record it as the first, stop now if nothing is kept, else write the completed passes.
    Terminate,
    /// The same Ctrl-C seen twice, or a termination signal repeated: nothing more.
    Ignore,
    /// A second Ctrl-C: quit at once, writing nothing.
    Quit,
}

/// The rules of the module's documentation.
pub fn action(signal: i32, first: Option<(i32, Duration)>) -> Action {
    match (signal, first) {
        (SIGINT, None) => Action::Stop,
        (_, None) => Action::Terminate,
        (SIGINT, Some((SIGINT, since))) if since < REPEAT_WINDOW => Action::Ignore,
        (SIGINT, Some((SIGINT, _))) => Action::Quit,
        // A termination signal while a Ctrl-C finishes its pass: the pass may be long.
        (SIGTERM | SIGHUP, Some((SIGINT, _))) => Action::Terminate,
        // After a termination signal, the write goes on whatever else arrives.
        _ => Action::Ignore,
    }
}

/// Install the handler (once per process). A failure to install is returned as text
/// (the render still runs; the signals then end it the default way).
pub fn install() -> Result<(), String> {
    INSTALLED
        .get_or_init(|| {
            epoch();
            let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]).map_err(|e| format!("cannot handle signals: {e}"))?;
            std::thread::Builder::new()
                .name("ember-signals".into())
                .spawn(move || {
                    for signal in signals.forever() {
                        handle(signal);
                    }
                })
                .map(|_| ())
                .map_err(|e| format!("cannot handle signals: {e}"))
        })
        .clone()
}

fn handle(signal: i32) {
    let first = match FIRST.load(Ordering::SeqCst) {
        0 => None,
        s => Some((s as i32, Duration::from_millis(now_ms().saturating_sub(FIRST_AT_MS.load(Ordering::SeqCst))))),
    };
    match action(signal, first) {
        Action::Stop | Action::Terminate => {
            FIRST_AT_MS.store(now_ms(), Ordering::SeqCst);
            FIRST.store(signal as u8, Ordering::SeqCst);
            REQUESTED.store(true, Ordering::SeqCst);
            if signal == SIGINT {
                eprintln!("\ninterrupt: finishing the pass in progress, then writing the image of the completed passes (Ctrl-C again to quit at once)");
            } else if COMMITTED.load(Ordering::SeqCst) == 0 {
                eprintln!("\n{}: no pass completed yet; nothing written", signal_name());
                std::process::exit(exit_code() as i32);
            } else {
                eprintln!(
                    "\n{}: writing the image of the completed passes (the pass in progress is abandoned unless it ends within {} s)",
                    signal_name(),
                    TERMINATE_GRACE.as_secs()
                );
            }
        }
        Action::Ignore => {}
        Action::Quit => {
            eprintln!("\ninterrupt: quitting; nothing written");
            std::process::exit(EXIT_CODE as i32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rules, signal by signal. Injected bug checked: without the `REPEAT_WINDOW`
    /// arm, the second assertion fails (two SIGINTs microseconds apart quit without
    /// writing, as GNU `timeout -s INT` made happen).
    #[test]
    fn repeats_within_the_window_are_one_and_termination_is_never_aborted() {
        let ms = Duration::from_millis;
        assert_eq!(action(SIGINT, None), Action::Stop);
        assert_eq!(action(SIGINT, Some((SIGINT, ms(0)))), Action::Ignore);
        assert_eq!(action(SIGINT, Some((SIGINT, ms(99)))), Action::Ignore);
        assert_eq!(action(SIGINT, Some((SIGINT, ms(1000)))), Action::Quit);
        assert_eq!(action(SIGTERM, None), Action::Terminate);
        assert_eq!(action(SIGHUP, None), Action::Terminate);
        for later in [SIGTERM, SIGHUP, SIGINT] {
            assert_eq!(action(later, Some((SIGTERM, ms(5000)))), Action::Ignore, "signal {later} after SIGTERM");
        }
        assert_eq!(action(SIGTERM, Some((SIGINT, ms(5000)))), Action::Terminate, "a scheduler's SIGTERM after a Ctrl-C");
    }
}
