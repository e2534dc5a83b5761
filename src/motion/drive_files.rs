//! The files of a drive iteration's folder: `drive.csv` (the reference to play),
//! `predicted.csv` (the model's response), `metrics.json` and `transfer.csv` (the transfer
//! estimate the next online iteration starts from), and reading them back with a lab's
//! measured run.

use super::drive::{DriveResult, Previous};
use super::metrics::Metrics;
use super::prepare::Target;
use super::read::{numbers, uniform_step};
use super::spectrum::resample;
use super::transfer::Transfer;
use super::MotionError;
use crate::campaign::files::{decode_utf8, lines_any, read_regular};
use crate::params::Params;
use realfft::num_complex::Complex;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

/// Largest drive-folder or measured-run file read (a 10-minute record at 4 kHz as text).
pub const MAX_FILE_BYTES: u64 = 200 << 20;

/// `metrics.json`: the figures (measured for an online iteration, predicted offline),
/// with what produced them.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MetricsFile {
    pub iteration: usize,
    /// `predicted` (offline) or `measured` (the run of the previous drive).
    pub basis: String,
    pub rms_error: f64,
    pub pga_error: f64,
    pub spectral_outside_fraction: f64,
    /// The model's prediction for this folder's drive.
    pub predicted: Metrics,
    /// Offline: the naive drive (the target played as is), predicted.
    pub naive: Option<Metrics>,
    pub trigger_delay_s: Option<f64>,
    pub noise_weighted: bool,
    pub gain: f64,
    pub band_hz: f64,
    pub offline_refinements: usize,
    pub transfer_pairs: usize,
    pub samples: usize,
    pub rate_hz: f64,
}

/// The folder's files as (name, text).
pub fn folder_files(
    r: &DriveResult,
    iteration: usize,
    gain: f64,
    band_hz: f64,
) -> BTreeMap<&'static str, String> {
    let d = &r.drive;
    let n = d.acceleration_m_s2.len();
    let mut drive =
        String::from("time_s,ref_displacement_m,ref_velocity_m_s,ref_acceleration_m_s2\n");
    let mut predicted = String::from("time_s,acceleration_m_s2,displacement_m,force_n\n");
    for k in 0..n {
        let t = k as f64 / d.rate_hz;
        let _ = writeln!(
            drive,
            "{t},{:e},{:e},{:e}",
            d.displacement_m[k], d.velocity_m_s[k], d.acceleration_m_s2[k]
        );
        let o = &r.predicted[k];
        let _ = writeln!(
            predicted,
            "{t},{:e},{:e},{:e}",
            o.acceleration_m_s2, o.displacement_m, o.actuator_force_n
        );
    }
    let (basis, shown) = match r.measured_metrics {
        Some(m) => ("measured", m),
        None => ("predicted", r.predicted_metrics),
    };
    let metrics = MetricsFile {
        iteration,
        basis: basis.into(),
        rms_error: shown.rms_error,
        pga_error: shown.pga_error,
        spectral_outside_fraction: shown.spectral_outside_fraction,
        predicted: r.predicted_metrics,
        naive: r.naive_metrics,
        trigger_delay_s: r.trigger_delay_s,
        noise_weighted: r.noise_weighted,
        gain,
        band_hz,
        offline_refinements: r.refinements,
        transfer_pairs: r.transfer.pairs,
        samples: n,
        rate_hz: d.rate_hz,
    };
    let tr = &r.transfer;
    let mut transfer = String::from("frequency_hz,s_dd,s_da_re,s_da_im,s_aa\n");
    for k in 0..tr.s_dd.len() {
        let f = k as f64 * tr.rate_hz / tr.n as f64;
        let _ = writeln!(
            transfer,
            "{f},{:e},{:e},{:e},{:e}",
            tr.s_dd[k], tr.s_da[k].re, tr.s_da[k].im, tr.s_aa[k]
        );
    }
    let json = serde_json::to_string_pretty(&metrics).unwrap_or_default() + "\n";
    BTreeMap::from([
        ("drive.csv", drive),
        ("predicted.csv", predicted),
        ("metrics.json", json),
        ("transfer.csv", transfer),
    ])
}

fn read_text(path: &Path) -> Result<String, MotionError> {
    let file = path.display().to_string();
    let bytes =
        read_regular(path, MAX_FILE_BYTES, "largest plausible drive file").map_err(|r| {
            MotionError::Read {
                file: file.clone(),
                message: r.to_string(),
            }
        })?;
    decode_utf8(bytes).map_err(|b| MotionError::Read {
        file,
        message: b.to_string(),
    })
}

