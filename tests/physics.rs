//! Physics moves the right way (issue 3): each catalogue effect of spec section 7 leaves
//! the signature its physics predicts, in the simulator and in the linear analysis.

mod common;
use common::{inputs_of, sine, FS};
use shaketable::campaign::synth;
use shaketable::identify::frf::{Welch, WelchOptions};
use shaketable::linear::Linearisation;
use shaketable::model::{ix, Inputs, SensorNoise};
use shaketable::params::ActuatorModel;
use shaketable::solver::DEFAULT_MAX_SUBSTEP_S;
use shaketable::{simulate_record, Model, Outputs, Params, Simulator};

/// The run of `p` on `inputs`: every physics test's run stays in the envelope.
fn run(p: &Params, inputs: &[Inputs]) -> Vec<Outputs> {
    simulate_record(&Model::new(p), inputs, FS, None, DEFAULT_MAX_SUBSTEP_S)
        .unwrap_or_else(|stop| panic!("{stop}"))
}

fn max_abs(x: impl Iterator<Item = f64>) -> f64 {
    x.fold(0.0, |m, v| m.max(v.abs()))
}

/// Index of the largest/smallest |h| within `[lo, hi]` Hz.
fn extremum(f: &[f64], h: &[f64], lo: f64, hi: f64, largest: bool) -> f64 {
    let mut best = (f64::NAN, if largest { f64::MIN } else { f64::MAX });
    for k in 0..f.len() {
        if f[k] >= lo && f[k] <= hi && ((largest && h[k] > best.1) || (!largest && h[k] < best.1)) {
            best = (f[k], h[k]);
        }
    }
    best.0
}

/// Small random test (0.05 m/s^2 RMS, 0.5-50 Hz, 128 s) and the Welch estimate of the
/// apparent mass, table acceleration -> actuator force (paper 4.1.2).
fn apparent_mass(p: &Params) -> (Vec<f64>, Vec<f64>) {
    let mut spec = synth::paper_program(128.0)
        .into_iter()
        .find(|t| t.name == "R2")
        .unwrap();
    spec.rms = Some(0.05);
    let r = synth::reference(&spec, 1, 5, 128.0, FS).unwrap();
    let out = run(p, &inputs_of(&r));
    let acc: Vec<f64> = out.iter().map(|o| o.acceleration_m_s2).collect();
    let force: Vec<f64> = out.iter().map(|o| o.actuator_force_n).collect();
    let w = Welch::new(FS, WelchOptions::for_resolution(FS, 0.125)).unwrap();
    let e = w.frf(&acc, &force).unwrap();
    (e.frequency_hz, e.h1.iter().map(|z| z.norm()).collect())
}

