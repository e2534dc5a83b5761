//! The solver: determinism, the Bouc-Wen bound, the delay valve's history.

use shaketable::params::{ActuatorModel, ServovalveModel};
use shaketable::solver::DEFAULT_MAX_SUBSTEP_S;
use shaketable::{simulate_record, Model, Params};

/// One reading of a sample.
type Reading = fn(&shaketable::Outputs) -> f64;

mod common;
use common::{sine, FS};

#[test]
fn runs_are_bit_identical() {
    let mut p = Params::trees_lab();
    p.actuator.model = ActuatorModel::Nonlinear;
    p.stick_slip.enabled = true;
    let m = Model::new(&p);
    let r = sine(0.05, 1.0, 5.0);
    let a = simulate_record(&m, &r, FS, None, DEFAULT_MAX_SUBSTEP_S).unwrap();
    let b = simulate_record(&m, &r, FS, None, DEFAULT_MAX_SUBSTEP_S).unwrap();
    assert!(a.iter().zip(&b).all(|(x, y)| x.actuator_force_n.to_bits()
        == y.actuator_force_n.to_bits()
        && x.displacement_m.to_bits() == y.displacement_m.to_bits()));
}

#[test]
fn bouc_wen_z_stays_in_unit_interval() {
    // Fast motion with a tiny yield displacement drives Z hard against +-1.
    let mut p = Params::trees_lab();
    p.friction.yield_displacement_m = 1e-5;
    p.friction.shape = 0.0;
    let m = Model::new(&p);
    let mut sim = shaketable::Simulator::new(m, 0.0, DEFAULT_MAX_SUBSTEP_S);
    let r = sine(0.1, 2.0, 3.0);
    let zero = Default::default();
    let mut max_z: f64 = 0.0;
    for k in 0..r.len() - 1 {
        sim.advance(1.0 / FS, &r[k], &r[k + 1], &zero);
        let z = sim.state[shaketable::model::ix::Z];
        assert!((-1.0..=1.0).contains(&z), "Z = {z}");
        max_z = max_z.max(z.abs());
    }
    assert!(
        max_z > 0.999,
        "Z never saturated ({max_z}): the check would be vacuous"
    );
}

#[test]
fn delay_valve_spool_is_the_delayed_command() {
    // Spec section 3: x_v(t) = Ks u(t - tau). tau = 4 samples exactly so no interpolation.
    let mut p = Params::trees_lab();
    p.servovalve.model = ServovalveModel::Delay;
    p.servovalve.time_constant_s = 4.0 / FS;
    p.servovalve.gain = 0.9;
    let m = Model::new(&p);
    let out = simulate_record(&m, &sine(0.02, 3.0, 2.0), FS, None, DEFAULT_MAX_SUBSTEP_S).unwrap();
    let scale = out
        .iter()
        .map(|o| o.valve_command.abs())
        .fold(0.0, f64::max);
    assert!(scale > 0.01);
    for k in 4..out.len() {
        let expected = 0.9 * out[k - 4].valve_command;
        assert!(
            (out[k].spool_position - expected).abs() < 1e-9 * scale,
            "sample {k}: spool {} vs delayed command {expected}",
            out[k].spool_position
        );
    }
    for o in &out[..4] {
        assert_eq!(
            o.spool_position, 0.0,
            "before tau the valve has seen no command"
        );
    }
}

/// RMS of `a - b` over RMS of `a`.
fn relative_rms_change(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    let den: f64 = a.iter().map(|x| x * x).sum();
    (num / den).sqrt()
}

