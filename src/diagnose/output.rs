//! What diagnosis returns: the fitted candidates and the whole diagnosis.

use super::candidates::PENALTY_PER_PARAMETER;
use super::effect::Effect;
use super::effect_values::EffectValues;
use super::effort::Effort;
use super::evidence::EVIDENCE_SIGMAS;
use super::pipeline::{
    COHERENT_MAJORITY, MAX_COHERENT_LEFT, MIN_COHERENT_REMOVED, UNRESOLVED_CHANGE,
};
use super::residuals::{
    Cells, NoiseFloor, HELDOUT_REALISATIONS, REALISATIONS, SCORE_WINDOW, WINDOW_DOF,
};
use super::specimen_modes::{parameters_json, MODE_SEPARATION};
use super::visibility::Visibility;
use super::{EXPLAINED_RATIO, MISS_RATIO, REQUIRED_GAIN};
use crate::identify::Identification;
use crate::params::{ActuatorModel, Params, ServovalveModel};
use serde::Serialize;
use std::collections::BTreeMap;

/// A model's figures per test and channel over one part of the tests (the order of the
/// campaign; [`Cells`]).
#[derive(Debug, Clone, Default)]
pub struct PartRows {
    /// The predictive score ([`super::residuals::CellScores::score`]).
    pub score: Vec<Cells>,
    /// The standardised residual ([`super::residuals::CellScores::residual`]).
    pub residual: Vec<Cells>,
    /// The sample-wise residual ([`super::residuals::CellScores::deviation`]).
    pub deviation: Vec<Cells>,
    /// Whether the model's noise-free run left the operating envelope (spec section 8)
    /// over the part where the measured table did not, per test.
    pub left_envelope: Vec<bool>,
}

/// A fitted candidate effect.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    pub effect: Effect,
    pub parameters: BTreeMap<String, f64>,
    /// One-sigma uncertainty of each parameter from the fit's covariance; absent where the
    /// fit gives none (the stick-slip fit is not a least-squares one).
    pub sigma: BTreeMap<String, f64>,
    /// RMS standardised residual (in units of the spread the model predicts) on the
    /// selection quarter's cells the model it extends misses.
    pub select_residual: f64,
    /// RMS sample-wise residual (the noise-free run's distance to the records, over the
    /// noise floor) on the same cells: it credits no spread the model predicts.
    pub select_deviation: f64,
    /// RMS predictive score on the same cells times a penalty of 1 % per parameter
    /// (lower is better): the ranking.
    pub score: f64,
    /// RMS standardised residual on the report quarter's cells the baseline misses (shown,
    /// never used for a decision).
    pub report_residual: f64,
    pub fit_residual: f64,
    /// Why the candidate is not evidence of its effect, if it is not ([`super::evidence`]).
    pub not_evidence: Option<String>,
    #[serde(skip)]
    pub params: Params,
    #[serde(skip)]
    pub select: PartRows,
    #[serde(skip)]
    pub report: PartRows,
    /// A specimen of several modes: itself with one mode fewer, which the search falls
    /// back to when polishing leaves no evidence of the last mode.
    #[serde(skip)]
    pub fewer_modes: Option<Box<Candidate>>,
    /// The one-sigma uncertainties of the causes accepted before, refitted with this one
    /// by its polish (empty without a polish).
    #[serde(skip)]
    pub refitted_sigma: Vec<EffectValues>,
}

impl Candidate {
    /// A candidate of `effect` with no parameters and no figures yet (NaN).
    pub fn empty(effect: Effect) -> Candidate {
        Candidate {
            effect,
            parameters: BTreeMap::new(),
            sigma: BTreeMap::new(),
            select_residual: f64::NAN,
            select_deviation: f64::NAN,
            score: f64::NAN,
            report_residual: f64::NAN,
            fit_residual: f64::NAN,
            not_evidence: None,
            params: Params::default(),
            select: PartRows::default(),
            report: PartRows::default(),
            fewer_modes: None,
            refitted_sigma: Vec::new(),
        }
    }
}

/// An accepted cause: an effect, its parameters, and what it gained on the report quarter.
#[derive(Debug, Clone, Serialize)]
pub struct Cause {
    pub effect: Effect,
    pub parameters: BTreeMap<String, f64>,
    pub sigma: BTreeMap<String, f64>,
    /// RMS report-quarter residual on the baseline's missed cells of the model before this
    /// cause over that of the model with it.
    pub gain: f64,
}

