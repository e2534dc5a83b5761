//! MATLAB level-5 `.mat` files, as MATLAB (`-v6`, `-v7`), dSPACE ControlDesk and most DAQ
//! software write them (campaign format, "MATLAB files").
//!
//! Written by hand rather than taken from crates.io: `matfile` reads numeric arrays only
//! (no structs, cells or chars, so no dSPACE recordings); `matio-rs` wraps the C library
//! matio (libmatio, cmake, HDF5); `matrw` reads structs and cells in pure Rust but unwraps
//! inside its zlib path (a corrupt compressed variable panics) and inflates without a
//! bound. A recording comes from outside the project, so this reader must refuse every
//! malformed byte with an error naming the file, the variable and the offset, never panic,
//! never allocate more than the file's size justifies, and never loop: about a thousand
//! lines of our own against the MathWorks "MAT-File Format" document do that. They are
//! checked against files MATLAB itself wrote (big-endian 6.1, compressed 7.4) and against
//! `scipy.io.savemat`, whose leniencies they share (dimensions stored as miUINT32, names
//! as miUTF8) except one: a compressed variable whose zlib checksum fails is refused.
//!
//! Refused with a clear message: v7.3 (HDF5) and level-4 files, and, when a `column`
//! addresses them, sparse, complex, object and function-handle variables (a complex
//! column is refused rather than silently reduced to its real part).
//!
//! [`read_mat`] parses the bytes into [`MatFile`]; [`MatFile::signal`] resolves a
//! campaign `column` (see `signal.rs`); [`MatFile::signals`] lists what a file holds;
//! [`MatFile::value_at`] reaches any struct field (`rec.Y(2).Unit`).

mod arrays;
mod dspace;
mod header;
mod parse;
mod signal;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_hostile;

pub use signal::{SignalInfo, SignalKind};

/// Most bytes all compressed variables of one file may inflate to: 2 GiB holds an hour of
/// 64 channels at 1 kHz in doubles (1.8 GB), far beyond a shake-table test, and stops a
/// zlib bomb (about 1000:1) before it exhausts memory.
pub const MAX_INFLATED_BYTES: usize = 2 << 30;

/// One MATLAB value. Numeric classes (double, single, int8 ... uint64, logical) become
/// `f64` (int64 beyond 2^53 rounds); arrays are column-major as in MATLAB.
#[derive(Debug, Clone, PartialEq)]
pub enum MatValue {
    Numeric {
        dims: Vec<usize>,
        data: Vec<f64>,
    },
    /// A char array; the rows of a multi-row char matrix are joined by `\n`.
    Char(String),
    /// `elements[e][f]` is field `fields[f]` of element `e` (column-major over `dims`).
    Struct {
        dims: Vec<usize>,
        fields: Vec<String>,
        elements: Vec<Vec<MatValue>>,
    },
    Cell {
        dims: Vec<usize>,
        elements: Vec<MatValue>,
    },
    /// A value this reader does not convert, named for messages ("sparse matrix", ...).
    Unsupported(String),
}

impl MatValue {
    /// Field `name` of a 1x1 struct.
    pub fn field(&self, name: &str) -> Option<&MatValue> {
        match self {
            MatValue::Struct {
                fields, elements, ..
            } if elements.len() == 1 => {
                let f = fields.iter().position(|n| n == name)?;
                elements[0].get(f)
            }
            _ => None,
        }
    }

    /// The text of a char value.
    pub fn text(&self) -> Option<&str> {
        match self {
            MatValue::Char(s) => Some(s),
            _ => None,
        }
    }

    /// What the value is, for messages: "50x3 double", "1x3 struct", "char", ...
    pub fn describe(&self) -> String {
        let size = |d: &[usize]| {
            d.iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join("x")
        };
        match self {
            MatValue::Numeric { dims, .. } => format!("{} numeric array", size(dims)),
            MatValue::Char(_) => "char array".into(),
            MatValue::Struct { dims, .. } => format!("{} struct", size(dims)),
            MatValue::Cell { dims, .. } => format!("{} cell array", size(dims)),
            MatValue::Unsupported(kind) => kind.clone(),
        }
    }
}

/// The variables of one level-5 file, in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct MatFile {
    /// The file's name as given to [`read_mat`], for messages.
    pub file: String,
    pub variables: Vec<(String, MatValue)>,
}

impl MatFile {
    /// The top-level variable `name`.
    pub fn variable(&self, name: &str) -> Option<&MatValue> {
        self.variables
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum MatError {
    #[error("{file}: MATLAB v7.3 (HDF5) MAT-files are not supported; save with -v7 or -v6")]
    V73 { file: String },
    #[error("{file}: level 4 MAT files are not supported; save with -v7 or -v6")]
    Level4 { file: String },
    #[error("{file}: not a MATLAB level-5 MAT-file: {why}")]
    NotMat { file: String, why: String },
    /// Bad bytes: `at` is "byte N" or "byte N of the compressed variable at byte M".
    #[error("{file}: {context}{at}: {why}")]
    Malformed {
        file: String,
        context: String,
        at: String,
        why: String,
    },
    #[error("{file}: no variable or signal `{column}`; the file holds: {available}")]
    UnknownColumn {
        file: String,
        column: String,
        available: String,
    },
    #[error(
        "{file}: `{column}` names {count} dSPACE signals; give its block path, one of: {paths}"
    )]
    Ambiguous {
        file: String,
        column: String,
        count: usize,
        paths: String,
    },
    #[error("{file}: `{column}`: {why}")]
    NotASignal {
        file: String,
        column: String,
        why: String,
    },
}

/// Parse a level-5 MAT-file held in `bytes`; `file` names it in every error.
pub fn read_mat(bytes: &[u8], file: &str) -> Result<MatFile, MatError> {
    read_mat_bounded(bytes, file, MAX_INFLATED_BYTES)
}

/// [`read_mat`] with the inflated-bytes budget as a parameter (tests use a small one).
pub(crate) fn read_mat_bounded(
    bytes: &[u8],
    file: &str,
    max_inflated: usize,
) -> Result<MatFile, MatError> {
    let big_endian = header::check_header(bytes, file)?;
    let mut parser = parse::Parser::new(file, big_endian, max_inflated);
    let variables = parser.variables(bytes)?;
    Ok(MatFile {
        file: file.to_string(),
        variables,
    })
}