/// A specimen (m_s, f_s) on the rigid table makes the apparent mass `M + m_s H_s(s)`:
/// a resonance at f_s and an anti-resonance at `f_s sqrt(1 + m_s/M)`. Both appear in the
/// simulated data and in the analytic acceleration -> force TF; without the specimen
/// the apparent mass is flat (M within a few % from 2 to 12 Hz).
#[test]
fn specimen_adds_a_resonance_antiresonance_pair() {
    let mut p = Params::trees_lab();
    let (fs, ms) = (6.0, 20_000.0);
    p.specimen.enabled = true;
    p.specimen.mass_kg = ms;
    p.specimen.frequency_hz = fs;
    p.specimen.damping_ratio = 0.02;
    let anti = fs * (1.0 + ms / p.table.mass_kg).sqrt();
    let (f, m) = apparent_mass(&p);
    let peak = extremum(&f, &m, 2.0, 12.0, true);
    let notch = extremum(&f, &m, peak, 12.0, false);
    eprintln!("specimen: simulated resonance {peak} Hz, anti-resonance {notch} Hz (expected {fs}, {anti:.3})");
    assert!((peak - fs).abs() <= 0.25, "resonance at {peak} Hz");
    assert!(
        (notch - anti).abs() <= 0.25,
        "anti-resonance at {notch} Hz, expected {anti}"
    );
    let lin = Linearisation::new(&p);
    let grid = shaketable::linear::linear_grid(2.0, 12.0, 0.01);
    let mag: Vec<f64> = grid
        .iter()
        .map(|&x| lin.acceleration_to_force(x).norm())
        .collect();
    let peak = extremum(&grid, &mag, 2.0, 12.0, true);
    let notch = extremum(&grid, &mag, peak, 12.0, false);
    assert!((peak - fs).abs() <= 0.05, "analytic resonance at {peak} Hz");
    // friction's pre-sliding stiffness F_mu/Y lowers the apparent mass by F_mu/(Y w^2),
    // about 2 t at 7 Hz, which raises the anti-resonance by about 0.07 Hz
    assert!(
        (notch - anti).abs() <= 0.12,
        "analytic anti-resonance at {notch} Hz"
    );
    // bare table: the simulated apparent mass is the analytic one (M less the friction's
    // pre-sliding stiffness F_mu/(Y w^2)), with no resonance; below 4 Hz the displacement
    // is large enough for the friction to slide, which the linearisation does not hold
    let bare = Params::trees_lab();
    let lin = Linearisation::new(&bare);
    let (f, m) = apparent_mass(&bare);
    for k in 0..f.len() {
        if (4.0..=12.0).contains(&f[k]) {
            let dev = m[k] / lin.acceleration_to_force(f[k]).norm() - 1.0;
            assert!(
                dev.abs() < 0.05,
                "bare table apparent mass {} kg at {} Hz",
                m[k],
                f[k]
            );
        }
    }
}

/// A compliant foundation adds a lightly damped closed-loop mode that the rigid one does
/// not have, and the LVDT (table relative to the reaction mass) then differs from the
/// table's absolute displacement; with a rigid foundation they are identical.
#[test]
fn foundation_adds_a_resonance_and_separates_lvdt_from_absolute() {
    let mut p = Params::trees_lab();
    p.foundation.enabled = true;
    p.foundation.mass_kg = 3e5;
    p.foundation.frequency_hz = 20.0;
    p.foundation.damping_ratio = 0.03;
    let oscillatory = |p: &Params| {
        Linearisation::new(p)
            .poles()
            .unwrap()
            .into_iter()
            .filter(|q| q.im > 0.0 && -q.re / q.norm() < 0.3)
            .map(|q| q.norm() / (2.0 * std::f64::consts::PI))
            .collect::<Vec<f64>>()
    };
    let bare = oscillatory(&Params::trees_lab());
    let with = oscillatory(&p);
    eprintln!("lightly damped modes: rigid {bare:?} Hz, compliant {with:?} Hz");
    assert_eq!(with.len(), bare.len() + 1, "one more lightly damped mode");
    // LVDT vs absolute displacement in a 15 Hz sine near the foundation mode
    let inputs = sine(0.01, 15.0, 4.0);
    for (params, differs) in [(Params::trees_lab(), false), (p, true)] {
        let mut sim = Simulator::new(Model::new(&params), 0.0, DEFAULT_MAX_SUBSTEP_S);
        let (mut diff, mut abs) = (0.0f64, 0.0f64);
        for k in 0..inputs.len() - 1 {
            sim.advance(
                1.0 / FS,
                &inputs[k],
                &inputs[k + 1],
                &SensorNoise::default(),
            );
            let lvdt = sim
                .outputs(&inputs[k + 1], &SensorNoise::default())
                .displacement_m;
            diff = diff.max((lvdt - sim.state[ix::X]).abs());
            abs = abs.max(sim.state[ix::X].abs());
        }
        eprintln!("foundation {differs}: max |LVDT - absolute| = {diff:.3e} m of {abs:.3e} m");
        if differs {
            assert!(
                diff > 0.05 * abs,
                "LVDT differs by only {diff} m of {abs} m"
            );
        } else {
            assert_eq!(diff, 0.0);
        }
    }
}

/// Largest mean speed over any window of `window_s` (stroke change / time).
fn max_mean_speed(out: &[Outputs], window_s: f64) -> f64 {
    let w = (window_s * FS) as usize;
    (0..out.len() - w)
        .map(|k| (out[k + w].displacement_m - out[k].displacement_m).abs() / (w as f64 / FS))
        .fold(0.0, f64::max)
}

