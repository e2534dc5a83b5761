//! Identification accuracy (issue 5): campaigns synthesised from three parameter sets at
//! the default noise levels, identified, every estimate within the paper's precision.

use shaketable::campaign::synth::{synthesise, SynthOptions};
use shaketable::identify::identify;
use shaketable::linear::OilColumn;
use shaketable::params::ServovalveModel;
use shaketable::Params;

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Check every accuracy target of issue 5 for a truth `p` and synthesis seed.
fn check(label: &str, p: &Params, seed: u64) {
    let opts = SynthOptions {
        seed,
        ..SynthOptions::default()
    };
    let c = synthesise(p, &opts, None);
    let id = identify(&c);
    assert!(id.missing.is_empty(), "{label}: {:?}", id.missing);
    let v = id.servovalve.as_ref().unwrap();
    let mut report = Vec::new();
    let mut ok = true;
    let mut expect = |name: &str, err: f64, tol: f64| {
        report.push(format!(
            "{name}: {:.2} % (tol {:.1} %)",
            100.0 * err,
            100.0 * tol
        ));
        ok &= err < tol;
    };
    match p.servovalve.model {
        ServovalveModel::SecondOrder => {
            expect(
                "valve f_v",
                rel(v.natural_frequency_hz, p.servovalve.natural_frequency_hz),
                0.03,
            );
            expect(
                "valve xi",
                rel(v.damping_ratio, p.servovalve.damping_ratio),
                0.10,
            );
            assert_eq!(v.chosen, ServovalveModel::SecondOrder, "{label}");
        }
        _ => {
            expect(
                "valve tau",
                rel(v.time_constant_s, p.servovalve.time_constant_s),
                0.10,
            );
            assert_eq!(v.chosen, ServovalveModel::FirstOrder, "{label}");
        }
    }
    let m = p.table.mass_kg;
    expect("mass (final)", rel(id.mass_kg.unwrap_or(f64::NAN), m), 0.02);
    expect(
        "mass random",
        rel(id.mass_random.as_ref().unwrap().mass_kg, m),
        0.02,
    );
    expect(
        "mass periodic",
        rel(id.mass_periodic.as_ref().unwrap().mass_kg, m),
        0.02,
    );
    let oil = OilColumn::of(p);
    let o = id.oil_column.as_ref().unwrap();
    expect(
        "oil frequency",
        rel(o.frequency_hz, oil.frequency_hz),
        0.015,
    );
    expect("oil damping", rel(o.damping_ratio, oil.damping_ratio), 0.25);
    expect(
        "bulk modulus",
        rel(o.bulk_modulus_pa, p.actuator.bulk_modulus_pa),
        0.04,
    );
    expect(
        "friction force",
        rel(id.friction.as_ref().unwrap().force_n, p.friction.force_n),
        0.15,
    );
    // the Bouc-Wen yield and shape (eq. 4.15), beyond the paper's table: driven by the
    // LVDT's noisy path they came out 1-2 % low and 11-16 % high (the path turned at every
    // wiggle); on the path without the noise's back-and-forth, the shape is within 3 % on
    // six seeds of the default table (scripts/dev/identify_sweep.py; 3-4.4 % on these
    // three tables), the yield within 1.3 %: the tolerances are about twice the largest
    // shape error and four times the largest yield error
    let fr = id.friction.as_ref().unwrap();
    expect(
        "yield displacement",
        rel(fr.yield_displacement_m, p.friction.yield_displacement_m),
        0.05,
    );
    expect("friction shape", rel(fr.shape, p.friction.shape), 0.10);
    // its sigma, widened by the residual's correlation, covers the error within three
    // sigmas (1.1-1.8 measured here)
    expect(
        "shape error / 3 sigma",
        (fr.shape - p.friction.shape).abs() / (3.0 * fr.sigma_shape),
        1.0,
    );
    let k = id.triangles.as_ref().unwrap().stiffness_n_m;
    if p.table.stiffness_n_m == 0.0 {
        report.push(format!("stiffness: {k:.0} N/m (|k| < 2e4)"));
        ok &= k.abs() < 2e4;
    } else {
        expect("stiffness", rel(k, p.table.stiffness_n_m), 0.10);
    }
    let val = id.validation.as_ref().unwrap();
    report.push(format!("table TF error {:.4}", val.table_tf_error));
    ok &= val.table_tf_error < 0.1;
    eprintln!("{label} (seed {seed}): {}", report.join("; "));
    assert!(ok, "{label} (seed {seed}): {}", report.join("; "));
}

#[test]
fn identifies_the_default_trees_lab_table() {
    check("defaults", &Params::trees_lab(), 11);
}

#[test]
fn identifies_a_heavier_table_with_a_first_order_valve() {
    let mut p = Params::trees_lab();
    p.table.mass_kg *= 1.25;
    p.servovalve.model = ServovalveModel::FirstOrder;
    check("mass +25 %, first-order valve", &p, 12);
}

#[test]
fn identifies_a_softer_oil_column_with_more_friction_and_a_spring() {
    let mut p = Params::trees_lab();
    p.actuator.bulk_modulus_pa *= 0.8;
    p.friction.force_n *= 2.0;
    p.table.stiffness_n_m = 5e5;
    check("bulk modulus -20 %, friction x2, k = 5e5 N/m", &p, 13);
}
