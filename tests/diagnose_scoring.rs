//! The diagnosis' noise estimates and predictive score (issue 6): the sensor noise is
//! recovered from the data alone, also when stick-slip chatter fills the rest segments'
//! neighbourhood; the true model scores at the noise floor on held-out data, a model 2 %
//! off in mass does not; and a stick-slip truth, which a noise-free simulation cannot
//! follow sample by sample, scores better than the baseline under the predictive score.

use shaketable::campaign::synth::{synthesise, NoiseLevels, SynthOptions};
use shaketable::diagnose::residuals::{test_scores_in_envelope, Cell};
use shaketable::diagnose::{estimate_noise, predict, ratios, scores, Part};
use shaketable::Params;

fn campaign(p: &Params, seed: u64) -> shaketable::campaign::Campaign {
    let opts = SynthOptions {
        seed,
        random_duration_s: 30.0,
        ..SynthOptions::default()
    };
    synthesise(p, &opts, None)
}

/// What [`heldout`] averages.
#[derive(Clone, Copy, PartialEq)]
enum Measure {
    /// The predictive score (ranks models; not in noise units).
    Score,
    /// The standardised residual: residual power over the predicted spread.
    Standardised,
    /// The sample-wise residual over the noise floor.
    SampleWise,
}

/// RMS over every held-out cell of `measure`.
fn heldout(p: &Params, c: &shaketable::campaign::Campaign, measure: Measure) -> f64 {
    let noise = estimate_noise(c);
    let mut v = Vec::new();
    for i in 0..c.records.len() {
        let pred = predict(p, c, i, Part::Whole, &noise);
        let cells = || scores(c, i, &pred, &noise, Part::HeldOut);
        let row = match measure {
            Measure::SampleWise => ratios(&c.records[i], &pred.locked, &noise, Part::HeldOut),
            Measure::Score => cells().score,
            Measure::Standardised => cells().residual,
        };
        v.extend(row.values().filter_map(|x| x.finite()));
    }
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

#[test]
fn sensor_noise_is_recovered_from_the_data() {
    let truth = NoiseLevels::default();
    let mut stick = Params::trees_lab();
    stick
        .apply_effect_spec("stick_slip:static_ratio=3,stribeck_velocity_m_s=0.003")
        .unwrap();
    for p in [Params::trees_lab(), stick] {
        let n = estimate_noise(&campaign(&p, 11));
        let s = n.sensor;
        for (got, want, what) in [
            (s.displacement_m, truth.displacement_m, "displacement"),
            (s.acceleration_m_s2, truth.acceleration_m_s2, "acceleration"),
            (s.force_n, truth.force_n, "force"),
            (s.spool, truth.spool, "spool"),
        ] {
            let got = got.unwrap_or_else(|| panic!("{what}: recorded, yet no level"));
            // 18 records of >= 32 s each: the median's sampling error is well below 1 %;
            // 3 % leaves room for the table's own content above 100 Hz in R1 and R3
            assert!(
                (got / want - 1.0).abs() < 0.03,
                "{what}: estimated {got}, generated {want}"
            );
        }
        // the floor (what a noise-free model cannot predict at rest) holds the loop's
        // response to the noise as well, so it is never below the sensor noise
        assert!(n.force_n >= s.force_n && n.acceleration_m_s2 >= s.acceleration_m_s2);
        assert!(n.force_n.is_some() && n.acceleration_m_s2.is_some());
    }
}

#[test]
fn the_true_model_scores_at_the_floor_and_a_wrong_one_does_not() {
    let p = Params::trees_lab();
    let c = campaign(&p, 12);
    let truth = heldout(&p, &c, Measure::Standardised);
    let mut heavy = p;
    heavy.table.mass_kg *= 1.02;
    let wrong = heldout(&heavy, &c, Measure::Standardised);
    let (truth_score, wrong_score) = (
        heldout(&p, &c, Measure::Score),
        heldout(&heavy, &c, Measure::Score),
    );
    eprintln!(
        "held-out standardised residual: truth {truth:.3}, mass +2 % {wrong:.3}; \
         score: truth {truth_score:.3}, mass +2 % {wrong_score:.3}"
    );
    // the spread is predicted with the noise the loop saw, so the true model's residual
    // is its own predicted spread: within 15 % of 1 (windows of 8 degrees of freedom per
    // octave band)
    assert!(truth > 0.85 && truth < 1.15, "truth {truth}");
    assert!(wrong > 1.5 * truth, "mass +2 %: {wrong} vs truth {truth}");
    assert!(
        wrong_score > 1.5 * truth_score,
        "score, mass +2 %: {wrong_score} vs truth {truth_score}"
    );
}

#[test]
fn stick_slip_chatter_is_judged_by_its_spread_not_its_phase() {
    let mut truth = Params::trees_lab();
    truth
        .apply_effect_spec("stick_slip:static_ratio=3,stribeck_velocity_m_s=0.003")
        .unwrap();
    let c = campaign(&truth, 13);
    let base = Params::trees_lab();
    let (t_score, b_score) = (
        heldout(&truth, &c, Measure::Score),
        heldout(&base, &c, Measure::Score),
    );
    let (t_ratio, b_ratio) = (
        heldout(&truth, &c, Measure::SampleWise),
        heldout(&base, &c, Measure::SampleWise),
    );
    eprintln!("score: truth {t_score:.2}, baseline {b_score:.2}; sample-wise: truth {t_ratio:.2}, baseline {b_ratio:.2}");
    // sample by sample, the true model's chatter has the wrong phase: it does no better
    // than the baseline, which has none
    assert!(
        t_ratio > 0.8 * b_ratio,
        "sample-wise {t_ratio} vs {b_ratio}"
    );
    // under the predictive score the truth wins clearly
    assert!(b_score > 1.5 * t_score, "score {t_score} vs {b_score}");
}

/// Spec section 8 in the diagnosis: a trial model whose held-out run leaves the operating
/// envelope (here a stroke of 2 cm, which the 5-cm sines pass) where the measured table
/// did not scores infinitely bad on that test, while the same model inside a wide
/// envelope scores finitely; tests it stays inside of keep their finite scores; and where
/// the measured table itself passed the limit, the model following it is not penalised.
#[test]
fn a_trial_model_outside_the_envelope_scores_infinitely_bad() {
    let p = Params::trees_lab();
    let opts = SynthOptions {
        seed: 11,
        random_duration_s: 12.0,
        tests: Some(vec!["S3".into(), "R2".into()]),
        ..SynthOptions::default()
    };
    let mut c = synthesise(&p, &opts, None);
    let noise = estimate_noise(&c);
    let s3 = c.info.tests.iter().position(|t| t.name == "S3").unwrap();
    let r2 = c.info.tests.iter().position(|t| t.name == "R2").unwrap();
    let inside = test_scores_in_envelope(&p, &c, s3, Part::HeldOut, &noise);
    let finite = |x: &Cell| x.finite().is_some();
    assert!(inside.score.values().any(finite), "{inside:?}");
    let mut narrow = p;
    narrow.limits.stroke_m = 0.02;
    // the measured S3 passed 2.2 cm too: the model follows the table, no penalty
    let followed = test_scores_in_envelope(&narrow, &c, s3, Part::HeldOut, &noise);
    assert!(followed.score.values().all(finite), "{followed:?}");
    // a table whose LVDT stayed within 2 cm: the model's 5 cm leave its envelope
    let lvdt = c.records[s3].displacement_m.as_mut().unwrap();
    lvdt.iter_mut().for_each(|x| *x *= 0.3);
    let outside = test_scores_in_envelope(&narrow, &c, s3, Part::HeldOut, &noise);
    assert!(
        outside.score.values().all(|x| *x == Cell::Diverged),
        "{outside:?}"
    );
    assert!(outside.residual.values().all(|x| *x == Cell::Diverged));
    // R2 (0.1 g random, millimetres of stroke) stays inside even the narrow envelope
    let r2_narrow = test_scores_in_envelope(&narrow, &c, r2, Part::HeldOut, &noise);
    assert!(r2_narrow.score.values().any(finite), "{r2_narrow:?}");
}

/// The worst held-out cell (selection and report quarters, standardised residual) of the
/// true model `p` on `c` with `draws` noisy runs per prediction.
fn worst_true_cell(p: &Params, c: &shaketable::campaign::Campaign, draws: usize) -> f64 {
    use shaketable::diagnose::residuals::predict_draws;
    let noise = estimate_noise(c);
    let mut worst: f64 = 0.0;
    for i in 0..c.records.len() {
        let pred = predict_draws(p, c, i, Part::Whole, &noise, draws);
        for part in [Part::Select, Part::Report] {
            let cells = scores(c, i, &pred, &noise, part).residual;
            worst = cells
                .values()
                .filter_map(|x| x.finite())
                .fold(worst, f64::max);
        }
    }
    worst
}

/// The true model explains every held-out cell by the rule of `explained` (at most 2.0)
/// with the held-out quarters' noise draws (`HELDOUT_REALISATIONS`): one draw misjudges
/// the power of noise-driven bursts (the fastest sine's low bands, chatter), and on full
/// campaigns left the truth's worst cell at 2.52 and 2.76 (stop 49). Campaigns of several
/// effects and seeds; the one-draw figure is printed beside. The chaotic ones too: a free
/// play's impacts (seed 16, 0.54 mm: worst cell 1.46) and stick-slip chatter on a 6-t
/// table at its 37-Hz oil column (seed 22: 1.50), whose fitted models the diagnosis
/// leaves `explained: false` (stop 55): their misses are the fit's, not the rule's.
#[test]
fn the_true_model_explains_every_heldout_cell() {
    use shaketable::diagnose::residuals::HELDOUT_REALISATIONS;
    let trees = Params::trees_lab().table.mass_kg;
    let cases = [
        (451, trees, ""),
        (458, trees, "flow_asymmetry:ratio=1.25"),
        (454, trees, "stick_slip:static_ratio=2.5"),
        (452, trees, "specimen:mass_kg=15000,frequency_hz=4.5"),
        (16, trees, "free_play:gap_m=0.00054"),
        (22, 6000.0, "stick_slip:static_ratio=2.5"),
    ];
    for (seed, table_kg, effect) in cases {
        let mut p = Params::trees_lab();
        p.table.mass_kg = table_kg;
        if !effect.is_empty() {
            p.apply_effect_spec(effect).unwrap();
        }
        let c = campaign(&p, seed);
        let one = worst_true_cell(&p, &c, 1);
        let several = worst_true_cell(&p, &c, HELDOUT_REALISATIONS);
        eprintln!("seed {seed} {effect}: worst cell {one:.3} with one draw, {several:.3} with {HELDOUT_REALISATIONS}");
        assert!(
            several <= 2.0,
            "seed {seed} {effect}: the truth's worst cell {several}"
        );
    }
}
