//! Unit tests of the selection rules of [`super`]: the verdict, the judged candidate, the
//! effects searched again.
use super::polish::explains;
use super::select::{best_candidate, spread_credited, verdict, CoherentSplit, Rule, Verdict};
use crate::diagnose::output::Candidate;
use crate::diagnose::{Effect, EXPLAINED_RATIO, REQUIRED_GAIN};

#[test]
fn a_candidate_explains_the_data_up_to_the_explained_ratio() {
    let mut c = Candidate::empty(Effect::of(&crate::effects::specimen::EFFECT));
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
            Effect::of(&crate::effects::valve_deadband::EFFECT),
            1.0,
            Some("deadband at its lower bound"),
        ),
        scored(Effect::of(&crate::effects::foundation::EFFECT), 2.0, None),
        scored(Effect::of(&crate::effects::specimen::EFFECT), 3.0, None),
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
    let mut c = Candidate::empty(Effect::of(&crate::effects::valve_deadband::EFFECT));
    c.score = 1.0;
    assert!(matches!(
        verdict(&c, REQUIRED_GAIN * 0.99, || 1.0, || None, 4e4),
        Verdict::NoGain
    ));
    assert!(matches!(
        verdict(&c, REQUIRED_GAIN, || 1.0, || None, 4e4),
        Verdict::Cause
    ));
    // a rough model whose score chance moves by 30 %: the gain is partial at most
    assert!(matches!(
        verdict(&c, 1.3 * REQUIRED_GAIN * 0.99, || 1.3, || None, 4e4),
        Verdict::Partial(_)
    ));
    assert!(matches!(
        verdict(&c, 1.3 * REQUIRED_GAIN, || 1.3, || None, 4e4),
        Verdict::Cause
    ));
    // chance is not measured for a gain that fails the plain rule
    assert!(matches!(
        verdict(&c, REQUIRED_GAIN * 0.99, || unreachable!(), || None, 4e4),
        Verdict::NoGain
    ));
    c.not_evidence = Some("at a bound".into());
    assert!(matches!(
        verdict(&c, 10.0, || 1.0, || None, 4e4),
        Verdict::Partial(_)
    ));
}

/// A mostly coherent residual (deterministic) must lose a tenth of its coherent power to
/// the cause; a mostly incoherent one (chatter, impacts) may be credited to spread unless
/// the cause leaves more than ten times the whole residual it is credited with as
/// coherent error.
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
    // a deadband on a sign-flipped valve command: 13 % coherent, but its run leaves 95
    // times the whole current residual as coherent error
    let why = spread_credited(&split(18.9, 146.2, 13909.0)).unwrap();
    assert!(why.contains("95.1 times"), "{why}");
    // a true free play: 74 % coherent, its run leaves 42 % of the whole (44 % removed)
    assert_eq!(spread_credited(&split(8.85e5, 1.19e6, 4.97e5)), None);
    // seed 703's 1.5-mm free play: 16 % coherent, its run leaves 1.03 times the whole
    assert_eq!(spread_credited(&split(1.061e4, 6.798e4, 6.975e4)), None);
    // no estimate at all (every test too short): nothing is claimed against it
    assert_eq!(spread_credited(&split(0.0, 0.0, 0.0)), None);
}

/// The rules are checked gain, chance, physics, evidence, spread: the order the verdicts
/// above rely on (each measurement taken only once the cheaper rules pass).
#[test]
fn the_rules_are_checked_in_their_order() {
    assert_eq!(
        Rule::ORDER,
        [
            Rule::Gain,
            Rule::Chance,
            Rule::Physical,
            Rule::Evidence,
            Rule::Spread
        ]
    );
}

/// A score that is not a number (a run that stopped) gains nothing.
#[test]
fn the_gain_rule_fails_a_score_that_is_not_a_number() {
    let c = Candidate::empty(Effect::of(&crate::effects::valve_deadband::EFFECT));
    assert!(matches!(
        verdict(&c, 10.0, || unreachable!(), || unreachable!(), 4e4),
        Verdict::NoGain
    ));
}

/// The chance rule says by which change of the table mass chance was measured.
#[test]
fn the_chance_rule_names_its_measurement() {
    let mut c = Candidate::empty(Effect::of(&crate::effects::valve_deadband::EFFECT));
    c.score = 1.0;
    let Verdict::Partial(why) = verdict(&c, 1.3, || 2.0, || unreachable!(), 4e4) else {
        panic!("a gain below twice the bar is partial");
    };
    assert!(why.contains("a 0.1 % change of the table mass"), "{why}");
}

/// An unphysical parameter makes the candidate partial before evidence and spread are read.
#[test]
fn the_physical_rule_comes_before_evidence_and_spread() {
    let mut c = Candidate::empty(Effect::of(&crate::effects::valve_deadband::EFFECT));
    c.score = 1.0;
    c.parameters.insert("deadband".into(), f64::NAN);
    c.not_evidence = Some("at a bound".into());
    let Verdict::Partial(why) = verdict(&c, 10.0, || 1.0, || unreachable!(), 4e4) else {
        panic!("an unphysical candidate is partial");
    };
    assert_ne!(why, "at a bound");
}

/// A candidate that is no evidence is partial with the reason, the spread not measured.
#[test]
fn the_evidence_rule_gives_its_reason() {
    let mut c = Candidate::empty(Effect::of(&crate::effects::valve_deadband::EFFECT));
    c.score = 1.0;
    c.not_evidence = Some("at a bound".into());
    let v = verdict(&c, 10.0, || 1.0, || unreachable!(), 4e4);
    assert!(matches!(v, Verdict::Partial(why) if why == "at a bound"));
}

/// A cause by every other rule is partial when its gain is credited to spread.
#[test]
fn the_spread_rule_comes_last() {
    let mut c = Candidate::empty(Effect::of(&crate::effects::valve_deadband::EFFECT));
    c.score = 1.0;
    let v = verdict(&c, 10.0, || 1.0, || Some("coherent".into()), 4e4);
    assert!(matches!(v, Verdict::Partial(why) if why == "coherent"));
    assert!(matches!(
        verdict(&c, 10.0, || 1.0, || None, 4e4),
        Verdict::Cause
    ));
}

/// A specimen's further modes are fitted unless another candidate already scores
/// [`super::FURTHER_MODES_WITHIN`] times better; a score that is not a number decides
/// nothing.
#[test]
fn further_modes_are_skipped_only_far_behind_another_candidate() {
    let k = super::FURTHER_MODES_WITHIN;
    assert!(super::further_modes_may_matter(0.7, 1.0));
    assert!(super::further_modes_may_matter(k * 1.0, 1.0));
    assert!(super::further_modes_may_matter(14.0, f64::INFINITY));
    assert!(super::further_modes_may_matter(f64::NAN, 1.0));
    // the 12-Hz foundation of seed 453: one mode at 14.1, the foundation at 0.67
    assert!(!super::further_modes_may_matter(14.084, 0.671));
}

/// The fits run longest first, but their results come back in the search's order, the
/// effects fitted to nothing left out.
#[test]
fn fits_started_longest_first_return_in_the_search_order() {
    let effects = Effect::search_order();
    let ranks: Vec<u8> = effects.iter().map(|e| e.fitting_rank()).collect();
    assert!(ranks.contains(&0) && ranks.contains(&2), "ranks {ranks:?}");
    let fitted = super::longest_first(&effects, |e| (e.fitting_rank() > 0).then(|| e.name()));
    let expected: Vec<&str> = effects
        .iter()
        .filter(|e| e.fitting_rank() > 0)
        .map(|e| e.name())
        .collect();
    assert_eq!(fitted, expected);
}
