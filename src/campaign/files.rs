//! Opening campaign files safely: the one place where the reader touches the disk.
//!
//! Only regular files are read (a FIFO, a socket, a device such as `/dev/zero` or a
//! directory is refused from its metadata, before it is opened, so nothing blocks or reads
//! without end); their size is checked before reading and the read itself is bounded;
//! a test file must lie inside the campaign folder (checked lexically before any access,
//! then again after resolving symlinks). Text is decoded as UTF-8 with the line and column
//! of the first invalid byte, and a line ends at `\n`, `\r\n` or a lone `\r` (classic Mac).

use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Component, Path, PathBuf};

/// Largest record file read, in bytes (1 GiB). The longest plausible test is an hour
/// (the paper's longest, a 0.05 Hz triangle, is minutes); at 1 kHz with 12 channels of
/// 24-character numbers an hour is 3600 * 1000 * 12 * 24 = 1.04e9 bytes. A larger file is
/// not a record of one test (or is `/dev/zero`-like), and reading it would take several
/// times its size in memory (text plus parsed columns), so it is refused before reading.
pub const MAX_RECORD_BYTES: u64 = 1 << 30;

/// Largest campaign.toml read, in bytes (16 MiB). A test entry is a few hundred bytes,
/// so this holds tens of thousands of tests with their comments: far beyond any test
/// programme, small enough to parse with spans in memory at once.
pub const MAX_TOML_BYTES: u64 = 16 << 20;

/// Why a file was not read. Displays without the path: the caller names file and test.
#[derive(Debug)]
pub enum Refusal {
    /// The OS refused (missing file, no permission, symlink loop, ...).
    Io(std::io::Error),
    /// Not a regular file: what it is ("a FIFO (named pipe)", "a directory", ...).
    NotRegular(&'static str),
    /// Larger than `limit` bytes: `size` from its metadata, or `None` when it grew past
    /// the limit while being read.
    TooLarge {
        size: Option<u64>,
        limit: u64,
        what: &'static str,
    },
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::Io(e) => write!(f, "cannot read: {e}"),
            Refusal::NotRegular(kind) => write!(
                f,
                "is {kind}, not a regular file: only regular files are read (refused before opening)"
            ),
            Refusal::TooLarge { size, limit, what } => {
                let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
                match size {
                    Some(s) => write!(f, "is {s} bytes ({:.2} GiB), ", gib(*s))?,
                    None => write!(f, "grew while being read and is ")?,
                }
                write!(
                    f,
                    "larger than the {what} ({limit} bytes, {:.3} GiB); refused before reading",
                    gib(*limit)
                )
            }
        }
    }
}

/// What a non-regular file type is, in words.
fn kind_of(t: &std::fs::FileType) -> &'static str {
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_socket() {
        "a socket"
    } else if t.is_char_device() {
        "a character device (like /dev/zero)"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_symlink() {
        "a symbolic link"
    } else {
        "a special file"
    }
}

/// Refuse anything but a regular file of at most `limit` bytes.
fn check_meta(m: &std::fs::Metadata, limit: u64, what: &'static str) -> Result<(), Refusal> {
    if !m.file_type().is_file() {
        return Err(Refusal::NotRegular(kind_of(&m.file_type())));
    }
    if m.len() > limit {
        return Err(Refusal::TooLarge {
            size: Some(m.len()),
            limit,
            what,
        });
    }
    Ok(())
}

/// The bytes of a regular file of at most `limit` bytes (`what` names the limit in
/// errors). Type and size are checked from metadata before opening; the file is opened
/// non-blocking without following a last symlink (so a file swapped for a FIFO after the
/// check cannot block), checked again on the handle, and read through `take(limit + 1)`.
pub fn read_regular(path: &Path, limit: u64, what: &'static str) -> Result<Vec<u8>, Refusal> {
    let real = path.canonicalize().map_err(Refusal::Io)?;
    check_meta(&std::fs::metadata(&real).map_err(Refusal::Io)?, limit, what)?;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOFOLLOW)
        .open(&real)
        .map_err(Refusal::Io)?;
    let meta = file.metadata().map_err(Refusal::Io)?;
    check_meta(&meta, limit, what)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(Refusal::Io)?;
    if bytes.len() as u64 > limit {
        return Err(Refusal::TooLarge {
            size: None,
            limit,
            what,
        });
    }
    Ok(bytes)
}

