//! Validation of the identified model on the table transfer function (paper section 5).

use super::error::IdentifyError;
use super::frf::FrfEstimate;
use super::results::{FrfData, Validation};
use super::servovalve::relative_error;
use super::signals::welch_for;
use super::VALIDATION_BAND_HZ;
use crate::campaign::{Campaign, Record};
use crate::linear::{Linearisation, TfFigures};
use crate::params::{ActuatorModel, Params};
use crate::solver::{simulate_record, Simulated, DEFAULT_MAX_SUBSTEP_S};
use crate::Model;
use num_complex::Complex64;

/// Measured table TF of a random test: reference acceleration -> table acceleration.
pub(super) fn table_tf_of(rec: &Record, fs: f64) -> Result<FrfEstimate, IdentifyError> {
    let a = rec.acceleration_m_s2.as_deref().ok_or_else(|| {
        IdentifyError::not_usable("no acceleration_m_s2 channel: no measured table TF")
    })?;
    let w = welch_for(fs, rec.len()).map_err(IdentifyError::not_usable)?;
    w.frf(&rec.ref_acceleration_m_s2, a)
        .map_err(IdentifyError::not_usable)
}

/// Validation (section 5): the measured table TF of `name` against the identified
/// model's, analytic (ideal actuator) and simulated (nonlinear actuator).
pub fn validate(c: &Campaign, name: &str, params: &Params) -> Result<Validation, IdentifyError> {
    let (spec, rec) = c
        .test(name)
        .ok_or_else(|| IdentifyError::not_usable(format!("no {name} test: validation skipped")))?;
    let fs = c.sample_rate_for(spec);
    let mut p = *params;
    p.controller = c.controller_for(spec).map_err(IdentifyError::not_usable)?;
    let meas = table_tf_of(rec, fs)?;
    let idx = meas.band(VALIDATION_BAND_HZ[0], VALIDATION_BAND_HZ[1]);
    let h: Vec<Complex64> = idx.iter().map(|&i| meas.h1[i]).collect();
    let f: Vec<f64> = idx.iter().map(|&i| meas.frequency_hz[i]).collect();
    let mut pi = p;
    pi.actuator.model = ActuatorModel::Ideal;
    let lin = Linearisation::new(&pi);
    let ideal: Vec<Complex64> = f.iter().map(|&x| lin.table_tf(x)).collect();
    let mut pn = p;
    pn.actuator.model = ActuatorModel::Nonlinear;
    let sim = simulate_record(
        &Model::new(&pn),
        &rec.inputs(),
        fs,
        None,
        DEFAULT_MAX_SUBSTEP_S,
    );
    let w = welch_for(fs, rec.len()).map_err(IdentifyError::not_usable)?;
    let acc = simulated_acceleration(sim)?;
    let simf = w
        .frf(&rec.ref_acceleration_m_s2, &acc)
        .map_err(IdentifyError::not_usable)?;
    let nonlinear: Vec<Complex64> = idx.iter().map(|&i| simf.h1[i]).collect();
    // the peak search runs over the validation band only (issue 14, item 9)
    let measured_figures = TfFigures::from_frf(&crate::linear::Frf {
        frequency_hz: f.clone(),
        response: h.clone(),
    });
    let model_figures = lin.table_tf_figures();
    let ones = vec![1.0; f.len()];
    Ok(Validation {
        test: name.to_string(),
        table_tf_error: relative_error(&ideal, &h),
        table_tf_error_nonlinear: relative_error(&nonlinear, &h),
        peak_hz: model_figures.map(|m| m.peak_hz).unwrap_or(f64::NAN),
        measured_figures,
        model_figures,
        measured: FrfData::from(
            &f,
            &h,
            &idx.iter().map(|&i| meas.coherence[i]).collect::<Vec<_>>(),
            [0.0, f64::MAX],
        ),
        ideal: FrfData::from(&f, &ideal, &ones, [0.0, f64::MAX]),
        nonlinear: FrfData::from(&f, &nonlinear, &ones, [0.0, f64::MAX]),
    })
}

/// The table acceleration of the nonlinear model's run. A run that stopped has no table
/// TF: the validation is not usable, and the error says that the identified model's run
/// stopped, where and why (not a non-finite sample, which a reader takes for the file's).
fn simulated_acceleration(sim: Simulated) -> Result<Vec<f64>, IdentifyError> {
    match sim {
        Ok(out) => Ok(out.iter().map(|o| o.acceleration_m_s2).collect()),
        Err(stop) => Err(IdentifyError::not_usable(format!(
            "the identified model's run with the nonlinear actuator: {stop}; no simulated \
             table transfer function"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::short_campaign;

    /// A model whose run leaves the envelope (a flow gain, and with it the loop gain, 50
    /// times the table's) makes the validation unusable with an error that says the
    /// model's run stopped, where and why, not a non-finite sample of the file.
    #[test]
    fn a_model_whose_run_stops_is_named_as_such() {
        let truth = Params::trees_lab();
        let c = short_campaign(&truth, &["R2"], 8.0);
        assert!(validate(&c, "R2", &truth).is_ok());
        let mut unstable = truth;
        unstable.actuator.flow_gain_m3_s *= 50.0;
        let text = validate(&c, "R2", &unstable).unwrap_err().to_string();
        assert!(
            text.contains("the identified model's run with the nonlinear actuator")
                && text.contains("stopped at sample")
                && !text.contains("non-finite sample"),
            "{text}"
        );
    }
}