/// `amplitude_m (1 - cos(w t))`: a sine that starts at rest, with consistent derivatives.
fn from_rest(amplitude_m: f64, frequency_hz: f64, seconds: f64) -> Vec<Inputs> {
    let w = 2.0 * std::f64::consts::PI * frequency_hz;
    sine(amplitude_m, frequency_hz, seconds)
        .into_iter()
        .enumerate()
        .map(|(k, mut x)| {
            let c = (w * k as f64 / FS).cos();
            x.reference.displacement_m = amplitude_m * (1.0 - c);
            x.reference.velocity_m_s = amplitude_m * w * (w * k as f64 / FS).sin();
            x.reference.acceleration_m_s2 = amplitude_m * w * w * c;
            x
        })
        .collect()
}

/// Flow saturation caps the table velocity at `Q_max / A` in a sine that demands more,
/// while the spool still follows the command past the saturated opening. The cap holds
/// for the mean speed: where the flow switches from `+Q_max` to `-Q_max` faster than the
/// 14 Hz oil column, the column rings around `Q_max / A` (as the spec's equations say),
/// so the test reads the stroke over 0.5 s windows (7 oil-column periods; the oil-column
/// compression `V_t dP_L / (4 beta A)` is under 5 mm, i.e. < 2 % of the cap over 0.5 s).
#[test]
fn flow_saturation_caps_velocity() {
    for actuator in [ActuatorModel::Ideal, ActuatorModel::Nonlinear] {
        let mut p = Params::trees_lab();
        p.actuator.model = actuator;
        p.flow_saturation.enabled = true;
        p.flow_saturation.max_flow_m3_s = 0.05;
        let cap = 0.05 / p.actuator.piston_area_m2;
        // 0.2 (1 - cos) m at 1 Hz demands 1.26 m/s from rest: the reference starts with
        // zero velocity, so the unsaturated table does not start with a velocity step
        // (which drives the load pressure past the relief level, spec section 8)
        let inputs = from_rest(0.2, 1.0, 6.0);
        let out = run(&p, &inputs);
        let steady = &out[out.len() / 3..];
        let v = max_mean_speed(steady, 0.5);
        let spool = max_abs(steady.iter().map(|o| o.spool_position));
        eprintln!("{actuator:?}: max mean speed {v:.4} m/s, cap {cap:.4} m/s, spool {spool:.3}");
        assert!(
            v <= 1.04 * cap && v >= 0.9 * cap,
            "{actuator:?}: {v} m/s vs cap {cap}"
        );
        assert!(
            spool * p.actuator.flow_gain_m3_s > 1.5 * 0.05,
            "spool {spool} did not pass the cap"
        );
        let free = run(
            &Params {
                actuator: p.actuator,
                ..Params::trees_lab()
            },
            &inputs,
        );
        let vf = max_mean_speed(&free[free.len() / 3..], 0.5);
        assert!(vf > 1.5 * cap, "unsaturated table only reaches {vf}");
    }
}

/// A deadband larger than the spool excursion gives zero flow: the table does not move,
/// while the same reference moves a table without deadband.
#[test]
fn deadband_blocks_small_commands() {
    let inputs = sine(0.001, 0.5, 4.0);
    let mut p = Params::trees_lab();
    p.valve_deadband.enabled = true;
    p.valve_deadband.deadband = 0.05;
    for actuator in [ActuatorModel::Ideal, ActuatorModel::Nonlinear] {
        p.actuator.model = actuator;
        let out = run(&p, &inputs);
        let x = max_abs(out.iter().map(|o| o.displacement_m));
        let spool = max_abs(out.iter().map(|o| o.spool_position));
        assert!(spool > 0.005 && spool < 0.05, "{actuator:?}: spool {spool}");
        assert!(
            x < 1e-9,
            "{actuator:?}: table moved {x} m inside the deadband"
        );
        let free = run(
            &Params {
                actuator: p.actuator,
                ..Params::trees_lab()
            },
            &inputs,
        );
        let xf = max_abs(free.iter().map(|o| o.displacement_m));
        assert!(xf > 0.8e-3, "no-deadband table moved only {xf} m");
    }
}