/// A candidate that helped on the selection quarter but is not a cause: not evidence
/// (significance, bounds), unphysical, below what chance moves the score by, or made
/// unneeded by the causes found after it (the backward step): at most a partial
/// explanation.
#[derive(Debug, Clone, Serialize)]
pub struct Partial {
    pub effect: Effect,
    pub parameters: BTreeMap<String, f64>,
    /// Selection-quarter score of the model before it over the model with it.
    pub selection_gain: f64,
    pub why_not_a_cause: String,
}

/// One report-quarter cell the final model still misses, located in frequency.
#[derive(Debug, Clone, Serialize)]
pub struct UnexplainedCell {
    pub test: String,
    pub channel: String,
    /// The octave band where the cell's residual is largest.
    pub band_hz: [f64; 2],
    /// The cell's standardised residual (all bands).
    pub residual: f64,
    /// The band's standardised residual.
    pub band_residual: f64,
    /// What the residual depends on, where measurable: RMS residual (noise units) while
    /// the table moves up against down, at large against small displacement.
    pub depends_on: super::locate::Dependence,
    /// The cell's sample-wise RMS residual (noise units), as it is and centred, and what
    /// the channel read with a fitted scale and offset, or a fitted delay, would leave of
    /// it ([`super::calibration`]); `None` where the run stopped in the report quarter.
    pub removed_by: Option<super::calibration::RemovedBy>,
}

