//! Bounds of the numeric options that size memory or run time (issue 14, item 3): a value
//! beyond them is refused with the option, the value and the limit, instead of aborting
//! on allocation or running for days.

use std::fmt::Display;

/// Most frequencies of `frf` (a log grid of 100 000 points is far finer than any plot or
/// CSV reader needs; each point is a few small complex solves, 4 CSV columns).
pub const MAX_FRF_POINTS: usize = 100_000;
/// Highest sample rate `simulate` accepts, Hz: 200x the lab's 512 Hz; the solver takes
/// at least one sub-step per sample, so higher rates only multiply the run time.
pub const MAX_SAMPLE_RATE_HZ: f64 = 100_000.0;
/// Longest `bench --seconds`: one hour of table time per workload.
pub const MAX_BENCH_SECONDS: f64 = 3600.0;
/// Most `bench --repeats` (the best of a few runs is already stable).
pub const MAX_BENCH_REPEATS: usize = 100;

pub use shaketable::campaign::synth::{MAX_RANDOM_DURATION_S, MIN_SUBSTEP_S};

/// `value` of `option` must lie in `[min, max]` (named limits in the message).
pub fn within<T: PartialOrd + Display>(
    option: &str,
    value: T,
    min: T,
    max: T,
    limits: &str,
) -> anyhow::Result<()> {
    // written so that NaN fails too
    if value >= min && value <= max {
        return Ok(());
    }
    anyhow::bail!("{option} {value}: must be between {min} and {max} ({limits})")
}

/// `value` of `option` must be at least `min` (NaN fails).
pub fn at_least<T: PartialOrd + Display>(
    option: &str,
    value: T,
    min: T,
    limit: &str,
) -> anyhow::Result<()> {
    if value >= min {
        return Ok(());
    }
    anyhow::bail!("{option} {value}: must be at least {min} ({limit})")
}