/// Stick-slip raises the friction force at velocity reversals by about `(r_s - 1) F_mu`:
/// in a slow sine (reversal velocities well below the Stribeck velocity while `Z`
/// saturates) the peak of `F_A - M a` (= `F_D`, k_h = 0) rises by that amount.
#[test]
fn stick_slip_raises_force_at_reversals() {
    let inputs = sine(0.01, 0.05, 30.0);
    let peak_friction = |p: &Params| {
        let out = run(p, &inputs);
        max_abs(
            out[out.len() / 3..]
                .iter()
                .map(|o| o.actuator_force_n - p.table.mass_kg * o.acceleration_m_s2),
        )
    };
    let base = Params::trees_lab();
    let mut p = base;
    p.stick_slip.enabled = true;
    p.stick_slip.static_ratio = 2.0;
    p.stick_slip.stribeck_velocity_m_s = 0.01;
    let (f0, f1) = (peak_friction(&base), peak_friction(&p));
    let expected = (p.stick_slip.static_ratio - 1.0) * p.friction.force_n;
    eprintln!(
        "stick-slip: peak friction {f0:.0} N -> {f1:.0} N, rise {:.0} N, expected {expected:.0} N",
        f1 - f0
    );
    assert!(
        (f0 / p.friction.force_n - 1.0).abs() < 0.05,
        "kinetic peak {f0}"
    );
    let ratio = (f1 - f0) / expected;
    assert!(
        (0.8..=1.1).contains(&ratio),
        "rise {} N vs (r_s-1)F_mu = {expected} N",
        f1 - f0
    );
}

/// Friction asymmetry (spec section 7): on a slow sine, the actuator force that keeps
/// the table sliding at mid-stroke (inertia and spring nil there, `Z` saturated) is
/// `F_mu 2r/(1+r)` one way and `F_mu 2/(1+r)` the other: their ratio is `r`, their mean
/// `F_mu`, as without the effect.
#[test]
fn friction_asymmetry_makes_one_direction_harder() {
    let mid_stroke_forces = |p: &Params| {
        let inputs = sine(0.05, 0.1, 20.0);
        let out = run(p, &inputs);
        let (mut up, mut down) = (Vec::new(), Vec::new());
        for (k, o) in out.iter().enumerate().skip(out.len() / 4) {
            if o.displacement_m.abs() < 0.1 * 0.05 {
                let v = inputs[k].reference.velocity_m_s;
                if v > 0.0 {
                    up.push(o.actuator_force_n)
                } else {
                    down.push(o.actuator_force_n)
                }
            }
        }
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
        (mean(&up), -mean(&down))
    };
    let mut p = Params::trees_lab();
    p.friction_asymmetry.enabled = true;
    p.friction_asymmetry.ratio = 1.5;
    let (up, down) = mid_stroke_forces(&p);
    let f_mu = p.friction.force_n;
    eprintln!("sliding forces {up:.0} N and {down:.0} N (F_mu {f_mu} N)");
    assert!((up / down / 1.5 - 1.0).abs() < 0.05, "{up} / {down}");
    assert!(((up + down) / 2.0 / f_mu - 1.0).abs() < 0.05, "{up} {down}");
    let (up0, down0) = mid_stroke_forces(&Params::trees_lab());
    assert!((up0 / down0 - 1.0).abs() < 0.03, "{up0} / {down0}");
}

