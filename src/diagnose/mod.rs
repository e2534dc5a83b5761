//! Diagnosis: what the identified baseline misses, which catalogue effect (spec section 7)
//! causes it (several at once), the effects' parameters, the gain on data no step saw,
//! and where the residual left lies.
//!
//! Method:
//! 1. Baseline from [`crate::identify`] (structure from the data: valve order from the
//!    valve FRF, or from the closed-loop fit's criterion without a spool channel,
//!    actuator variant by output error), refined by output-error least squares
//!    on the fitting halves: the valve on the spool channel alone (blind to the flow
//!    effects), then mass, bulk modulus, leakage and friction amplitude on every channel.
//! 2. Noise from the data ([`residuals::estimate_noise`]): the floor from the rest
//!    segments, the white sensor noise from the high-frequency content; an LVDT nobody
//!    recorded, from the acceleration at rest through the baseline's loop
//!    ([`residuals::NoiseFloor::with_unrecorded_lvdt`]).
//! 3. Residuals per test and channel in noise units (the heat map), and the predictive
//!    score of every model on the held-out halves ([`residuals`]): each model is run
//!    noise-free and with seeded in-loop sensor noise, so a model whose response the
//!    noise drives (stick-slip chatter) is judged on the spread it predicts, not on a
//!    phase it cannot know.
//! 4. Each catalogue effect fitted over the fitting halves of the tests where its
//!    signature lives (of every test when the baseline came from the closed-loop fit of
//!    the motion: [`baseline::from_motion`]), with the baseline's refined parameters
//!    free, from physically
//!    informed starts (FRF fits for specimen and foundation, the velocity plateau for flow
//!    saturation, small grids for the deadband) by output-error least squares; stick-slip
//!    from the friction-velocity curve of the slow tests ([`stribeck`]), polished on the
//!    predictive score (its chatter has no reproducible phase). A specimen is refitted
//!    with one mode more, every mode free, while that divides its selection score by
//!    [`REQUIRED_GAIN`] and each mode is evidence ([`specimen_modes`], up to three).
//! 5. The best candidate by score on the cells the current model misses in the
//!    selection quarter is a cause when it divides that model's score by at least
//!    [`REQUIRED_GAIN`] times what chance moves that score by (a rough model's: free
//!    play), is physical and is evidence (no parameter at a bound, its strength
//!    significant: [`evidence`]); then the search repeats with the causes in the model
//!    ([`pipeline::MAX_CAUSES`] at most). A candidate with the gain but no evidence is
//!    listed as a partial explanation. With two causes or more, one the others make
//!    unneeded is dropped again (the backward step, `pipeline/prune.rs`).
//! 6. The gain and `explained` on the report quarter only, which no fit and no decision
//!    saw ([`Part`]); `explained` when every report cell the baseline missed is within
//!    [`EXPLAINED_RATIO`]; otherwise the cells still missed are located ([`locate`]).
//! 7. Without a force channel and no specimen named, the lightest specimen per
//!    frequency the records would have shown ([`visibility`]): a stiff displacement loop
//!    can hide a heavy one from the table's motion, and then `none` is no evidence.

mod baseline;
pub mod calibration;
mod candidate_fit;
mod candidates;
mod direction_starts;
mod effect;
mod effect_table;
mod effect_values;
mod effort;
mod evidence;
mod fits;
mod free_play_fit;
mod free_play_start;
pub mod kinematics;
mod locate;
mod missed;
mod mode_starts;
pub mod model_error;
mod output;
mod part;
mod pipeline;
pub mod residuals;
mod simplex;
mod specimen_modes;
mod starts;
mod stick_slip;
pub mod stribeck;
mod visibility;

pub use effect::Effect;
pub use effort::Effort;
pub use fits::{medians_by_channel, ChannelMedian, ModelFit};
pub use locate::{Dependence, Split};
pub use model_error::{
    model_error_response, unexplained_responses, CellResponse, ModelErrorPeak, ModelErrorResponse,
    NoResponse, ResponseEstimate,
};
pub use output::{Candidate, Cause, Diagnosis, PartRows, Partial, UnexplainedCell};
pub use part::Part;

pub use residuals::{
    estimate_noise, predict, ratios, readings, scores, simulate_test, CellScores, Cells, Channel,
    Diverged, NoiseFloor, PerChannel, TestRun, Whitening, SCORE_WINDOW,
};

use crate::campaign::screen::screen;
use crate::campaign::Campaign;
use crate::identify::{identify_screened, Identification};

/// `SHAKETABLE_TRACE` set: the diagnosis prints its steps' and fits' timings on stderr.
pub fn trace_enabled() -> bool {
    std::env::var_os("SHAKETABLE_TRACE").is_some()
}

