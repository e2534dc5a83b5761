//! Friction, stiffness and mass from periodic tests at any frequencies and amplitudes
//! (issue 16, part 4a; paper 4.2, eqs. 4.5-4.15): two sines and one triangle that are not
//! the paper's program, no random test (so no mass from 4.1.2 to start from), synthesised
//! by the project's simulator at the default noise levels, several seeds.

use shaketable::campaign::synth::{synthesise_program, SynthOptions};
use shaketable::campaign::{TestKind, TestSpec};
use shaketable::identify::identify;
use shaketable::Params;

fn periodic(name: &str, kind: TestKind, frequency_hz: f64, amplitude_m: f64) -> TestSpec {
    TestSpec::periodic(name, format!("{name}.csv"), kind, frequency_hz, amplitude_m)
}

/// A lab's own periodic program: a slow sine (inertia about half the friction), a fast
/// one (inertia about 50 times the friction) and one triangle, under lab names.
fn program() -> Vec<(usize, TestSpec)> {
    vec![
        (0, periodic("sweep-a 0.2Hz", TestKind::Sine, 0.2, 0.03)),
        (1, periodic("sweep-b 1.3Hz", TestKind::Sine, 1.3, 0.07)),
        (2, periodic("ramp 0.08Hz", TestKind::Triangle, 0.08, 0.05)),
    ]
}

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Identify the program synthesised from `truth` with `seed`; the estimates within the
/// tolerances (relative: mass, F_mu, Y; b within 0.1; k within 2e4 N/m or 10 %, the
/// paper's stiffness precision). Measured on seeds 1-6: mass within 0.05 %, F_mu 0.5 %,
/// Y 4 %, b 0.08, k 215 N/m.
fn check(label: &str, truth: &Params, seed: u64, tol: [f64; 3]) {
    let opts = SynthOptions {
        seed,
        ..SynthOptions::default()
    };
    let c = synthesise_program(truth, &program(), &opts, None).unwrap();
    let id = identify(&c);
    let fr = id
        .friction
        .as_ref()
        .unwrap_or_else(|| panic!("{label}: {:?}", id.missing));
    let tri = id.triangles.as_ref().unwrap();
    let m = id.mass_kg.unwrap_or(f64::NAN);
    let f = &truth.friction;
    let msg = format!(
        "{label} seed {seed}: M {m:.0} ({:.2} %), F_mu {:.1} ({:.2} %), Y {:.3e} ({:.1} %), b {:.3}, k {:.0}; missing {:?}",
        100.0 * rel(m, truth.table.mass_kg),
        fr.force_n,
        100.0 * rel(fr.force_n, f.force_n),
        fr.yield_displacement_m,
        100.0 * rel(fr.yield_displacement_m, f.yield_displacement_m),
        fr.shape,
        tri.stiffness_n_m,
        id.missing
    );
    eprintln!("{msg}");
    // no random test: the mass is the periodic tests' own (the fast sine's loop approach)
    assert!(
        id.mass_random.is_none() && id.mass_periodic.is_some(),
        "{msg}"
    );
    assert!(rel(m, truth.table.mass_kg) < tol[0], "{msg}");
    assert!(rel(fr.force_n, f.force_n) < tol[1], "{msg}");
    assert!(
        rel(fr.yield_displacement_m, f.yield_displacement_m) < tol[2],
        "{msg}"
    );
    assert!((fr.shape - f.shape).abs() < 0.1, "{msg}");
    let k = truth.table.stiffness_n_m;
    assert!((tri.stiffness_n_m - k).abs() < (0.1 * k).max(2e4), "{msg}");
    // every estimate carries its sigma
    for key in [
        "friction.force_n",
        "friction.yield_displacement_m",
        "friction.shape",
    ] {
        let e = id.estimate(key).unwrap();
        assert!(
            e.sigma.is_some_and(|s| s.is_finite() && s > 0.0),
            "{key}: {e:?}"
        );
    }
}

#[test]
fn defaults_from_two_sines_and_a_triangle() {
    for seed in [1, 2, 3] {
        check("defaults", &Params::trees_lab(), seed, [0.005, 0.02, 0.1]);
    }
}

#[test]
fn heavier_stiffer_table_with_other_friction() {
    let mut p = Params::trees_lab();
    p.table.mass_kg = 52_000.0;
    p.table.stiffness_n_m = 5e5;
    p.friction.force_n = 6_000.0;
    p.friction.yield_displacement_m = 5e-4;
    p.friction.shape = 0.2;
    for seed in [4, 5, 6] {
        check("heavier", &p, seed, [0.005, 0.02, 0.1]);
    }
}