/// A CSV of numbers with a header: the named columns, and the row line numbers.
fn read_columns(path: &Path, want: &[&str]) -> Result<(Vec<Vec<f64>>, Vec<usize>), MotionError> {
    let file = path.display().to_string();
    let text = read_text(path)?;
    let mut lines = lines_any(&text)
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let (hl, header) = lines.next().ok_or_else(|| MotionError::Read {
        file: file.clone(),
        message: "empty file".into(),
    })?;
    let names: Vec<&str> = header
        .trim_start_matches('\u{feff}')
        .split(',')
        .map(str::trim)
        .collect();
    let mut idx = Vec::new();
    for w in want {
        idx.push(
            names
                .iter()
                .position(|n| n == w)
                .ok_or_else(|| MotionError::Line {
                    file: file.clone(),
                    line: hl + 1,
                    message: format!("no `{w}` column (columns: {})", names.join(", ")),
                })?,
        );
    }
    let mut cols = vec![Vec::new(); want.len()];
    let mut rows = Vec::new();
    for (i, line) in lines {
        let v = numbers(line).ok_or_else(|| MotionError::Line {
            file: file.clone(),
            line: i + 1,
            message: "a value is not a number".into(),
        })?;
        if v.len() != names.len() || v.iter().any(|x| !x.is_finite()) {
            return Err(MotionError::Line {
                file: file.clone(),
                line: i + 1,
                message: format!(
                    "{} values for {} columns, or a value that is not finite",
                    v.len(),
                    names.len()
                ),
            });
        }
        for (c, &j) in cols.iter_mut().zip(&idx) {
            c.push(v[j]);
        }
        rows.push(i + 1);
    }
    Ok((cols, rows))
}

/// The previous iteration's folder, checked against the target (same rate and length).
pub fn read_previous(dir: &Path, p: &Params, target: &Target) -> Result<Previous, MotionError> {
    let metrics_path = dir.join("metrics.json");
    let m: MetricsFile =
        serde_json::from_str(&read_text(&metrics_path)?).map_err(|e| MotionError::Read {
            file: metrics_path.display().to_string(),
            message: format!("not a drive folder's metrics.json: {e}"),
        })?;
    let n = target.acceleration_m_s2.len();
    let mismatch = |what: String| MotionError::Read {
        file: dir.display().to_string(),
        message: what,
    };
    if m.samples != n || (m.rate_hz - target.rate_hz).abs() > 1e-9 * target.rate_hz {
        return Err(mismatch(format!(
            "made for {} samples at {} Hz, the target has {n} at {} Hz: --previous must come from this target",
            m.samples, m.rate_hz, target.rate_hz
        )));
    }
    let (d, _) = read_columns(
        &dir.join("drive.csv"),
        &[
            "ref_displacement_m",
            "ref_velocity_m_s",
            "ref_acceleration_m_s2",
        ],
    )?;
    if d[0].len() != n {
        return Err(mismatch(format!(
            "drive.csv has {} rows, metrics.json says {n}",
            d[0].len()
        )));
    }
    let (t, _) = read_columns(
        &dir.join("transfer.csv"),
        &["s_dd", "s_da_re", "s_da_im", "s_aa"],
    )?;
    let mut transfer = Transfer::from_model(p, n, target.rate_hz);
    if t[0].len() != transfer.s_dd.len() {
        return Err(mismatch(format!(
            "transfer.csv has {} rows, expected {}",
            t[0].len(),
            transfer.s_dd.len()
        )));
    }
    transfer.s_dd = t[0].clone();
    transfer.s_da = t[1]
        .iter()
        .zip(&t[2])
        .map(|(re, im)| Complex::new(*re, *im))
        .collect();
    transfer.s_aa = t[3].clone();
    transfer.pairs = m.transfer_pairs;
    let mut it = d.into_iter();
    let (x, v, a) = (
        it.next().unwrap_or_default(),
        it.next().unwrap_or_default(),
        it.next().unwrap_or_default(),
    );
    Ok(Previous {
        drive: Target {
            rate_hz: target.rate_hz,
            displacement_m: x,
            velocity_m_s: v,
            acceleration_m_s2: a,
        },
        transfer,
        iteration: m.iteration,
    })
}

/// The table acceleration a lab measured (`time_s`, `acceleration_m_s2`), at `rate_hz`
/// (resampled if recorded at another rate), `n` samples (cut or zero-filled at the end).
pub fn read_measured(path: &Path, rate_hz: f64, n: usize) -> Result<Vec<f64>, MotionError> {
    let file = path.display().to_string();
    let (cols, rows) = read_columns(path, &["time_s", "acceleration_m_s2"])?;
    let times: Vec<(usize, f64)> = rows.iter().copied().zip(cols[0].iter().copied()).collect();
    if times.len() < 16 {
        return Err(MotionError::Read {
            file,
            message: format!("{} samples: too short", times.len()),
        });
    }
    let step = uniform_step(&times, &file, None)?;
    let rate = 1.0 / step;
    let mut a = if ((rate - rate_hz) / rate_hz).abs() < 1e-6 {
        cols[1].clone()
    } else {
        resample(&cols[1], rate, rate_hz).map_err(|m| MotionError::Read {
            file: file.clone(),
            message: m,
        })?
    };
    a.resize(n, 0.0);
    Ok(a)
}
