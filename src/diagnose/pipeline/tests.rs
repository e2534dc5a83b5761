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

/// A cause needs the gain on the selection quarter, beyond what chance moves the score
/// by, physics and evidence; a candidate with the gain but no evidence is partial.
#[test]
fn the_verdict_needs_gain_physics_and_evidence() {
    let mut c = Candidate::empty(Effect::ValveDeadband);
    c.score = 1.0;
    assert!(matches!(
        verdict(&c, REQUIRED_GAIN * 0.99, || 1.0, 4e4),
        Verdict::NoGain
    ));
    assert!(matches!(
        verdict(&c, REQUIRED_GAIN, || 1.0, 4e4),
        Verdict::Cause
    ));
    // a rough model whose score chance moves by 30 %: the gain is partial at most
    assert!(matches!(
        verdict(&c, 1.3 * REQUIRED_GAIN * 0.99, || 1.3, 4e4),
        Verdict::Partial(_)
    ));
    assert!(matches!(
        verdict(&c, 1.3 * REQUIRED_GAIN, || 1.3, 4e4),
        Verdict::Cause
    ));
    // chance is not measured for a gain that fails the plain rule
    assert!(matches!(
        verdict(&c, REQUIRED_GAIN * 0.99, || unreachable!(), 4e4),
        Verdict::NoGain
    ));
    c.not_evidence = Some("at a bound".into());
    assert!(matches!(
        verdict(&c, 10.0, || 1.0, 4e4),
        Verdict::Partial(_)
    ));
}