/// Issue 3, part 4: halving the sub-step changes every output of a full random test of the
/// paper program (R2: 0.1 g, 0.5-50 Hz; R3: 0.05 g, 0.5-125 Hz; 92 s each) by less than
/// 1e-6 of its RMS, for the default model and the nonlinear + specimen + foundation model.
#[test]
fn halving_the_substep_changes_outputs_by_less_than_1e_6_of_rms() {
    use shaketable::campaign::synth;
    for test in ["R2", "R3"] {
        let spec = synth::paper_program(90.0)
            .into_iter()
            .find(|t| t.name == test)
            .unwrap();
        let r = synth::reference(&spec, 2, 11, 90.0, FS).unwrap();
        let inputs = common::inputs_of(&r);
        for (name, params) in shaketable::benchmark::models() {
            let m = Model::new(&params);
            let a = simulate_record(&m, &inputs, FS, None, DEFAULT_MAX_SUBSTEP_S).unwrap();
            let b = simulate_record(&m, &inputs, FS, None, DEFAULT_MAX_SUBSTEP_S / 2.0).unwrap();
            let channels: [(&str, Reading); 6] = [
                ("valve_command", |o| o.valve_command),
                ("spool_position", |o| o.spool_position),
                ("displacement", |o| o.displacement_m),
                ("acceleration", |o| o.acceleration_m_s2),
                ("force", |o| o.actuator_force_n),
                ("pressure_a", |o| o.pressure_a_pa - 14e6),
            ];
            for (channel, f) in channels {
                let xa: Vec<f64> = a.iter().map(f).collect();
                let xb: Vec<f64> = b.iter().map(f).collect();
                let change = relative_rms_change(&xa, &xb);
                assert!(
                    change < 1e-6,
                    "{test}, {name}: {channel} changes by {change:.2e} of its RMS"
                );
            }
        }
    }
}

/// A valve far faster than the sub-step (1 kHz at one sub-step a sample, 1/512 s: h w =
/// 12, beyond RK4's stability limit of 2.78, as a fitted overdamped valve can be in the
/// diagnosis' runs) is integrated stably: the sub-steps follow the fastest pole at rest
/// ([`shaketable::solver::POLE_STEP`]). Its run matches one at a sub-step 30 times finer
/// to within 1e-4 of the displacement's RMS (the fast mode is over within a sub-step).
#[test]
fn a_valve_faster_than_the_sub_step_is_integrated_stably() {
    let mut q = Params::trees_lab();
    q.servovalve.natural_frequency_hz = 1000.0;
    let r = sine(0.01, 1.0, 5.0);
    let out = simulate_record(&Model::new(&q), &r, FS, None, 1.0 / FS).expect("no stop");
    let fine = simulate_record(&Model::new(&q), &r, FS, None, 1.0 / FS / 30.0).unwrap();
    let x: Vec<f64> = out.iter().map(|o| o.displacement_m).collect();
    let y: Vec<f64> = fine.iter().map(|o| o.displacement_m).collect();
    let change = relative_rms_change(&x, &y);
    assert!(
        change < 1e-4,
        "the two runs differ by {change:.2e} of the RMS"
    );
}

/// An unstable loop (a displacement gain 300 times the TREES Lab table's) is stopped when
/// the table outruns ten times its valve's full-opening speed: the run returns
/// [`shaketable::Diverged`], saying when, with the finite readings before, rather than the
/// Bouc-Wen guard refining sub-steps of a meaningless state for minutes.
#[test]
fn an_unstable_run_is_stopped_and_marked() {
    let p = Params::trees_lab();
    let r = sine(0.01, 1.0, 5.0);
    let stable = simulate_record(&Model::new(&p), &r, FS, None, DEFAULT_MAX_SUBSTEP_S);
    assert!(stable.is_ok(), "{:?}", stable.err());
    let mut q = p;
    q.controller.kp *= 300.0;
    assert!(!shaketable::linear::Linearisation::new(&q)
        .unstable_poles()
        .unwrap()
        .is_empty());
    let stop = simulate_record(&Model::new(&q), &r, FS, None, DEFAULT_MAX_SUBSTEP_S)
        .expect_err("the loop diverges");
    let t = stop.time_s;
    assert!(t > 0.0 && t < 5.0, "diverged at {t} s");
    let k = (t * FS).round() as usize;
    assert_eq!((stop.sample(), stop.samples), (k, r.len()));
    assert!(
        stop.reason.contains(&format!("t = {t} s")),
        "{}",
        stop.reason
    );
    assert!(stop.outputs.iter().all(|o| o.displacement_m.is_finite()));
}
