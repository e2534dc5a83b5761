//! What diagnosis returns: the fitted candidates and the whole diagnosis.

use super::effect::Effect;
use super::residuals::{NoiseFloor, CHANNELS, SCORE_WINDOW};
use super::{EXPLAINED_RATIO, MISS_RATIO, REQUIRED_GAIN};
use crate::identify::Identification;
use crate::params::{ActuatorModel, Params, ServovalveModel};
use serde::Serialize;
use std::collections::BTreeMap;

/// A fitted candidate effect.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    pub effect: Effect,
    pub parameters: BTreeMap<String, f64>,
    /// RMS standardised residual (in units of the spread the model predicts) on the
    /// held-out cells the baseline misses.
    pub heldout_residual: f64,
    /// RMS predictive score on the same cells times a penalty of 1 % per parameter
    /// (lower is better): the ranking.
    pub score: f64,
    pub fit_residual: f64,
    #[serde(skip)]
    pub params: Params,
    /// Held-out standardised residuals per test and channel.
    #[serde(skip)]
    pub heldout_rows: Vec<[f64; 5]>,
    /// Held-out predictive scores per test and channel.
    #[serde(skip)]
    pub score_rows: Vec<[f64; 5]>,
}

/// The whole diagnosis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    pub identification: Identification,
    pub baseline: Params,
    pub noise: NoiseFloor,
    /// Per test (campaign order) and channel.
    pub baseline_rows: Vec<(String, [f64; 5])>,
    pub baseline_heldout: f64,
    /// Standardised held-out residual of the baseline per held-out test and channel.
    pub baseline_heldout_rows: Vec<[f64; 5]>,
    /// RMS predictive score of the baseline on the missed cells.
    pub baseline_score: f64,
    pub candidates: Vec<Candidate>,
    pub cause: Option<Effect>,
    /// Why the best candidate was not taken as the cause though it scored (unphysical).
    pub cause_rejected: Option<String>,
    pub explained: bool,
    pub gain: f64,
    pub extended: Params,
    pub fit_tests: Vec<String>,
    pub heldout_tests: Vec<String>,
    pub valve_model: ServovalveModel,
    pub actuator_model: ActuatorModel,
    /// Output-error cost of the refined baseline with the ideal and nonlinear actuator.
    pub actuator_costs: [f64; 2],
}

impl Diagnosis {
    /// A sentence when the extended model's actuator variant differs from the baseline's
    /// (chosen again with the effect in place, step 4 of [`diagnose`]).
    pub fn structure_change(&self) -> Option<String> {
        let ext = self.extended.actuator.model;
        (ext != self.actuator_model).then(|| {
            format!(
                "the extended model's actuator is {} (the baseline's, {}, was chosen with the \
                 effect missing; with it in place the {} actuator fits better)",
                ext.name(),
                self.actuator_model.name(),
                ext.name()
            )
        })
    }

    /// The JSON of issue 6 (fixed keys).
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::json;
        let cause = self.cause.map(|e| e.name()).unwrap_or("none");
        let parameters = match self
            .cause
            .and_then(|e| self.candidates.iter().find(|c| c.effect == e))
        {
            Some(c) => json!(c.parameters),
            None => json!({}),
        };
        let mut base = serde_json::Map::new();
        for (name, r) in &self.baseline_rows {
            let mut m = serde_json::Map::new();
            for (ch, v) in CHANNELS.iter().zip(r) {
                if v.is_finite() {
                    m.insert(ch.to_string(), json!(v));
                }
            }
            base.insert(name.clone(), serde_json::Value::Object(m));
        }
        json!({
            "cause": cause,
            "cause_rejected": self.cause_rejected,
            "parameters": parameters,
            "gain": self.gain,
            "explained": self.explained,
            "baseline_residuals": base,
            "baseline_heldout_residual": self.baseline_heldout,
            "baseline_heldout_score": self.baseline_score,
            "baseline_heldout_residuals": self.heldout_tests.iter().zip(&self.baseline_heldout_rows).map(|(t, r)| {
                (t.clone(), serde_json::Value::Object(CHANNELS.iter().zip(r).filter(|(_, v)| v.is_finite()).map(|(ch, v)| (ch.to_string(), json!(v))).collect()))
            }).collect::<serde_json::Map<_, _>>(),
            "candidates": self.candidates.iter().map(|c| json!({
                "effect": c.effect.name(),
                "parameters": c.parameters,
                "heldout_residual": c.heldout_residual,
                "score": c.score,
            })).collect::<Vec<_>>(),
            "noise": self.noise,
            "fit_tests": self.fit_tests,
            "heldout_tests": self.heldout_tests,
            "baseline_structure": {
                "servovalve": self.valve_model.name(),
                "actuator": self.actuator_model.name(),
            },
            "extended_structure": {
                "servovalve": self.extended.servovalve.model.name(),
                "actuator": self.extended.actuator.model.name(),
            },
            "rule": format!("held-out = second half of every test; every model is simulated noise-free and with seeded sensor noise at the estimated levels inside the loop; residual (measured - noise-free run) and predicted spread (noisy run with its own sensor noise - noise-free run) are split into octave bands (the lowest from 0 Hz, the highest to Nyquist) and scored per band in windows of {SCORE_WINDOW} samples or more (8 degrees of freedom in the band): score = sqrt(mean over bands of mean(P_meas/P_pred + ln(P_pred/floor^2 share))) (Gaussian log score, a proper scoring rule), residual = sqrt(mean over bands of mean(P_meas/P_pred)) (1 for a model that predicts the data to within its noise); missed cells = held-out (test, channel) cells whose baseline residual exceeds {MISS_RATIO}; cause = the candidate with the lowest RMS score on the missed cells (1 % penalty per parameter) when it divides the baseline's score by >= {REQUIRED_GAIN}; none when no cell is missed; gain = baseline residual / extended residual on the missed cells; explained when the extended residual <= {EXPLAINED_RATIO}"),
        })
    }
}