/// The whole diagnosis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// How hard its fits worked (a quick diagnosis is for the development loop).
    pub effort: Effort,
    pub identification: Identification,
    pub baseline: Params,
    pub noise: NoiseFloor,
    /// Per test (campaign order) and channel, over the whole test
    /// ([`super::residuals::ratios`]).
    pub baseline_rows: Vec<(String, Cells)>,
    /// The baseline on the selection and report quarters.
    pub baseline_select: PartRows,
    pub baseline_report: PartRows,
    /// RMS report residual of the baseline on its missed report cells.
    pub baseline_heldout: f64,
    /// RMS selection score of the baseline on its missed selection cells.
    pub baseline_score: f64,
    /// The first search's candidates (every catalogue effect on the baseline).
    pub candidates: Vec<Candidate>,
    /// Accepted causes in order of acceptance.
    pub causes: Vec<Cause>,
    /// Candidates that helped but are not evidence.
    pub partial: Vec<Partial>,
    /// Effects the recorded channels cannot show, with why (never reported as absent).
    pub not_testable: Vec<String>,
    /// Without a force channel and no specimen named: the lightest specimen the records
    /// would have shown, per frequency ([`super::visibility`]).
    pub specimen_visibility: Option<Visibility>,
    /// Why the best candidate was not taken as the cause though it scored (unphysical).
    pub cause_rejected: Option<String>,
    /// Why no search ran, when the refined baseline could not be scored on any test.
    pub baseline_unscorable: Option<String>,
    /// No report cell the baseline missed is still missed ([`super::EXPLAINED_RATIO`]).
    pub explained: bool,
    /// Report residual of the baseline over the extended model's, on the baseline's
    /// missed report cells.
    pub gain: f64,
    /// The report residual of the extended model on the same cells.
    pub extended_heldout: f64,
    pub extended: Params,
    /// Where the residual lies when not explained, worst first.
    pub unexplained: Vec<UnexplainedCell>,
    /// Channels whose unexplained cells one sensor number (a scale, a delay) removes.
    pub sensor_findings: Vec<super::calibration::SensorFinding>,
    /// The accelerometer against the LVDT's second derivative, from the recordings alone;
    /// `None` when no test recorded both.
    pub kinematics: Option<super::kinematics::KinematicCheck>,
    /// Per test and channel, the fit % of the baseline and the extended model on the
    /// report quarter ([`super::fits`]).
    pub fits: Vec<super::ModelFit>,
    pub tests: Vec<String>,
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

    /// The first cause (the JSON's `cause`, for readers of one cause).
    pub fn cause(&self) -> Option<Effect> {
        self.causes.first().map(|c| c.effect)
    }

    /// Where the baseline came from: section 4's estimates, or the closed-loop fit of the
    /// recorded motion when section 4 could not give every part or the gains are unknown
    /// (issue 16 part 3), with what section 4 lacked.
    pub fn baseline_from(&self) -> String {
        let id = &self.identification;
        if id.closed_loop.is_none() {
            return "section 4 estimates (refined by output error)".into();
        }
        let lacked: Vec<&str> = id
            .section4_gaps()
            .into_iter()
            .chain(id.unknown_inputs.iter().copied())
            .collect();
        format!(
            "closed-loop fit of the recorded motion (refined by output error); section 4 could not give: {}",
            lacked.join(", ")
        )
    }

    /// Whether the model's table mass is a convention (no force channel: the closed-loop
    /// fit held it as the scale of the motion's combinations), so that every mass the
    /// diagnosis names is on that scale and only its ratio to the table mass is measured.
    pub fn mass_is_convention(&self) -> bool {
        self.identification
            .closed_loop
            .as_ref()
            .is_some_and(|f| f.conventions.iter().any(|k| k.key == "table.mass_kg"))
    }

    /// Each `*mass_kg` parameter of `parameters` over the extended model's table mass.
    pub fn mass_ratios(&self, parameters: &BTreeMap<String, f64>) -> BTreeMap<String, f64> {
        parameters
            .iter()
            .filter(|(k, _)| k.ends_with("mass_kg"))
            .map(|(k, m)| {
                (
                    k.replace("mass_kg", "mass_ratio"),
                    m / self.extended.table.mass_kg,
                )
            })
            .collect()
    }

    /// Without a force channel, a sentence saying the named masses are on a conventional
    /// scale and giving their ratios (`None` when the table mass was measured or no cause
    /// has a mass).
    pub fn mass_scale_text(&self) -> Option<String> {
        if !self.mass_is_convention() {
            return None;
        }
        let ratios: Vec<String> = self
            .causes
            .iter()
            .flat_map(|c| {
                self.mass_ratios(&c.parameters)
                    .into_iter()
                    .map(move |(k, r)| format!("{} {k} {r:.3}", c.effect.name()))
            })
            .collect();
        (!ratios.is_empty()).then(|| {
            format!(
                "No force channel: the table mass is a convention ({:.3} t in the extended model) and the masses above are on its scale; only their ratios to it are measured (every fit holds it, and a specimen that takes its mass out of it is fitted against the rest): {}",
                self.extended.table.mass_kg / 1000.0,
                ratios.join(", ")
            )
        })
    }

    /// What the records could not show of a specimen, in a sentence (`None` when
    /// [`Diagnosis::specimen_visibility`] was not computed).
    pub fn visibility_text(&self) -> Option<String> {
        let v = self.specimen_visibility.as_ref()?;
        let share = |m: f64| format!("{:.3} t ({:.1} %)", m / 1000.0, 100.0 * m / v.table_mass_kg);
        let each: Vec<String> = v
            .specimens
            .iter()
            .map(|s| match s.smallest_visible_mass_kg {
                Some(m) if s.at_lightest_probed => {
                    format!("at most {} at {} Hz", share(m), s.frequency_hz)
                }
                Some(m) => format!("{} at {} Hz", share(m), s.frequency_hz),
                None => format!(
                    "more than {} at {} Hz",
                    share(s.probed_mass_kg[1]),
                    s.frequency_hz
                ),
            })
            .collect();
        Some(format!(
            "No force channel: a specimen shows only through the recorded motion. Probed on {}, a specimen (damping {}) must weigh at least {} to change these records beyond their noise (percent of the model's table mass, itself a convention without a force channel); a lighter one may be on the table unseen",
            v.tests.join(", "),
            v.specimens.first().map_or(0.0, |s| s.damping_ratio),
            each.join(", ")
        ))
    }

    /// The JSON of issue 6 (fixed keys), with issue 17's `causes`, `partial` and
    /// `unexplained`.
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::json;
        let cause = self.cause().map(|e| e.name()).unwrap_or("none");
        let parameters = match self.causes.first() {
            Some(c) => parameters_json(c.effect, &c.parameters),
            None => json!({}),
        };
        let base: serde_json::Map<String, serde_json::Value> = self
            .baseline_rows
            .iter()
            .map(|(name, r)| (name.clone(), cells_json(r)))
            .collect();
        json!({
            "effort": self.effort.name(),
            "cause": cause,
            "cause_rejected": self.cause_rejected,
            "baseline_unscorable": self.baseline_unscorable,
            "parameters": parameters,
            "causes": self.causes_json(),
            "mass_scale": {
                "table_mass_kg": self.extended.table.mass_kg,
                "convention": self.mass_is_convention(),
                "rule": "without a force channel the table mass is held at a conventional value (the closed-loop fit's scale) and every mass named is on its scale: only the ratios (mass_ratios: mass over the extended model's table mass) are measured",
            },
            "partial": self.partial_json(),
            "not_testable": self.not_testable,
            "specimen_visibility": self.specimen_visibility,
            "gain": self.gain,
            "explained": self.explained,
            "unexplained": self.unexplained,
            "sensor_findings": self.sensor_findings,
            "kinematics": self.kinematics,
            "fits": self.fits,
            "baseline_residuals": base,
            "baseline_heldout_residual": self.baseline_heldout,
            "extended_heldout_residual": self.extended_heldout,
            "baseline_heldout_score": self.baseline_score,
            "baseline_heldout_residuals": self.per_test_json(&self.baseline_report.residual),
            "baseline_selection_residuals": self.per_test_json(&self.baseline_select.residual),
            "candidates": self.candidates_json(),
            "noise": self.noise,
            "fit_tests": self.tests,
            "heldout_tests": self.tests,
            "split": split_json(),
            "baseline_from": self.baseline_from(),
            "closed_loop": self.identification.closed_loop,
            "baseline_structure": {
                "servovalve": self.valve_model.name(),
                "actuator": self.actuator_model.name(),
            },
            "extended_structure": {
                "servovalve": self.extended.servovalve.model.name(),
                "actuator": self.extended.actuator.model.name(),
            },
            "rule": self.rule(),
        })
    }

    /// The accepted causes as the JSON lists them (a specimen of several modes as the
    /// parameter file writes it, `modes`).
    fn causes_json(&self) -> Vec<serde_json::Value> {
        self.causes
            .iter()
            .map(|c| {
                serde_json::json!({
                    "effect": c.effect.name(),
                    "parameters": parameters_json(c.effect, &c.parameters),
                    "sigma": c.sigma,
                    "gain": c.gain,
                    "mass_ratios": self.mass_ratios(&c.parameters),
                })
            })
            .collect()
    }

    /// The partial explanations as the JSON lists them.
    fn partial_json(&self) -> Vec<serde_json::Value> {
        self.partial
            .iter()
            .map(|c| {
                serde_json::json!({
                    "effect": c.effect.name(),
                    "parameters": parameters_json(c.effect, &c.parameters),
                    "selection_gain": c.selection_gain,
                    "why_not_a_cause": c.why_not_a_cause,
                })
            })
            .collect()
    }

    /// The first search's candidates as the JSON lists them.
    fn candidates_json(&self) -> Vec<serde_json::Value> {
        self.candidates
            .iter()
            .map(|c| {
                serde_json::json!({
                    "effect": c.effect.name(),
                    "parameters": parameters_json(c.effect, &c.parameters),
                    "sigma": c.sigma,
                    "selection_residual": c.select_residual,
                    "selection_deviation": c.select_deviation,
                    "heldout_residual": c.report_residual,
                    "score": c.score,
                    "not_evidence": c.not_evidence,
                })
            })
            .collect()
    }

    /// `rows` (one per test, campaign order) keyed by test name ([`cells_json`]).
    fn per_test_json(&self, rows: &[Cells]) -> serde_json::Map<String, serde_json::Value> {
        self.tests
            .iter()
            .zip(rows)
            .map(|(t, r)| (t.clone(), cells_json(r)))
            .collect()
    }

    /// The rule the diagnosis followed, in words (the JSON's `rule`, the report's).
    pub fn rule(&self) -> String {
        rule_text()
    }
}

