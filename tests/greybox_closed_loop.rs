//! The grey-box output-error identification of the closed loop (issue 16, part 3) on
//! campaigns the project's simulator made from tables unlike the TREES Lab one, stripped
//! to what a laboratory often has: the reference and the table's motion, no valve
//! command, spool or force, no gains and no geometry. The fit must recover what the
//! motion determines (the loop gain, the feed-forward ratio, the valve and the oil
//! column), say which parameters are held by convention, and predict the test it did not
//! see.

use shaketable::campaign::synth::{paper_program, synthesise_program, SynthOptions};
use shaketable::campaign::{Campaign, ControllerOverride, TestKind};
use shaketable::identify::identify;
use shaketable::params::ServovalveModel;
use shaketable::Params;

/// A table unlike the TREES Lab one: its loop gain, feed-forward, valve, mass and oil
/// column all differ from the defaults the conventions keep.
fn truth(variant: u64) -> Params {
    let mut p = Params::trees_lab();
    let v = variant as f64;
    p.controller.kp = 6.0 + 3.0 * v;
    p.controller.fv = 0.20 + 0.1 * v;
    // no delta-P feedback: the oil column damped by a leaky piston alone. With the
    // delta-P feedback on, the fit does not yet recover the loop gain within 5 % (20 %
    // measured; issue 16 continues), so this suite does not claim it.
    if variant < 2 {
        p.controller.kdp = 0.0;
        p.actuator.leakage_m3_s_pa *= 4.0 + 2.0 * v;
    } else {
        p.controller.kp = 5.0;
        p.table.mass_kg = 30_000.0;
        p.actuator.bulk_modulus_pa = 1.4e9;
    }
    p.servovalve.model = ServovalveModel::FirstOrder;
    p.servovalve.time_constant_s = 0.009 + 0.004 * v;
    p.table.mass_kg = 25_000.0 + 10_000.0 * v;
    p.actuator.bulk_modulus_pa = 1.6e9 - 0.3e9 * v;
    p.friction.force_n = 2_000.0;
    p
}

/// Two random displacement-control tests (different levels and bands) and one sine,
/// synthesised from `p`, then stripped of the valve, spool and force channels, the gains
/// and the geometry.
fn stripped_campaign(p: &Params, seed: u64) -> Campaign {
    let base = paper_program(30.0)[0].clone();
    let mut w1 = base.clone();
    w1.name = "W1".into();
    // the lightly damped oil column of a delta-P-fed table rings: a smaller level keeps
    // its load within the supply pressure
    let level = if p.controller.kdp > 0.0 { 0.4 } else { 1.0 };
    w1.rms = Some(0.0015 * level);
    w1.band_hz = Some([0.3, 25.0]);
    w1.controller = ControllerOverride::default();
    let mut w2 = w1.clone();
    w2.name = "W2".into();
    w2.rms = Some(0.002 * level);
    w2.band_hz = Some([0.3, 15.0]);
    let mut s1 = paper_program(30.0)[5].clone();
    assert_eq!(s1.kind, TestKind::Sine);
    s1.name = "S1".into();
    let opts = SynthOptions {
        seed,
        random_duration_s: 30.0,
        ..SynthOptions::default()
    };
    let program = vec![(0, w1), (1, w2), (5, s1)];
    synthesise_program(p, &program, &opts, None)
        .unwrap_or_else(|e| panic!("{e}"))
        .as_motion_only()
}

fn combination(id: &shaketable::identify::Identification, name: &str) -> (f64, f64) {
    let cl = id.closed_loop.as_ref().expect("a closed-loop fit");
    let c = cl
        .combinations
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no {name} in {:?}", cl.combinations));
    (c.value, c.sigma.unwrap_or(f64::NAN))
}

/// Relative tolerance of the valve bandwidth when the model's structure matches the table.
const VALVE_TOLERANCE: f64 = 0.10;
/// Relative tolerance of the oil-column frequency when the structure matches.
const OIL_COLUMN_TOLERANCE: f64 = 0.05;

#[test]
fn the_motion_alone_gives_the_loop_the_valve_and_the_oil_column() {
    recovers(0, VALVE_TOLERANCE, OIL_COLUMN_TOLERANCE);
}

/// A strong feed-forward (ratio 0.66), a slow valve (12 Hz) and a damped oil column at
/// 16 Hz: the low-band servo reading is bent by the valve's lag, and only the starts
/// read at 45 degrees with a feed-forward lead the fit to the table.
#[test]
fn a_strong_feed_forward_and_a_slow_valve() {
    recovers(1, VALVE_TOLERANCE, OIL_COLUMN_TOLERANCE);
}

/// The delta-P feedback on, its gain unknown: the fit holds it at zero and carries its
/// damping by the leakage (the structure's convention; freeing both sent the fit to a
/// loop gain 2.3 times too high). The delta-P path through the valve then has no
/// counterpart, and the valve and oil column become effective values: 12 % and 7 % off
/// measured, so they are held to 20 % and 10 % here; the loop gain and feed-forward to
/// the tolerances of a matching structure.
#[test]
fn a_delta_p_feedback_nobody_wrote_down() {
    recovers(2, 0.20, 0.10);
}

