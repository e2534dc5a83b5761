//! How hard a diagnosis works ([`Effort`]): every iteration cap and start count of its
//! fits in one place, for the full diagnosis and for the quick one of the development
//! loop (a change to the selection rules checked in seconds on a short campaign).

use crate::identify::lsq::LsqOptions;
use serde::Serialize;

/// How hard a diagnosis works. The quick one runs every step of the full one (baseline,
/// searches, selection, polish, acceptance) with fewer fit iterations: its numbers
/// are rougher and it is for checking a change to the pipeline, not for a decision.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Effort {
    #[default]
    Full,
    Quick,
}

/// Output-error iterations of the baseline's refinement: a baseline that lacks an effect
/// never converges, and 8 bring a clean campaign's to its noise floor.
const BASELINE_ITERATIONS: usize = 8;

/// The same for a baseline fitted to the motion ([`super::baseline::from_motion`]): the
/// closed-loop fit ran on excerpts and its estimation tests, and its parameters move far
/// on every test's fitting half (a clean 1-kHz campaign's cost fell 1600-fold from 8 to
/// 40 iterations); a baseline stopped short leaves its gain to whichever candidate
/// refines it further.
const MOTION_BASELINE_ITERATIONS: usize = 40;

/// The least-squares settings of the candidates' fits: 12 iterations bring an effect's
/// parameters from an informed start to its valley; the tolerances are relative. The
/// Jacobian's columns are computed in parallel: a search's last fits run alone, and
/// rayon lends them the cores the others left (each column is its own run, so the fit
/// is the same whatever the threads).
const CANDIDATE_LSQ: LsqOptions = LsqOptions {
    max_iterations: 12,
    tolerance: 1e-4,
    step: 1e-4,
    parallel: true,
};

/// Screened starts of a candidate fitted in full (besides the one read off the data): the
/// best two of its grid on both bases, as one valley is often a few percent from another.
const SCREENED_STARTS: usize = 2;

/// Output-error iterations of one polish of the best candidate.
const POLISH_ITERATIONS: usize = 6;

/// Polishing rounds of the best candidate at most.
const POLISH_ROUNDS: usize = 3;

/// The quick diagnosis's caps for the candidates: half the iterations of each fit stage
/// and of the polish, and one polish round. Its starts stay the full diagnosis's: with one
/// start and 3 iterations a 23-t specimen at 3.2 Hz was not found, and stick-slip absorbed
/// the misfit instead (seed 31 of `tests/diagnose_quick.rs`).
const QUICK_ITERATIONS: usize = CANDIDATE_LSQ.max_iterations / 2;
const QUICK_POLISH_ITERATIONS: usize = POLISH_ITERATIONS / 2;

impl Effort {
    /// Output-error iterations of the baseline's refinement, per actuator variant: the
    /// same for both efforts, as a baseline stopped short of its noise floor leaves cells
    /// "missed" that a candidate then absorbs (3 iterations left a clean campaign's force
    /// at 1.5 floor RMS, and stick-slip was named).
    pub(super) fn baseline_iterations(self, from_motion: bool) -> usize {
        if from_motion {
            MOTION_BASELINE_ITERATIONS
        } else {
            BASELINE_ITERATIONS
        }
    }

    /// The least-squares settings of each candidate's fit stages.
    pub(super) fn candidate_lsq(self) -> LsqOptions {
        match self {
            Effort::Full => CANDIDATE_LSQ,
            Effort::Quick => LsqOptions {
                max_iterations: QUICK_ITERATIONS,
                ..CANDIDATE_LSQ
            },
        }
    }

    /// Starts of a candidate's grid kept after screening (both efforts).
    pub(super) fn screened_starts(self) -> usize {
        SCREENED_STARTS
    }

    /// Output-error iterations of one polish.
    pub(super) fn polish_iterations(self) -> usize {
        match self {
            Effort::Full => POLISH_ITERATIONS,
            Effort::Quick => QUICK_POLISH_ITERATIONS,
        }
    }

    /// Polishing rounds at most.
    pub(super) fn polish_rounds(self) -> usize {
        match self {
            Effort::Full => POLISH_ROUNDS,
            Effort::Quick => 1,
        }
    }

    /// Its name in the JSON and the CLI.
    pub fn name(self) -> &'static str {
        match self {
            Effort::Full => "full",
            Effort::Quick => "quick",
        }
    }
}