/// The rule every diagnosis follows, in words, its numbers read from the constants that
/// decide.
fn rule_text() -> String {
    let mode_apart_percent = 100.0 * (MODE_SEPARATION - 1.0);
    let unresolved_percent = 100.0 * UNRESOLVED_CHANGE;
    let majority = share_in_words(COHERENT_MAJORITY);
    let min_removed = share_in_words(MIN_COHERENT_REMOVED);
    let penalty_percent = 100.0 * PENALTY_PER_PARAMETER;
    format!("every model is simulated noise-free and with seeded sensor noise at the estimated levels inside the loop ({REALISATIONS} draw on the fitting halves, the same for every model; {HELDOUT_REALISATIONS} on the selection and report quarters); residual (measured - noise-free run) and predicted spread (noisy run with its own sensor noise - noise-free run) are split into octave bands (the lowest from 0 Hz, the highest to Nyquist) and scored per band in windows of {SCORE_WINDOW} samples or more ({WINDOW_DOF} degrees of freedom in the band): score = sqrt(mean over bands of mean(P_meas/P_pred + ln(P_pred/floor^2 share))) (Gaussian log score, a proper scoring rule), residual = sqrt(mean over bands of mean(P_meas/P_pred)) (1 for a model that predicts the data to within its noise), deviation = RMS(measured - noise-free run) / floor (shown per candidate as selection_deviation; it credits no spread, and decides nothing); on a test whose displacement reference was integrated from its recorded acceleration the displacement's lowest band is not scored (the integral's error there is bounded by no recording); missed cells = (test, channel) cells whose residual exceeds {MISS_RATIO}; each search fits every effect not yet accepted on the current model (fit half) and ranks them by RMS score on the cells the current model misses in the selection quarter ({penalty_percent} % penalty per parameter; a specimen is refitted with one mode more, every mode free, up to three, while that divides its score there by >= {REQUIRED_GAIN}, every mode's mass is significant and its modes lie {mode_apart_percent:.0} % apart in frequency); the best is a cause when it divides the current score there by >= {REQUIRED_GAIN} times the factor by which chance moves that score (its largest ratio when the table mass changes by {unresolved_percent} % either way: 1 for a smooth model, more where free play bounces), is physical and is evidence (no parameter at a bound of its range, its strength parameter more than {EVIDENCE_SIGMAS} sigma from its no-effect value) and, where more than {majority} the residual power on those cells is coherent with the reference (deterministic: no predicted spread holds it), its noise-free run removes at least {min_removed} of that coherent power; and in any case its noise-free run leaves at most {MAX_COHERENT_LEFT} x the current model's whole residual power on those cells as coherent power (more is a deterministic error it adds, credited only by the spread it predicts); the search repeats with the causes in the model until no candidate passes or no selection cell is missed; a candidate that passes {REQUIRED_GAIN} but not that bar is listed in partial; then, while two causes or more are named, each is taken out of the final model in turn, and the one whose removal raises the selection score least against its bar is dropped (listed in partial) when the model with it would not pass that rule on top of the model without it; gain = baseline residual / extended residual on the baseline's missed cells of the report quarter; explained when every such cell has an extended residual <= {EXPLAINED_RATIO}")
}