/// Flow asymmetry (spec section 7): the same spool opening meters `r` times more flow
/// one way than the other, for both actuators, and the table's reversal does not jump.
#[test]
fn flow_asymmetry_scales_the_flow_by_the_spool_sign() {
    for actuator in [ActuatorModel::Ideal, ActuatorModel::Nonlinear] {
        let mut p = Params::trees_lab();
        p.actuator.model = actuator;
        p.flow_asymmetry.enabled = true;
        p.flow_asymmetry.ratio = 2.0;
        let m = Model::new(&p);
        let rate = |spool: f64| {
            let mut s = m.rest_state();
            s[ix::XV] = spool;
            let mut ds = [0.0; shaketable::model::NX];
            m.derivatives(
                &s,
                &Inputs::default(),
                &SensorNoise::default(),
                0.0,
                &mut ds,
            );
            ds[ix::PA]
        };
        let (pos, neg) = (rate(0.01), rate(-0.01));
        assert!(
            (pos / -neg / 2.0 - 1.0).abs() < 1e-9,
            "{actuator:?}: {pos} vs {neg}"
        );
        // the mean flow is the symmetric valve's
        let sym = Model::new(&Params {
            flow_asymmetry: Default::default(),
            ..p
        });
        let mut s = sym.rest_state();
        s[ix::XV] = 0.01;
        let mut ds = [0.0; shaketable::model::NX];
        sym.derivatives(
            &s,
            &Inputs::default(),
            &SensorNoise::default(),
            0.0,
            &mut ds,
        );
        assert!(
            ((pos - neg) / 2.0 / ds[ix::PA] - 1.0).abs() < 1e-9,
            "{actuator:?}"
        );
    }
}

/// A specimen with two modes (spec section 7, second part) makes the apparent mass
/// `M + sum_k m_k T_k(s)`, `T_k = (c_k s + k_k)/(m_k s^2 + c_k s + k_k)`, plus the
/// friction's pre-sliding stiffness `F_mu/(Y s^2)`: the analytic FRF is that sum, with a
/// resonance at each mode and an anti-resonance above each; the simulated data show both
/// resonances.
#[test]
fn two_mode_specimen_is_the_sum_of_its_modes() {
    let mut p = Params::trees_lab();
    p.apply_effect_spec(
        "specimen:mass_kg=15000,frequency_hz=6,damping_ratio=0.02,\
         mode2.mass_kg=6000,mode2.frequency_hz=21,mode2.damping_ratio=0.02",
    )
    .unwrap();
    let lin = Linearisation::new(&p);
    let w_of = |f: f64| 2.0 * std::f64::consts::PI * f;
    let modes = [(15_000.0, 6.0, 0.02), (6000.0, 21.0, 0.02)];
    let analytic = |f: f64| {
        let s = num_complex::Complex64::new(0.0, w_of(f));
        let mut m = num_complex::Complex64::new(p.table.mass_kg, 0.0)
            + p.friction.force_n / p.friction.yield_displacement_m / (s * s);
        for (mk, fk, zk) in modes {
            let (k, c) = (mk * w_of(fk).powi(2), 2.0 * zk * mk * w_of(fk));
            m += mk * (c * s + k) / (mk * s * s + c * s + k);
        }
        m
    };
    let grid = shaketable::linear::linear_grid(2.0, 30.0, 0.01);
    for &f in &grid {
        let (h, a) = (lin.acceleration_to_force(f), analytic(f));
        assert!((h - a).norm() / a.norm() < 1e-6, "{f} Hz: {h} vs {a}");
    }
    let mag: Vec<f64> = grid
        .iter()
        .map(|&f| lin.acceleration_to_force(f).norm())
        .collect();
    let peak1 = extremum(&grid, &mag, 2.0, 12.0, true);
    let notch1 = extremum(&grid, &mag, peak1, 15.0, false);
    let peak2 = extremum(&grid, &mag, 15.0, 25.0, true);
    let notch2 = extremum(&grid, &mag, peak2, 30.0, false);
    // undamped anti-resonances: M + sum m_k w_k^2/(w_k^2 - w^2) = 0 (friction ignored)
    let undamped = |f: f64| {
        p.table.mass_kg
            + modes
                .iter()
                .map(|&(mk, fk, _)| mk * fk * fk / (fk * fk - f * f))
                .sum::<f64>()
    };
    let root = |mut lo: f64, mut hi: f64| {
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if undamped(mid) > 0.0 {
                hi = mid
            } else {
                lo = mid
            }
        }
        0.5 * (lo + hi)
    };
    let (anti1, anti2) = (root(6.001, 20.999), root(21.001, 60.0));
    eprintln!("two modes: peaks {peak1} {peak2} Hz, notches {notch1} {notch2} Hz (expected {anti1:.3} {anti2:.3})");
    // the other mode's and the table's terms move each extremum a little off the modal
    // frequency; friction's pre-sliding stiffness lifts the anti-resonances (as for one mode)
    assert!(
        (peak1 - 6.0).abs() <= 0.1 && (peak2 - 21.0).abs() <= 0.2,
        "{peak1} {peak2}"
    );
    assert!(
        (notch1 - anti1).abs() <= 0.2 && (notch2 - anti2).abs() <= 0.2,
        "{notch1} {notch2}"
    );
    // the simulated random test shows both resonances
    let (f, m) = apparent_mass(&p);
    let sim1 = extremum(&f, &m, 2.0, 12.0, true);
    let sim2 = extremum(&f, &m, 15.0, 25.0, true);
    eprintln!("two modes simulated: resonances {sim1} {sim2} Hz");
    assert!(
        (sim1 - 6.0).abs() <= 0.25 && (sim2 - 21.0).abs() <= 0.25,
        "{sim1} {sim2}"
    );
}

