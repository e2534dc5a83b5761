//! Target files: `time_s, acceleration_m_s2` (and the velocity and displacement
//! `record import` writes beside them), uniform in time.

use super::prepare::Target;
use super::read::{numbers, uniform_step, MIN_SAMPLES};
use super::MotionError;
use crate::campaign::files::{decode_utf8, lines_any, read_regular};
use std::fmt::Write;
use std::path::Path;

/// Largest target file read: a 10-minute record at 4 kHz as text is about 100 MB.
pub const MAX_TARGET_BYTES: u64 = 200 << 20;

/// The header `record import` writes.
pub const HEADER: &str = "time_s,acceleration_m_s2,velocity_m_s,displacement_m";

/// A target as CSV text.
pub fn to_csv(t: &Target) -> String {
    let mut s = String::with_capacity(t.acceleration_m_s2.len() * 80);
    s.push_str(HEADER);
    s.push('\n');
    for k in 0..t.acceleration_m_s2.len() {
        let _ = writeln!(
            s,
            "{},{:e},{:e},{:e}",
            k as f64 / t.rate_hz,
            t.acceleration_m_s2[k],
            t.velocity_m_s[k],
            t.displacement_m[k]
        );
    }
    s
}

/// A target read from `path`: its `time_s` (uniform, rounding allowed) and
/// `acceleration_m_s2` columns; the velocity and displacement are the acceleration
/// integrated from rest (trapezoid), as the table that follows it would move.
pub fn read_target(path: &Path) -> Result<Target, MotionError> {
    let file = path.display().to_string();
    let err = |message: String| MotionError::Read {
        file: file.clone(),
        message,
    };
    let err_at = |line: usize, message: String| MotionError::Line {
        file: file.clone(),
        line,
        message,
    };
    let bytes = read_regular(path, MAX_TARGET_BYTES, "largest plausible target")
        .map_err(|r| err(r.to_string()))?;
    let text = decode_utf8(bytes).map_err(|b| err(b.to_string()))?;
    let mut lines = lines_any(&text)
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines.next().ok_or_else(|| err("empty file".into()))?;
    let names: Vec<&str> = header
        .trim_start_matches('\u{feff}')
        .split(',')
        .map(str::trim)
        .collect();
    let col = |want: &str| {
        names.iter().position(|n| *n == want).ok_or_else(|| {
            err_at(
                1,
                format!("no `{want}` column (columns: {})", names.join(", ")),
            )
        })
    };
    let (tc, ac) = (col("time_s")?, col("acceleration_m_s2")?);
    let mut times = Vec::new();
    let mut acceleration = Vec::new();
    for (i, line) in lines {
        let row = numbers(line).ok_or_else(|| err_at(i + 1, "a value is not a number".into()))?;
        if row.len() != names.len() {
            return Err(err_at(
                i + 1,
                format!("{} values for {} columns", row.len(), names.len()),
            ));
        }
        if !row[ac].is_finite() {
            return Err(err_at(i + 1, "acceleration_m_s2 is not finite".into()));
        }
        times.push((i + 1, row[tc]));
        acceleration.push(row[ac]);
    }
    if acceleration.len() < MIN_SAMPLES {
        return Err(err(format!(
            "{} samples: a target needs at least {MIN_SAMPLES}",
            acceleration.len()
        )));
    }
    let step = uniform_step(&times, &file, None)?;
    Ok(from_acceleration(acceleration, 1.0 / step))
}

/// A target from its acceleration, integrated from rest by the trapezoid rule.
pub fn from_acceleration(acceleration_m_s2: Vec<f64>, rate_hz: f64) -> Target {
    let dt = 1.0 / rate_hz;
    let integrate = |x: &[f64]| {
        let mut out = Vec::with_capacity(x.len());
        let mut sum = 0.0;
        out.push(0.0);
        for k in 1..x.len() {
            sum += 0.5 * dt * (x[k - 1] + x[k]);
            out.push(sum);
        }
        out
    };
    let velocity_m_s = integrate(&acceleration_m_s2);
    let displacement_m = integrate(&velocity_m_s);
    Target {
        rate_hz,
        acceleration_m_s2,
        velocity_m_s,
        displacement_m,
    }
}
