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

/// A mostly coherent residual (deterministic) must lose a tenth of its coherent power to
/// the cause; a mostly incoherent one (chatter, impacts) may be credited to spread.
#[test]
fn a_deterministic_residual_is_not_credited_to_spread() {
    let split = |coherent: f64, total: f64, after: f64| CoherentSplit {
        current_coherent: coherent,
        current_total: total,
        candidate_coherent: after,
    };
    // the UTFSM damper's stick-slip: 97 % coherent, 1 % of it removed
    let why = spread_credited(&split(2.89e4, 2.99e4, 2.865e4)).unwrap();
    assert!(why.contains("97 %"), "{why}");
    // a true deadband beside a specimen: 89 % coherent, 47 % removed
    assert_eq!(spread_credited(&split(5.84e6, 6.60e6, 3.12e6)), None);
    // a true stick-slip: 3 % coherent, whatever its run does to that part
    assert_eq!(spread_credited(&split(3.3, 120.0, 3.3)), None);
    // no estimate at all (every test too short): nothing is claimed against it
    assert_eq!(spread_credited(&split(0.0, 0.0, 0.0)), None);
}