/// Absent higher modes (mass 0, whatever their other values) change nothing: the
/// one-mode specimen computes bit for bit as the specimen always did (mode 1 alone, the
/// higher modes' states untouched).
#[test]
fn one_mode_specimen_is_bit_for_bit_the_specimen() {
    let mut p = Params::trees_lab();
    p.apply_effect_spec("specimen:mass_kg=15000,frequency_hz=6,damping_ratio=0.03")
        .unwrap();
    let mut q = p;
    q.specimen.mode2.frequency_hz = 9.0;
    q.specimen.mode3.damping_ratio = 0.3;
    let inputs = from_rest(0.02, 3.0, 2.0);
    let (a, b) = (run(&p, &inputs), run(&q, &inputs));
    assert_eq!(a, b);
    let mut sim = Simulator::new(Model::new(&q), 0.0, DEFAULT_MAX_SUBSTEP_S);
    for w in inputs.windows(2) {
        sim.advance(1.0 / FS, &w[0], &w[1], &SensorNoise::default());
    }
    for i in [ix::XS2, ix::VS2, ix::XS3, ix::VS3, ix::XR, ix::VR] {
        assert_eq!(sim.state[i], 0.0);
    }
    assert!(sim.state[ix::XS] != 0.0);
}

/// Free-play runs: the outputs and, every sample, the rod-table distance `d` and the
/// contact force.
fn free_play_run(p: &Params, inputs: &[Inputs]) -> (Vec<Outputs>, Vec<(f64, f64)>) {
    let mut sim = Simulator::new(Model::new(p), 0.0, DEFAULT_MAX_SUBSTEP_S);
    let noise = SensorNoise::default();
    let (mut out, mut contact) = (Vec::new(), Vec::new());
    for w in inputs.windows(2) {
        out.push(sim.outputs(&w[0], &noise));
        let alg = sim.model.algebraic(&sim.state, &w[0], &noise, 0.0);
        contact.push((sim.state[ix::XR] - sim.state[ix::X], alg.contact_force_n));
        sim.advance(1.0 / FS, &w[0], &w[1], &noise);
        assert!(sim.diverged().is_none(), "{:?}", sim.diverged());
    }
    (out, contact)
}