/// What each part of every test is used for ([`super::Part`]).
fn split_json() -> serde_json::Value {
    serde_json::json!({
        "fit": "first half of every test: every least-squares fit",
        "select": "third quarter of every test: missed cells, ranking, polishing, actuator variant, acceptance, whether to search again",
        "report": "last quarter of every test: gain, explained and unexplained only",
    })
}

/// The finite cells of `r` keyed by channel name: a diverged run's are left out like
/// absent channels.
fn cells_json(r: &Cells) -> serde_json::Value {
    serde_json::Value::Object(
        r.iter()
            .filter_map(|(ch, v)| v.finite().map(|v| (ch, v)))
            .map(|(ch, v)| (ch.name().to_string(), serde_json::json!(v)))
            .collect(),
    )
}

/// A share in words as the rule's text says it ("half", "a tenth"), a percentage when it
/// is no simple fraction.
fn share_in_words(share: f64) -> String {
    const WORDS: [(f64, &str); 4] = [
        (0.5, "half"),
        (0.25, "a quarter"),
        (0.2, "a fifth"),
        (0.1, "a tenth"),
    ];
    WORDS
        .iter()
        .find(|(x, _)| *x == share)
        .map_or_else(|| format!("{:.0} %", 100.0 * share), |(_, w)| w.to_string())
}

#[cfg(test)]
mod tests {
    use super::{rule_text, share_in_words};

    #[test]
    fn simple_shares_are_said_in_words() {
        assert_eq!(share_in_words(0.5), "half");
        assert_eq!(share_in_words(0.1), "a tenth");
        assert_eq!(share_in_words(0.15), "15 %");
    }

    /// The numbers the rule's text reads from the constants, as it has always printed them.
    #[test]
    fn the_rule_says_its_numbers_as_before() {
        let rule = rule_text();
        for said in [
            "its modes lie 10 % apart in frequency",
            "the table mass changes by 0.1 % either way",
            "where more than half the residual power",
            "removes at least a tenth of that coherent power",
        ] {
            assert!(rule.contains(said), "{said}");
        }
    }
}
