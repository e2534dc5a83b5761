//! Target motions for the table (issue 19): a ground motion read as laboratories get it
//! ([`read`]: PEER NGA `.AT2`, one or two columns, a campaign CSV channel), prepared as a
//! table target ([`prepare`]: resampled, high-passed, at rest at both ends, scaled to a
//! PGA) and checked against the table's envelope with its specimen ([`envelope`]).

pub mod at2;
pub mod drive;
pub mod drive_files;
pub mod envelope;
pub mod figures;
pub mod metrics;
pub mod prepare;
pub mod read;
pub(crate) mod spectrum;
pub mod target_file;
pub mod transfer;
pub mod tune;

/// Standard gravity, m/s^2 (the `g` of records in units of g).
pub const STANDARD_GRAVITY_M_S2: f64 = 9.80665;

/// Why a motion could not be read or prepared; every message names the file and line,
/// or the option.
#[derive(Debug, thiserror::Error)]
pub enum MotionError {
    #[error("{file}: {message}")]
    Read { file: String, message: String },
    #[error("{file}:{line}: {message}")]
    Line {
        file: String,
        line: usize,
        message: String,
    },
    #[error("{option}: {message}")]
    Option { option: String, message: String },
}
