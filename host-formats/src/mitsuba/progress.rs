//! Progress of a long scene load on stderr: "loading <file>: N of M shapes".
//!
//! Nothing is printed for a scene that loads within [`QUIET_FOR`] (the suite's scenes,
//! the tests' scenes); past it, one line when the XML is parsed, then at most one line
//! every [`EVERY`] while shapes are instantiated, and a last line with the total time
//! (the only one for a scene whose time goes into one large mesh).
//! Plain lines rather than a redrawn bar: they read the same in a terminal and a log.

use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

/// Loads shorter than this print nothing.
const QUIET_FOR: Duration = Duration::from_secs(1);
/// The most often a line is printed.
const EVERY: Duration = Duration::from_secs(1);

/// Where a load's progress goes, and when it last went there.
pub(crate) struct Progress {
    file: String,
    start: Instant,
    quiet_for: Duration,
    every: Duration,
    last: Option<Instant>,
    shapes: usize,
    sink: Box<dyn Write>,
}

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Progress").field("file", &self.file).field("shapes", &self.shapes).finish_non_exhaustive()
    }
}

impl Progress {
    /// Progress of loading `file`, starting now, on stderr.
    pub fn stderr(file: &Path) -> Self {
        Self::to(file, QUIET_FOR, EVERY, Box::new(std::io::stderr()))
    }

    /// Progress into `sink`, silent for loads shorter than `quiet_for`, a line at most
    /// `every` after that.
    pub fn to(file: &Path, quiet_for: Duration, every: Duration, sink: Box<dyn Write>) -> Self {
        Self { file: file.display().to_string(), start: Instant::now(), quiet_for, every, last: None, shapes: 0, sink }
    }

    /// The XML is parsed: `shapes` shapes are to be instantiated.
    pub fn parsed(&mut self, shapes: usize) {
        self.shapes = shapes;
        let now = Instant::now();
        if self.due(now) {
            self.say(now, format_args!("XML read, {shapes} shape{} to build", plural(shapes)));
        }
    }

    /// `done` of the shapes are instantiated. Cheap when no line is due.
    pub fn shape_done(&mut self, done: usize) {
        // One clock read per 64 shapes keeps this off the profile of huge scenes.
        if !done.is_multiple_of(64) {
            return;
        }
        let now = Instant::now();
        if self.due(now) {
            let shapes = self.shapes;
            self.say(now, format_args!("{done} of {shapes} shapes"));
        }
    }

    /// Everything is instantiated: a last line with the load's time, if it took
    /// `quiet_for` or more (a scene of one huge mesh prints only this).
    pub fn finish(&mut self) {
        let now = Instant::now();
        if now.duration_since(self.start) >= self.quiet_for {
            let shapes = self.shapes;
            self.say(now, format_args!("done, {shapes} shape{}", plural(shapes)));
        }
    }

    fn due(&self, now: Instant) -> bool {
        now.duration_since(self.start) >= self.quiet_for && self.last.is_none_or(|t| now.duration_since(t) >= self.every)
    }

    fn say(&mut self, now: Instant, what: std::fmt::Arguments) {
        self.last = Some(now);
        let seconds = now.duration_since(self.start).as_secs_f64();
        // A closed stderr is no reason to fail a load.
        let _ = writeln!(self.sink, "loading {}: {what} ({seconds:.1} s)", self.file);
    }
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}
