//! Unit tests of the selection rules of [`super`]: the verdict, the judged candidate, the
//! effects searched again.
use super::*;

#[test]
fn a_candidate_explains_the_data_up_to_the_explained_ratio() {
    let mut c = Candidate::empty(Effect::Specimen);
    c.select_residual = EXPLAINED_RATIO;
    assert!(explains(&c));
    c.select_residual = EXPLAINED_RATIO * 1.001;
    assert!(!explains(&c));
}

/// A search judges the best candidate that is evidence, not a better-scoring empty one.
#[test]
fn the_best_candidate_is_the_best_that_is_evidence() {
    let scored = |e: Effect, score: f64, why: Option<&str>| {
        let mut c = Candidate::empty(e);
        c.score = score;
        c.not_evidence = why.map(str::to_string);
        c
    };
    let mut cands = vec![
        scored(
            Effect::ValveDeadband,
            1.0,
            Some("deadband at its lower bound"),
        ),
        scored(Effect::Foundation, 2.0, None),
        scored(Effect::Specimen, 3.0, None),
    ];
    assert_eq!(best_candidate(&cands, 4e4), Some(1));
    cands[1].not_evidence = Some("at a bound".into());
    cands[2].not_evidence = Some("at a bound".into());
    assert_eq!(best_candidate(&cands, 4e4), Some(0));
    assert_eq!(best_candidate(&[], 4e4), None);
}

/// The model a candidate extends, scored `score`, its noise-free run 3 noise RMS off.
fn standing(score: f64) -> Standing {
    Standing {
        score,
        deviation: 3.0,
    }
}

/// A cause needs the gain on the selection quarter, beyond what chance moves the score
/// by, physics and evidence; a candidate with the gain but no evidence is partial.
#[test]
fn the_verdict_needs_gain_physics_and_evidence() {
    let mut c = Candidate::empty(Effect::ValveDeadband);
    c.score = 1.0;
    c.select_deviation = 2.0;
    assert!(matches!(
        verdict(&c, standing(REQUIRED_GAIN * 0.99), || 1.0, 4e4),
        Verdict::NoGain
    ));
    assert!(matches!(
        verdict(&c, standing(REQUIRED_GAIN), || 1.0, 4e4),
        Verdict::Cause
    ));
    // a rough model whose score chance moves by 30 %: the gain is partial at most
    assert!(matches!(
        verdict(&c, standing(1.3 * REQUIRED_GAIN * 0.99), || 1.3, 4e4),
        Verdict::Partial(_)
    ));
    assert!(matches!(
        verdict(&c, standing(1.3 * REQUIRED_GAIN), || 1.3, 4e4),
        Verdict::Cause
    ));
    // chance is not measured for a gain that fails the plain rule
    assert!(matches!(
        verdict(&c, standing(REQUIRED_GAIN * 0.99), || unreachable!(), 4e4),
        Verdict::NoGain
    ));
    c.not_evidence = Some("at a bound".into());
    assert!(matches!(
        verdict(&c, standing(10.0), || 1.0, 4e4),
        Verdict::Partial(_)
    ));
}

/// A candidate that divides the score only by the spread it predicts, its noise-free run
/// no closer to the records than the model it extends (the UTFSM damper's stick-slip), is
/// partial however large its gain; any step closer passes.
#[test]
fn a_cause_must_bring_its_noise_free_run_closer() {
    let mut c = Candidate::empty(Effect::StickSlip);
    c.score = 1.0;
    c.select_deviation = 3.0;
    let Verdict::Partial(why) = verdict(&c, standing(10.0), || 1.0, 4e4) else {
        panic!("a cause at the same sample-wise residual");
    };
    assert!(why.contains("spread"), "{why}");
    c.select_deviation = 3.1;
    assert!(matches!(
        verdict(&c, standing(10.0), || 1.0, 4e4),
        Verdict::Partial(_)
    ));
    c.select_deviation = 2.9;
    assert!(matches!(
        verdict(&c, standing(10.0), || 1.0, 4e4),
        Verdict::Cause
    ));
    // a candidate without a figure there (NaN) is no cause either
    c.select_deviation = f64::NAN;
    assert!(matches!(
        verdict(&c, standing(10.0), || 1.0, 4e4),
        Verdict::Partial(_)
    ));
}