/// A candidate must divide the predictive score of the model it extends, on the cells
/// that model misses in the selection quarter, by at least this to be named.
pub const REQUIRED_GAIN: f64 = 1.25;
/// Report-quarter residual of a cell (in noise units) at or below which the extended
/// model counts as explaining it; the data is explained when every cell the baseline
/// missed is.
pub const EXPLAINED_RATIO: f64 = 2.0;
/// A held-out (test, channel) cell whose baseline residual exceeds this many noise RMS is
/// one the baseline misses; with no such cell the data is at the noise floor (`none`).
/// Candidates are scored on the missed cells, so an effect that lives in a few tests
/// is not diluted by the many it does not touch.
pub const MISS_RATIO: f64 = 1.5;

/// Progress callback: (step done, steps in all, what).
pub type Progress<'a> = &'a (dyn Fn(usize, usize, &str) + Sync);

/// Largest added (specimen, foundation) mass a cause may have, in table masses: beyond it
/// the "effect" is a fit absorbing garbage, not a physical body on or under the table.
pub const MAX_ADDED_MASS_RATIO: f64 = 100.0;

/// Why the baseline identification cannot support a diagnosis of `c`, if it cannot:
/// every part of the baseline must be identified, or the candidates would explain the
/// defaults, and every test's gains known to simulate it. The closed-loop fit (issue 16
/// part 3) supplies both when section 4 could not: its model is the baseline then.
fn baseline_gaps(c: &Campaign, id: &Identification) -> Option<String> {
    if id.closed_loop.is_some() {
        return None;
    }
    let mut gaps: Vec<String> = id.section4_gaps().into_iter().map(String::from).collect();
    if let Err(e) = c.gains_known() {
        gaps.push(format!("controller gains ({e})"));
    }
    (!gaps.is_empty()).then(|| {
        format!(
            "diagnosis refused: the baseline identification lacks the {} and no closed-loop fit replaced it ({})",
            gaps.join(", "),
            id.missing.join("; ")
        )
    })
}

/// Why candidate `b` is not a physical cause, if it is not: a non-finite parameter, or an
/// added mass or frequency outside physical bounds.
fn unphysical(b: &Candidate, table_mass_kg: f64) -> Option<String> {
    let f = crate::identify::FREQUENCY_BOUNDS_HZ;
    b.parameters.iter().find_map(|(k, &v)| {
        let bad = !v.is_finite()
            || (k.ends_with("mass_kg") && !(v > 0.0 && v <= MAX_ADDED_MASS_RATIO * table_mass_kg))
            || (k.ends_with("frequency_hz") && !(v >= f[0] && v <= f[1]));
        bad.then(|| {
            format!(
                "{} rejected as a cause: {k} = {v:.4e} is not physical (bounds: finite, added mass <= {MAX_ADDED_MASS_RATIO} table masses, frequency in {f:?} Hz)",
                b.effect.name()
            )
        })
    })
}

/// Diagnose a campaign (see the module doc) after screening its records, on the channels
/// it recorded (an effect whose signature needs a missing channel is not testable), with
/// the fits' `effort`; refused (with the reason) when neither section 4 nor the
/// closed-loop fit gives a complete baseline.
pub fn diagnose(
    c: &Campaign,
    effort: Effort,
    progress: Option<Progress>,
) -> Result<Diagnosis, String> {
    let screened = screen(c);
    let id = identify_screened(&screened);
    if let Some(why) = baseline_gaps(&screened.campaign, &id) {
        return Err(why);
    }
    Ok(pipeline::diagnose_with(
        screened.compared(),
        id,
        effort,
        progress,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidate(mass_kg: f64, frequency_hz: f64) -> Candidate {
        let mut c = Candidate::empty(Effect::of(&crate::effects::foundation::EFFECT));
        c.parameters = [
            ("mass_kg".to_string(), mass_kg),
            ("frequency_hz".to_string(), frequency_hz),
            ("damping_ratio".to_string(), 0.05),
        ]
        .into_iter()
        .collect();
        c
    }

    /// Issue 14 item 7: a 100 000 t foundation under a 41 t table is not a cause.
    #[test]
    fn an_unphysical_cause_is_rejected() {
        assert!(unphysical(&candidate(1e8, 10.0), 41_258.0).is_some());
        assert!(unphysical(&candidate(f64::NAN, 10.0), 41_258.0).is_some());
        assert!(unphysical(&candidate(5e5, 1e6), 41_258.0).is_some());
        assert!(unphysical(&candidate(5e5, 10.0), 41_258.0).is_none());
    }
}