/// Free play with no gap and a stiff contact: the table follows the rod, and the run is
/// close to the table without the effect (the moving mass stays M).
#[test]
fn free_play_without_gap_follows_the_rod() {
    let mut p = Params::trees_lab();
    p.apply_effect_spec("free_play:gap_m=0,contact_stiffness_n_m=1e10,contact_damping_ratio=0.2")
        .unwrap();
    let inputs = from_rest(0.02, 2.0, 3.0);
    let (out, contact) = free_play_run(&p, &inputs);
    let bare = run(&Params::trees_lab(), &inputs);
    let dmax = max_abs(bare.iter().map(|o| o.displacement_m));
    let amax = max_abs(bare.iter().map(|o| o.acceleration_m_s2));
    let ddev = max_abs(
        out.iter()
            .zip(&bare)
            .map(|(a, b)| a.displacement_m - b.displacement_m),
    );
    let adev = max_abs(
        out.iter()
            .zip(&bare)
            .map(|(a, b)| a.acceleration_m_s2 - b.acceleration_m_s2),
    );
    let rms = |x: &mut dyn Iterator<Item = f64>| {
        let v: Vec<f64> = x.collect();
        (v.iter().map(|y| y * y).sum::<f64>() / v.len() as f64).sqrt()
    };
    let arms = rms(&mut bare.iter().map(|o| o.acceleration_m_s2));
    let adev_rms = rms(&mut out
        .iter()
        .zip(&bare)
        .map(|(a, b)| a.acceleration_m_s2 - b.acceleration_m_s2));
    let gap = max_abs(contact.iter().map(|c| c.0));
    eprintln!(
        "no gap: displacement dev {ddev:.2e} of {dmax:.3}, acceleration dev {adev:.3} of \
         {amax:.3} (RMS {adev_rms:.3} of {arms:.3}), |d| <= {gap:.2e}"
    );
    assert!(ddev < 0.005 * dmax, "{ddev}");
    // the contact's ringing (kHz) shows in the peak acceleration, little in its RMS
    assert!(adev < 0.1 * amax, "{adev}");
    assert!(adev_rms < 0.05 * arms, "{adev_rms}");
    // the contact deflection is the force over k_c: 0.24 MN / 1e10 N/m = 24 um
    assert!(gap < 3e-5, "{gap}");
    // and the no-gap linearisation is close to the baseline's
    let (lin, base) = (
        Linearisation::new(&p),
        Linearisation::new(&Params::trees_lab()),
    );
    // (below the oil-column peak; the peak and above move with its frequency)
    for f in [1.0, 5.0, 10.0] {
        let (h, h0) = (lin.table_tf(f), base.table_tf(f));
        assert!((h - h0).norm() < 0.05 * h0.norm(), "{f} Hz: {h} vs {h0}");
    }
    // the contact in series with the oil column lowers its peak a little (k_c = 30 k_oil)
    let (fig, fig0) = (
        lin.table_tf_figures().unwrap(),
        base.table_tf_figures().unwrap(),
    );
    eprintln!(
        "no gap: oil-column peak {:.2} Hz (bare {:.2} Hz)",
        fig.peak_hz, fig0.peak_hz
    );
    assert!(fig.peak_hz < fig0.peak_hz && fig0.peak_hz - fig.peak_hz < 0.4);
    assert!(lin.plant.names.contains(&"rod_x"));
}

