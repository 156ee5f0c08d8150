//! Places in the XML text, resolved into line:column only when a message shows them.
//!
//! The parser records a byte offset ([`Loc`]) for every element, attribute and property;
//! nearly all of them are never shown. Turning an offset into a line and column is a scan
//! of the text (roxmltree's `text_pos_at` scans from the start every time), so doing it
//! for every element made loading quadratic in the file's size: 10 000 spheres took 22 s.
//! [`Positions`] resolves an offset when an error or warning needs it: a line through a
//! table of line starts built on first use (a binary search), a column by counting the
//! characters from the line's start, exactly as roxmltree counts them.
//!
//! It also remembers which `-D name=value` overrides were substituted at which offsets,
//! so that an error about a substituted value names the override that supplied it.

use std::cell::{Cell, OnceCell, RefCell};
use std::collections::HashMap;

use super::{Fail, Loc};

/// The text of one scene file and what is known about places in it.
#[derive(Debug)]
pub(crate) struct Positions<'t> {
    text: &'t str,
    /// Byte offset of the start of each line, built on the first resolution.
    line_starts: OnceCell<Vec<usize>>,
    /// How many offsets were resolved (a valid scene without warnings resolves none).
    resolutions: Cell<usize>,
    /// `-D name=value` texts substituted into the attribute or element at each offset.
    overrides: RefCell<HashMap<usize, Vec<String>>>,
}

impl<'t> Positions<'t> {
    pub fn new(text: &'t str) -> Self {
        Self { text, line_starts: OnceCell::new(), resolutions: Cell::new(0), overrides: RefCell::new(HashMap::new()) }
    }

    pub fn text(&self) -> &'t str {
        self.text
    }

    /// The place where the text ends (a truncated file's errors are reported there).
    pub fn end(&self) -> Loc {
        Loc::Offset(self.text.len())
    }

    /// The 1-based line of `loc`.
    pub fn line(&self, loc: Loc) -> u32 {
        self.resolutions.set(self.resolutions.get() + 1);
        match loc {
            Loc::At { line, .. } => line,
            Loc::Offset(offset) => clamp_u32(self.line_index(offset) + 1),
        }
    }

    /// The 1-based line and column (in characters) of `loc`, as roxmltree's
    /// `text_pos_at` gives them.
    pub fn line_col(&self, loc: Loc) -> (u32, u32) {
        self.resolutions.set(self.resolutions.get() + 1);
        match loc {
            Loc::At { line, col } => (line, col),
            Loc::Offset(offset) => {
                let index = self.line_index(offset);
                let start = self.line_starts().get(index).copied().unwrap_or(0);
                let end = offset.min(self.text.len());
                // Offsets come from roxmltree and lie on character boundaries; count bytes
                // should one not.
                let chars = self.text.get(start..end).map_or(end.saturating_sub(start), |s| s.chars().count());
                (clamp_u32(index + 1), clamp_u32(chars + 1))
            }
        }
    }

    /// Record that `-D {name}={value}` was substituted into the text at `loc`.
    pub fn note_override(&self, loc: Loc, given: &str) {
        if let Loc::Offset(offset) = loc {
            let mut map = self.overrides.borrow_mut();
            let list = map.entry(offset).or_default();
            if !list.iter().any(|g| g == given) {
                list.push(given.to_string());
            }
        }
    }

    /// `file`'s error for `fail`: its line and column, and the `-D` overrides that
    /// supplied the value at fault, if any.
    pub fn resolve(&self, fail: Fail) -> (Option<(u32, u32)>, String) {
        let Some(loc) = fail.loc else { return (None, fail.message) };
        let mut message = fail.message;
        if let Loc::Offset(offset) = loc
            && let Some(given) = self.overrides.borrow().get(&offset)
        {
            let list: Vec<String> = given.iter().map(|g| format!("`-D {g}`")).collect();
            message.push_str(&format!(" (the value comes from {} on the command line)", list.join(" and ")));
        }
        (Some(self.line_col(loc)), message)
    }

    /// How many places were resolved so far.
    #[cfg(test)]
    pub fn resolutions(&self) -> usize {
        self.resolutions.get()
    }

    fn line_starts(&self) -> &[usize] {
        self.line_starts.get_or_init(|| std::iter::once(0).chain(self.text.bytes().enumerate().filter(|&(_, b)| b == b'\n').map(|(i, _)| i + 1)).collect())
    }

    /// 0-based index of the line holding byte `offset`.
    fn line_index(&self, offset: usize) -> usize {
        // Line starts are ≤ offset for every line up to and including offset's.
        self.line_starts().partition_point(|&s| s <= offset).saturating_sub(1)
    }
}

fn clamp_u32(v: usize) -> u32 {
    v.min(u32::MAX as usize) as u32
}