/// The first `max_bytes` of a regular file (any size): the same checks as
/// [`read_regular`], for looking into a file without reading all of it.
pub fn read_head(path: &Path, max_bytes: u64) -> Result<Vec<u8>, Refusal> {
    let real = path.canonicalize().map_err(Refusal::Io)?;
    check_meta(
        &std::fs::metadata(&real).map_err(Refusal::Io)?,
        u64::MAX,
        "",
    )?;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOFOLLOW)
        .open(&real)
        .map_err(Refusal::Io)?;
    check_meta(&file.metadata().map_err(Refusal::Io)?, u64::MAX, "")?;
    let mut bytes = Vec::new();
    file.take(max_bytes)
        .read_to_end(&mut bytes)
        .map_err(Refusal::Io)?;
    Ok(bytes)
}

/// `file` relative to the campaign folder with `.` and `..` resolved lexically, or `None`
/// when it is absolute or climbs out of the folder. Used before any file system access,
/// and to compare test files (`./R1.csv` is `R1.csv`).
pub fn normalise_relative(file: &str) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    for c in Path::new(file).components() {
        match c {
            Component::Normal(s) => out.push(s),
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            Component::RootDir | Component::Prefix(_) => return None,
        }
    }
    Some(out)
}

/// `dir/file` with symlinks resolved, if it lies inside the (canonical) folder `root`;
/// `Err(Some(resolved))` when it resolves outside, `Err(None)` with the OS error kept by
/// the caller's later read when it cannot be resolved.
pub fn resolve_inside(root: &Path, dir: &Path, file: &str) -> Result<PathBuf, Option<PathBuf>> {
    let real = dir.join(file).canonicalize().map_err(|_| None)?;
    if real.starts_with(root) && real != root {
        Ok(real)
    } else {
        Err(Some(real))
    }
}

/// Where a line starts: after `\n`, after `\r\n`, or after a lone `\r`.
fn is_line_end(bytes: &[u8], i: usize) -> bool {
    bytes[i] == b'\n' || (bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n'))
}

/// The first invalid UTF-8 byte of a text: its 1-based line and character column, the
/// 1-based comma-separated cell it falls in, and the byte.
#[derive(Debug, Clone, Copy)]
pub struct BadByte {
    pub line: usize,
    pub column: usize,
    pub cell: usize,
    pub byte: u8,
}

impl std::fmt::Display for BadByte {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "not UTF-8 text: invalid byte 0x{:02X} at column {} (cell {}); \
             save the file as UTF-8 (ASCII is UTF-8)",
            self.byte, self.column, self.cell
        )
    }
}

/// Decode UTF-8, locating the first invalid byte.
pub fn decode_utf8(bytes: Vec<u8>) -> Result<String, BadByte> {
    match String::from_utf8(bytes) {
        Ok(s) => Ok(s),
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let bytes = e.into_bytes();
            let line = 1 + (0..at).filter(|&i| is_line_end(&bytes, i)).count();
            let start = (0..at)
                .rev()
                .find(|&i| is_line_end(&bytes, i))
                .map_or(0, |i| i + 1);
            // valid up to `at`, so this slice is UTF-8
            let head = std::str::from_utf8(&bytes[start..at]).unwrap_or("");
            let head = head.strip_prefix('\u{feff}').unwrap_or(head);
            Err(BadByte {
                line,
                column: head.chars().count() + 1,
                cell: head.matches(',').count() + 1,
                byte: bytes[at],
            })
        }
    }
}

/// The lines of a text, each without its ending (`\n`, `\r\n` or a lone `\r`); a text
/// ending with a line end yields a last empty line, like `str::split('\n')`.
pub fn lines_any(text: &str) -> impl Iterator<Item = &str> {
    let mut rest = Some(text);
    std::iter::from_fn(move || {
        let s = rest?;
        match s.bytes().position(|b| b == b'\n' || b == b'\r') {
            None => {
                rest = None;
                Some(s)
            }
            Some(i) => {
                let skip = if s[i..].starts_with("\r\n") { 2 } else { 1 };
                rest = Some(&s[i + skip..]);
                Some(&s[..i])
            }
        }
    })
}

/// `text` with every lone `\r` (classic Mac line end) turned into `\n`; byte offsets and
/// line numbers are unchanged.
pub fn lone_cr_to_lf(text: &str) -> std::borrow::Cow<'_, str> {
    let b = text.as_bytes();
    if !(0..b.len()).any(|i| b[i] == b'\r' && is_line_end(b, i)) {
        return std::borrow::Cow::Borrowed(text);
    }
    let out: Vec<u8> = (0..b.len())
        .map(|i| {
            if b[i] == b'\r' && is_line_end(b, i) {
                b'\n'
            } else {
                b[i]
            }
        })
        .collect();
    // only ASCII bytes were replaced by ASCII bytes
    std::borrow::Cow::Owned(String::from_utf8(out).unwrap_or_else(|_| text.to_string()))
}