/// Free play with a gap: at each reversal of a slow sine (inertia below friction, so the
/// contact changes side when the motion does) the rod (and the LVDT) crosses the gap
/// while the table (the accelerometer) waits, so LVDT minus table displacement swings by
/// the gap there; the contact never pulls and is silent inside the gap.
#[test]
fn free_play_gap_shows_at_reversals_and_never_pulls() {
    let (gap, f_hz) = (2e-3, 0.2);
    let mut p = Params::trees_lab();
    // a well-damped contact: the table settles against the rod soon after each impact
    p.apply_effect_spec(&format!("free_play:gap_m={gap},contact_damping_ratio=0.5"))
        .unwrap();
    let inputs = from_rest(0.02, f_hz, 12.0);
    let (out, contact) = free_play_run(&p, &inputs);
    let settled = &contact[(3.0 * FS) as usize..];
    let hi = settled.iter().map(|c| c.0).fold(f64::MIN, f64::max);
    let lo = settled.iter().map(|c| c.0).fold(f64::MAX, f64::min);
    eprintln!("gap {gap}: LVDT - table from {lo:.3e} to {hi:.3e}");
    assert!(((hi - lo) / gap - 1.0).abs() < 0.1, "{lo} {hi}");
    // the rod crosses the middle of the gap in the first part of each stroke after a
    // reversal (every 1/(2f) s; the friction's pre-sliding spring F_mu/Y lets the table
    // creep back with the rod for a while), and mid-stroke the LVDT leads the table by
    // half the gap in the direction of motion
    let half_period = 0.5 / f_hz;
    let mut crossings = 0;
    for k in 1..contact.len() {
        if contact[k - 1].0.signum() != contact[k].0.signum() && k as f64 / FS > 1.0 {
            let t = k as f64 / FS;
            let since = t - (t / half_period).floor() * half_period;
            eprintln!("crossing at {t} s, {since:.3} s after a reversal");
            assert!(
                since < 0.4 * half_period,
                "the rod crossed the gap at t = {t} s, {since} s after a reversal"
            );
            crossings += 1;
        }
    }
    assert!(crossings >= 4, "{crossings} crossings");
    // (not pressed against it at every sample: the loop, tuned for the 41-t table, drives
    // the light rod alone while it crosses the gap and the rod hammers the table a while)
    let v_max = max_abs(out.iter().map(|o| o.velocity_m_s));
    for (o, &(d, _)) in out.iter().zip(&contact).skip((3.0 * FS) as usize) {
        if o.velocity_m_s.abs() > 0.8 * v_max {
            assert!(
                d * o.velocity_m_s > 0.0,
                "mid-stroke: d {d} at velocity {}",
                o.velocity_m_s
            );
        }
    }
    for &(d, f) in &contact {
        assert!(f * d >= 0.0, "pulls: d {d}, force {f}");
        if d.abs() <= gap / 2.0 {
            assert_eq!(f, 0.0, "inside the gap: d {d}, force {f}");
        }
    }
    assert!(out.iter().all(|o| o.displacement_m.is_finite()));
    // the linearisation joins rod and table rigidly and says so
    let lin = Linearisation::new(&p);
    assert!(lin.notes.iter().any(|n| n.contains("free_play")));
    assert_eq!(
        lin.plant.order(),
        Linearisation::new(&Params::trees_lab()).plant.order()
    );
}

/// The contact's damping dissipates energy: a rod striking a free table rebounds with its
/// kinetic energy kept when `zeta_c = 0` and lost in part when `zeta_c > 0` (the contact
/// force alone, integrated with RK4 over the impact).
#[test]
fn free_play_contact_damping_dissipates_energy() {
    let energy_after = |zeta: f64| {
        let mut fp = Params::trees_lab().free_play;
        fp.enabled = true;
        fp.contact_damping_ratio = zeta;
        let c = fp.contact();
        let (mr, mt) = (fp.rod_mass_kg, 40_000.0);
        // (x_r, v_r, x_t, v_t): the rod at the gap's edge closing at 0.1 m/s
        let mut s = [c.half_gap_m, 0.1, 0.0, 0.0];
        let energy = |s: &[f64; 4]| 0.5 * mr * s[1] * s[1] + 0.5 * mt * s[3] * s[3];
        let e0 = energy(&s);
        let rate = |s: &[f64; 4]| {
            let f = c.force(s[0] - s[2], s[1] - s[3]);
            assert!(f * (s[0] - s[2]) >= 0.0);
            [s[1], -f / mr, s[3], f / mt]
        };
        let h = 1e-6;
        // one impact: until the rod, having touched, is back inside the gap
        let mut touched = false;
        for _ in 0..100_000 {
            let d = s[0] - s[2];
            touched |= d > c.half_gap_m;
            if touched && d <= c.half_gap_m {
                break;
            }
            let k1 = rate(&s);
            let step = |k: &[f64; 4], a: f64| std::array::from_fn(|i| s[i] + a * k[i]);
            let k2 = rate(&step(&k1, h / 2.0));
            let k3 = rate(&step(&k2, h / 2.0));
            let k4 = rate(&step(&k3, h));
            s = std::array::from_fn(|i| {
                s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
        }
        // separated again: the rod behind the table
        assert!(s[1] < s[3], "{s:?}");
        energy(&s) / e0
    };
    let (elastic, damped) = (energy_after(0.0), energy_after(0.1));
    eprintln!("kinetic energy kept: {elastic:.6} without damping, {damped:.4} with zeta_c 0.1");
    assert!((elastic - 1.0).abs() < 1e-6, "{elastic}");
    assert!(damped < 0.8, "{damped}");
}