fn recovers(variant: u64, valve_tolerance: f64, oil_tolerance: f64) {
    {
        let p = truth(variant);
        let c = stripped_campaign(&p, 11 + variant);
        let id = identify(&c);
        let cl = id
            .closed_loop
            .as_ref()
            .unwrap_or_else(|| panic!("{:?}", id.missing));
        let loop_gain = p.controller.kp * p.actuator.flow_gain_m3_s / p.actuator.piston_area_m2;
        let ff = p.controller.fv * p.actuator.flow_gain_m3_s / p.actuator.piston_area_m2;
        let oil = shaketable::linear::OilColumn::of(&p);
        let valve_hz = 1.0 / (2.0 * std::f64::consts::PI * p.servovalve.time_constant_s);
        for (name, want, tol) in [
            ("loop_gain_1_s", loop_gain, 0.05),
            ("feed_forward_ratio", ff, 0.10),
            ("valve_bandwidth_hz", valve_hz, valve_tolerance),
            ("oil_column_frequency_hz", oil.frequency_hz, oil_tolerance),
        ] {
            let (got, sigma) = combination(&id, name);
            eprintln!("variant {variant}: {name} {got:.4} (sigma {sigma:.2e}) for {want:.4}");
            assert!(
                ((got - want) / want).abs() < tol,
                "variant {variant}: {name} = {got} for {want} (tolerance {tol})"
            );
            assert!(sigma.is_finite() && sigma > 0.0, "{name}: sigma {sigma}");
        }
        // a first-order valve's table is not given a second-order valve
        let order = cl.valve_order.as_ref().expect("the valve order chosen");
        assert_eq!(order.chosen, "first_order", "variant {variant}: {order:?}");
        // what the motion cannot tell is held and said so, not passed off as identified
        for key in ["table.mass_kg", "actuator.piston_area_m2", "controller.kv"] {
            assert!(
                cl.conventions.iter().any(|k| k.key == key),
                "{key} not listed among the conventions: {:?}",
                cl.conventions
            );
        }
        // the test it did not see is predicted
        let val: Vec<_> = cl
            .fits
            .iter()
            .filter(|f| f.role == shaketable::identify::greybox::Role::Validation)
            .collect();
        assert!(!val.is_empty(), "no validation test: {:?}", cl.fits);
        for f in val {
            eprintln!(
                "variant {variant}: {} {} fit {:.2} %",
                f.test, f.channel, f.fit_percent
            );
            assert!(f.fit_percent > 90.0, "{f:?}");
        }
    }
}

/// The TREES Lab table itself (a second-order valve at 20.5 Hz, damping 1.05, and the
/// delta-P feedback on), the paper's program (30-s random tests) stripped to its motion
/// (the three short tests of [`stripped_campaign`] do not pin the delta-P table: its
/// first-order fit there has a loop gain 2.8 times too high, and the second-order one
/// ends worse from that start): the data choose the second-order valve,
/// whose natural frequency then comes out within 10 % (the delta-P path through the
/// valve, held at zero, is carried by the leakage and bends it: 8 % measured), and the
/// loop gain and feed-forward as closely as for a matching structure. The first-order
/// valve left the loop gain 21 % high on this campaign (26.6 for 21.95).
#[test]
fn the_motion_tells_a_second_order_valve() {
    let p = Params::trees_lab();
    assert_eq!(p.servovalve.model, ServovalveModel::SecondOrder);
    let opts = SynthOptions {
        seed: 5,
        random_duration_s: 30.0,
        ..SynthOptions::default()
    };
    let program = shaketable::campaign::synth::selected_program(&opts);
    let c = synthesise_program(&p, &program, &opts, None)
        .unwrap_or_else(|e| panic!("{e}"))
        .as_motion_only();
    let id = identify(&c);
    let cl = id.closed_loop.as_ref().expect("a closed-loop fit");
    let order = cl.valve_order.as_ref().expect("the valve order chosen");
    eprintln!("{order:?}");
    for k in &cl.combinations {
        eprintln!("  {} {:.4} {:?}", k.name, k.value, k.sigma);
    }
    assert_eq!(order.chosen, "second_order", "{order:?}");
    assert!(order.second_order_cost.unwrap() < order.first_order_cost);
    let loop_gain = p.controller.kp * p.actuator.flow_gain_m3_s / p.actuator.piston_area_m2;
    let ff = p.controller.fv * p.actuator.flow_gain_m3_s / p.actuator.piston_area_m2;
    for (name, want, tol) in [
        ("loop_gain_1_s", loop_gain, 0.05),
        ("feed_forward_ratio", ff, 0.10),
        (
            "valve_natural_frequency_hz",
            p.servovalve.natural_frequency_hz,
            0.10,
        ),
    ] {
        let (got, sigma) = combination(&id, name);
        eprintln!("TREES Lab: {name} {got:.4} (sigma {sigma:.2e}) for {want:.4}");
        assert!(
            ((got - want) / want).abs() < tol,
            "{name} = {got} for {want}"
        );
    }
    assert_eq!(cl.params.servovalve.model, ServovalveModel::SecondOrder);
}
