//! The identification's summary: every estimate with its uncertainty (against the truth
//! when a parameter file gives it), the closed loop's fitted parameters, and what could
//! not be identified with the reason. Rows are read from the typed results
//! ([`Identification::estimates`], [`crate::identify::greybox::FreeEstimate`]).

use super::page::{Section, Table};
use crate::identify::{Identification, Quantity};
use crate::linear::{Linearisation, OilColumn};
use crate::params::{Params, ServovalveModel};
use std::fmt::Write as _;

/// One line of the summary table.
#[derive(Debug, Clone)]
pub struct Row {
    pub key: String,
    /// `None`: not identified (`null` in the JSON; the reason is in `missing`).
    pub value: Option<f64>,
    pub sigma: Option<f64>,
    pub truth: Option<f64>,
}

impl Row {
    /// Relative error against the truth, percent (absolute value when the truth is 0).
    pub fn error(&self) -> Option<f64> {
        let (v, t) = (self.value?, self.truth?);
        match (v.is_finite(), t == 0.0) {
            (false, _) => None,
            (true, true) => Some(v),
            (true, false) => Some(100.0 * (v / t - 1.0)),
        }
    }

    /// The error as shown: percent, or absolute against a zero truth.
    fn error_text(&self) -> String {
        match (self.error(), self.truth) {
            (Some(e), Some(0.0)) => format!("{} abs", fmt(e)),
            (Some(e), _) => format!("{e:+.2} %"),
            _ => String::new(),
        }
    }
}

/// How the truth of an estimate reads off the true parameters (`None`: no such truth).
type Truth = fn(&Params) -> Option<f64>;

fn second_order(p: &Params) -> bool {
    p.servovalve.model == ServovalveModel::SecondOrder
}

/// Whether the summary shows estimates of `q` and how their truth reads: `None` for what
/// it leaves out (figures of the validation the report shows elsewhere, the leakage the
/// oil column's damping carries), a truth of `None` where no parameter is the truth (a
/// device is no parameter of the table). Every quantity is named: a new one must be
/// placed here.
fn shown(q: Quantity) -> Option<Truth> {
    use Quantity::*;
    let truth: Truth = match q {
        ServovalveGain => |p| Some(p.servovalve.gain),
        ServovalveTimeConstant => |p| (!second_order(p)).then_some(p.servovalve.time_constant_s),
        ServovalveNaturalFrequency => {
            |p| second_order(p).then_some(p.servovalve.natural_frequency_hz)
        }
        ServovalveDampingRatio => |p| second_order(p).then_some(p.servovalve.damping_ratio),
        Mass | MassRandom | MassPeriodic => |p| Some(p.table.mass_kg),
        Stiffness => |p| Some(p.table.stiffness_n_m),
        OilColumnFrequency => |p| Some(OilColumn::of(p).frequency_hz),
        OilColumnDampingRatio => |p| Some(OilColumn::of(p).damping_ratio),
        BulkModulus => |p| Some(p.actuator.bulk_modulus_pa),
        FrictionForce => |p| Some(p.friction.force_n),
        FrictionYieldDisplacement => |p| Some(p.friction.yield_displacement_m),
        FrictionShape => |p| Some(p.friction.shape),
        TableTfError => |_| None,
        PeakHz => bare_table_peak_hz,
        TableTfErrorNonlinear | MeasuredPeakHz | Leakage => return None,
        DeviceForce
        | DeviceYieldDisplacement
        | DeviceShape
        | DeviceViscous
        | DeviceStiffness
        | DeviceMass
        | DeviceOffset
        | DeviceNrmse
        | DeviceFitPercent => |_| None,
    };
    Some(truth)
}

/// The peak of the bare table's transfer function (the validation's truth: the
/// identification models the table without specimen or foundation).
fn bare_table_peak_hz(p: &Params) -> Option<f64> {
    let mut q = *p;
    q.specimen.enabled = false;
    q.foundation.enabled = false;
    Linearisation::new(&q).table_tf_figures().map(|f| f.peak_hz)
}

/// The summary's rows: section 4's estimates, the device's when a test recorded
/// displacement and force, and the closed loop's fitted parameters (prefixed
/// `closed_loop:`), each with the truth where `truth` gives it.
pub fn summary_rows(id: &Identification, truth: Option<&Params>) -> Vec<Row> {
    let mut rows: Vec<Row> = id
        .estimates()
        .into_iter()
        // the device's only when a device was fitted
        .filter(|e| id.device.is_some() || !e.quantity.is_device())
        .filter_map(|e| {
            let t = shown(e.quantity)?;
            Some(Row {
                key: e.key().to_string(),
                value: e.value.filter(|v| v.is_finite()),
                sigma: e.sigma.filter(|s| s.is_finite()),
                truth: truth.and_then(t),
            })
        })
        .collect();
    if let Some(cl) = &id.closed_loop {
        rows.extend(cl.estimates.iter().map(|e| Row {
            key: format!("closed_loop: {}", e.key),
            value: Some(e.value),
            sigma: e.sigma,
            truth: truth.map(|p| e.parameter.get(p)),
        }));
    }
    rows
}

