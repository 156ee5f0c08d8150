//! Bounded reads of input files: scenes, meshes, textures, models and parts.
//!
//! `std::fs::read` on `/dev/zero`, a FIFO or a file that keeps growing reads until memory
//! runs out. Every input the program reads goes through [`read_bounded`] (or
//! [`open_regular`] for streaming readers): a path that is not a regular file is refused
//! by name, and a read never takes more than the file's size when it was opened nor more
//! than a stated limit, so a hostile input costs at most that limit.

use std::fs::File;
use std::io::Read;
use std::path::Path;

/// The most any one input file may hold: 64 GiB (a 2 M-triangle PLY is about 50 MB; a
/// file beyond this is refused before it is read).
pub const MAX_INPUT_BYTES: u64 = 64 << 30;

/// Open `path` for reading if it is a regular file (after symbolic links), with its size.
/// A directory, device (`/dev/zero`), FIFO or socket is refused, naming what it is.
pub fn open_regular(path: &Path) -> Result<(File, u64), String> {
    // The type is checked before opening: opening a FIFO for reading blocks until a
    // writer appears. Checked again on the open file, which may have been replaced.
    let check = |meta: std::fs::Metadata| {
        let ft = meta.file_type();
        if ft.is_file() {
            Ok(meta.len())
        } else {
            let what = if ft.is_dir() { "a directory" } else { "not a regular file (a device, FIFO or socket)" };
            Err(format!("is {what}: only regular files are read"))
        }
    };
    check(std::fs::metadata(path).map_err(|e| e.to_string())?)?;
    let file = File::open(path).map_err(|e| e.to_string())?;
    let len = check(file.metadata().map_err(|e| e.to_string())?)?;
    Ok((file, len))
}

/// The bytes of the regular file `path`, refused if it holds more than `limit` bytes.
/// Reads at most the size the file had when opened (plus one byte, to notice growth), so
/// a file that grows while it is read is refused instead of read without end.
pub fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let (file, len) = open_regular(path)?;
    if len > limit {
        return Err(format!("holds {len} bytes, more than the {limit} this input may have"));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(len + 1).read_to_end(&mut bytes).map_err(|e| e.to_string())?;
    if bytes.len() as u64 > len {
        return Err("grew while it was read".into());
    }
    Ok(bytes)
}

/// [`read_bounded`] as UTF-8 text.
pub fn read_text_bounded(path: &Path, limit: u64) -> Result<String, String> {
    String::from_utf8(read_bounded(path, limit)?).map_err(|e| format!("is not UTF-8 text (byte {})", e.utf8_error().valid_up_to()))
}

/// Do two paths name the same file (the same path, or the same existing file by any path)?
pub fn same_file(a: &Path, b: &Path) -> bool {
    a == b || matches!((std::fs::canonicalize(a), std::fs::canonicalize(b)), (Ok(x), Ok(y)) if x == y)
}

/// Try `path` as an output before any work (issue 50: an unwritable `-o` failed after
/// the whole render): refuse, naming the reason, a path that is a directory, exists as
/// something other than a regular file (`/dev/full`), is one of `inputs` (the same file,
/// by any path), or lies in a missing or unwritable directory; the last is found by
/// creating and removing an empty file beside it.
pub fn probe_output(path: &Path, inputs: &[&Path]) -> Result<(), String> {
    let name = path.display();
    if let Ok(meta) = std::fs::metadata(path) {
        if meta.is_dir() {
            return Err(format!("output '{name}' is a directory: name a file in it"));
        }
        if !meta.is_file() {
            return Err(format!("output '{name}' is not a regular file (a device, FIFO or socket): nothing is written there"));
        }
        if let Some(input) = inputs.iter().find(|i| same_file(path, i)) {
            return Err(format!("output '{name}' is one of the inputs ({}): it would be overwritten", input.display()));
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(format!("output directory '{}' does not exist", dir.display()));
    }
    let file = path.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
    let probe = dir.join(format!(".{file}.ember-probe-{}", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(format!("cannot write output '{name}': {e} (in '{}')", dir.display())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Injected bug checked: with `open_regular`'s file-type test removed, reading
    /// `/dev/zero` with a 1 KiB limit passes the size test (its length is 0) and the
    /// `take` returns one byte, so the "grew" error appears instead of "regular file".
    #[test]
    fn devices_directories_and_oversized_files_are_refused() {
        let zero = read_bounded(Path::new("/dev/zero"), 1 << 10).unwrap_err();
        assert!(zero.contains("regular file"), "{zero}");
        // A FIFO is refused without blocking on its open.
        let fifo = std::env::temp_dir().join(format!("ember-files-fifo-{}", std::process::id()));
        let _ = std::fs::remove_file(&fifo);
        if std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
            assert!(read_bounded(&fifo, 1 << 10).unwrap_err().contains("FIFO"));
            let _ = std::fs::remove_file(&fifo);
        }
        let dir = read_bounded(Path::new("/"), 1 << 10).unwrap_err();
        assert!(dir.contains("directory"), "{dir}");
        let path = std::env::temp_dir().join(format!("ember-files-{}.txt", std::process::id()));
        std::fs::write(&path, b"hello").unwrap();
        assert_eq!(read_bounded(&path, 5).unwrap(), b"hello");
        assert!(read_bounded(&path, 4).unwrap_err().contains("more than the 4"));
        assert_eq!(read_text_bounded(&path, 16).unwrap(), "hello");
        let _ = std::fs::remove_file(&path);
    }

    /// Injected bug checked: without the directory test, the first assertion gets a
    /// probe that succeeds (the probe file lands beside the directory).
    #[test]
    fn outputs_are_tried_before_the_work() {
        let dir = std::env::temp_dir().join(format!("ember-probe-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        assert!(probe_output(&dir, &[]).unwrap_err().contains("is a directory"));
        assert!(probe_output(Path::new("/dev/full"), &[]).unwrap_err().contains("not a regular file"));
        assert!(probe_output(&dir.join("missing/x.exr"), &[]).unwrap_err().contains("does not exist"));
        let input = dir.join("scene.xml");
        std::fs::write(&input, "x").unwrap();
        let via = dir.join(".").join("scene.xml");
        assert!(probe_output(&via, &[&input]).unwrap_err().contains("is one of the inputs"));
        assert_eq!(probe_output(&dir.join("out.exr"), &[&input]), Ok(()));
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "the probe file is removed");
        if std::path::Path::new("/proc/self").is_dir() {
            assert!(probe_output(Path::new("/proc/nope.exr"), &[]).is_err());
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