pub(super) fn fmt(x: f64) -> String {
    if !x.is_finite() {
        "-".into()
    } else if x == 0.0 {
        "0".into()
    } else if x.abs() >= 1e5 || x.abs() < 1e-2 {
        format!("{x:.4e}")
    } else {
        format!("{x:.4}")
    }
}

/// A value as shown: the number, or "null" for an estimate that could not be made.
fn value_text(v: Option<f64>) -> String {
    v.map_or("null".into(), fmt)
}

/// The summary as a fixed-width text table.
pub fn text_table(rows: &[Row], with_truth: bool) -> String {
    let mut s = String::new();
    let last = if with_truth { "truth" } else { "+- 1 sigma" };
    let _ = write!(s, "  {:40} {:>14} {:>14}", "estimate", "identified", last);
    s.push_str(if with_truth { "      error\n" } else { "\n" });
    for r in rows {
        let (third, fourth) = match with_truth {
            true => (r.truth.map(fmt).unwrap_or_default(), r.error_text()),
            false => (r.sigma.map(fmt).unwrap_or_default(), String::new()),
        };
        let line = format!(
            "  {:40} {:>14} {:>14} {:>10}",
            r.key,
            value_text(r.value),
            third,
            fourth
        );
        let _ = writeln!(s, "{}", line.trim_end());
    }
    s
}

/// The report's summary section: the table, then what could not be identified and the
/// parameter-file keys that hold a default or a convention, with why.
pub fn section(id: &Identification, rows: &[Row], with_truth: bool) -> Vec<Section> {
    let mut header = vec!["estimate", "identified", "+- 1 sigma"];
    if with_truth {
        header.extend(["truth", "error"]);
    }
    let mut t = Table::new(&header);
    for r in rows {
        let mut cells = vec![
            r.key.clone(),
            value_text(r.value),
            r.sigma.map(fmt).unwrap_or_default(),
        ];
        if with_truth {
            cells.extend([r.truth.map(fmt).unwrap_or_default(), r.error_text()]);
        }
        t.push(cells);
    }
    let identified = Section::tables(
        "What was identified",
        "Each estimate with its one-sigma uncertainty (null: not identified, see below); the \
         closed loop's fitted parameters are prefixed closed_loop, their identifiable \
         combinations are in the closed-loop section."
            .into(),
        vec![t],
    );
    let mut missing = Table::new(&["what", "why not"]);
    for m in &id.missing {
        let (what, why) = m.split_once(": ").unwrap_or(("", m));
        missing.push(vec![what.to_string(), why.to_string()]);
    }
    let mut defaults = Table::new(&["parameter-file key", "value written, and why"]);
    for (k, why) in id.defaults() {
        defaults.push(vec![k.to_string(), why.to_string()]);
    }
    let not = Section::tables(
        "What could not be identified, and why",
        "Estimates that could not be made are null in the JSON with the reason; the parameter \
         file keeps a default or a stated convention for these keys."
            .into(),
        vec![missing, defaults],
    );
    vec![identified, not]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::short_campaign;

    #[test]
    fn every_report_row_is_an_estimate_and_carries_its_value() {
        let c = short_campaign(&Params::trees_lab(), &["R2"], 12.0);
        let id = crate::identify::identify(&c);
        let rows = summary_rows(&id, Some(&Params::trees_lab()));
        let keys: Vec<&str> = rows.iter().map(|r| r.key.as_str()).collect();
        // section 4's sixteen in the report's order, then the device's, then the closed loop's
        assert_eq!(
            keys[..3],
            [
                "servovalve.gain",
                "servovalve.time_constant_s",
                "servovalve.natural_frequency_hz"
            ]
        );
        assert_eq!(
            keys[14..16],
            ["validation.table_tf_error", "validation.peak_hz"]
        );
        let device = keys.iter().filter(|k| k.starts_with("device.")).count();
        assert_eq!(device, if id.device.is_some() { 9 } else { 0 });
        assert!(keys[16 + device..]
            .iter()
            .all(|k| k.starts_with("closed_loop: ")));
        let mass = rows
            .iter()
            .find(|r| r.key == "table.mass_random_kg")
            .unwrap();
        assert_eq!(
            mass.value,
            id.estimate_of(Quantity::MassRandom).and_then(|e| e.value)
        );
        assert!(
            (mass.value.unwrap() / 41_258.0 - 1.0).abs() < 0.05,
            "{:?}",
            mass.value
        );
        assert!(mass.sigma.is_some_and(|s| s > 0.0));
        assert_eq!(mass.truth, Some(Params::trees_lab().table.mass_kg));
        // no sine: the loop approach's mass is null, not a number
        let loop_mass = rows
            .iter()
            .find(|r| r.key == "table.mass_periodic_kg")
            .unwrap();
        assert_eq!(loop_mass.value, None);
        assert!(text_table(&rows, true).contains("null"));
    }
}
