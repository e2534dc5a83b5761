//! Issue 17 part 6: the oil column identified at three times the default sensor noise,
//! on the 41-t TREES Lab table and on a 6-t table (campaigns from the project's own
//! synthesiser, seeded; section-4 identification only, no device fit).
//!
//! Tolerances from `scripts/dev/identify_sweep.py --seeds 1-6 --noise 1,3 --table 41t
//! --table 6t=scripts/dev/table_6t.toml` (24 campaigns): the oil-column frequency came
//! out +0.04 to +0.19 % (the identified mass's -0.14 to -0.26 % enters `sqrt(k/M)`),
//! the damping -2.8 to +4.3 %. Before the fix the same seeds gave -1.4 to -5.9 % and
//! -1.4 to +37 % at three times the noise; the seeds below were among the worst.

use shaketable::campaign::screen::screen;
use shaketable::campaign::synth::{synthesise, NoiseLevels, SynthOptions};
use shaketable::identify::{identify_screened, OilColumnInput};
use shaketable::linear::OilColumn;
use shaketable::Params;

/// Oil-column frequency tolerance, relative: three times the largest error of the sweep
/// (0.19 %), a third of the smallest bias of the former estimator on these seeds.
const FREQUENCY_TOLERANCE: f64 = 0.006;
/// Oil-column damping tolerance, relative: twice the largest error of the sweep (4.3 %),
/// below the former estimator's +17 to +37 % on these seeds.
const DAMPING_TOLERANCE: f64 = 0.08;
/// How many times the default sensor noise.
const NOISE_SCALE: f64 = 3.0;

fn noisy(scale: f64) -> NoiseLevels {
    let n = NoiseLevels::default();
    NoiseLevels {
        spool: scale * n.spool,
        displacement_m: scale * n.displacement_m,
        acceleration_m_s2: scale * n.acceleration_m_s2,
        force_n: scale * n.force_n,
    }
}

/// The 6-t table of `scripts/dev/table_6t.toml`: the TREES Lab table scaled by
/// `r = 6000 / 41258` in everything the force scales with (piston area, oil volume, flow
/// gain, leakage, friction), the delta-P gain by `1 / r`; its oil column stays at 14.2 Hz
/// with a 0.0336 damping ratio, under the same absolute sensor noise.
fn table_6t() -> Params {
    let mut p = Params::trees_lab();
    p.table.mass_kg = 6000.0;
    p.controller.kdp = 2.264e-7;
    p.actuator.piston_area_m2 = 0.01325;
    p.actuator.total_oil_volume_m3 = 0.0176;
    p.actuator.flow_gain_m3_s = 0.02909;
    p.actuator.leakage_m3_s_pa = 2.208e-11;
    p.friction.force_n = 582.0;
    p
}

/// How far an identified oil column may be from the truth, relative.
struct Tolerance {
    frequency: f64,
    damping: f64,
}

/// The tolerances at three times the noise ([`FREQUENCY_TOLERANCE`], [`DAMPING_TOLERANCE`]).
const AT_THREE_TIMES_THE_NOISE: Tolerance = Tolerance {
    frequency: FREQUENCY_TOLERANCE,
    damping: DAMPING_TOLERANCE,
};

/// Synthesise the program's random tests, triangles and sines of `truth` at `seed` and
/// three times the noise, identify, and check the oil column against the truth.
fn check_oil_column(truth: &Params, seed: u64, what: &str) {
    check_oil_column_at(truth, seed, NOISE_SCALE, &AT_THREE_TIMES_THE_NOISE, what)
}

/// [`check_oil_column`] at `noise_scale` times the default noise, within `tol`.
fn check_oil_column_at(truth: &Params, seed: u64, noise_scale: f64, tol: &Tolerance, what: &str) {
    let opts = SynthOptions {
        seed,
        noise: noisy(noise_scale),
        ..SynthOptions::default()
    };
    let id = identify_screened(&screen(&synthesise(truth, &opts, None)));
    let oil = id
        .oil_column
        .as_ref()
        .unwrap_or_else(|| panic!("{what}: no oil column: {:?}", id.missing));
    assert_eq!(oil.input, OilColumnInput::CommandThroughValve, "{what}");
    let true_oil = OilColumn::of(truth);
    let f_err = oil.frequency_hz / true_oil.frequency_hz - 1.0;
    let zeta_err = oil.damping_ratio / true_oil.damping_ratio - 1.0;
    assert!(
        f_err.abs() < tol.frequency,
        "{what}: oil-column frequency {:.4} Hz vs {:.4} Hz ({:+.2} %)",
        oil.frequency_hz,
        true_oil.frequency_hz,
        100.0 * f_err
    );
    assert!(
        zeta_err.abs() < tol.damping,
        "{what}: oil-column damping {:.5} vs {:.5} ({:+.1} %)",
        oil.damping_ratio,
        true_oil.damping_ratio,
        100.0 * zeta_err
    );
}

/// Seed 3 of the 41-t table at three times the noise: formerly -5.9 % and +37 %.
#[test]
fn oil_column_of_the_41_t_table_at_three_times_the_noise() {
    check_oil_column(&Params::trees_lab(), 3, "41 t, seed 3");
}

/// Seed 2 of the 6-t table at three times the noise: formerly -1.6 % and +32 %.
#[test]
fn oil_column_of_a_6_t_table_at_three_times_the_noise() {
    check_oil_column(&table_6t(), 2, "6 t, seed 2");
}

/// Tables whose oil column is far from the TREES Lab's 14 Hz, at the default noise: 6 t
/// and 15 t on the TREES Lab actuator (37.2 and 23.5 Hz), and 6 t on an actuator twice as
/// stiff (53.8 Hz, above the fit's 40-Hz band). The fit from the paper's 14-Hz start alone
/// stopped in a local minimum near 14-15 Hz on all three (-60, -35 and -72 %).
/// Tolerances: about twice the largest error of a sweep (frequency -0.24 to +2.35 %,
/// damping +0.4 to +11.7 %; the 3-t table's 52.5-Hz column gave both largest errors): the
/// 6-t table at seeds 1-4 and 471 at one and seeds 1-4 at three times the noise, the 3-t,
/// 15-t and 80-t tables and the stiff actuator at seed 5.
#[test]
fn oil_column_of_tables_far_from_14_hz() {
    const FAR: Tolerance = Tolerance {
        frequency: 0.05,
        damping: 0.25,
    };
    let light = |mass_kg: f64, bulk_modulus_pa: f64| {
        let mut p = Params::trees_lab();
        p.table.mass_kg = mass_kg;
        p.actuator.bulk_modulus_pa = bulk_modulus_pa;
        p
    };
    let beta = Params::trees_lab().actuator.bulk_modulus_pa;
    check_oil_column_at(&light(6000.0, beta), 471, 1.0, &FAR, "6 t, 37 Hz");
    check_oil_column_at(&light(15_000.0, beta), 5, 1.0, &FAR, "15 t, 23.5 Hz");
    check_oil_column_at(&light(6000.0, 2.5e9), 5, 1.0, &FAR, "6 t, 53.8 Hz");
}

/// A 6-t table carrying a specimen whose mode lies at or below the mass band's 2-Hz edge
/// (3 t at 2.2 Hz, 3 t at 1.8 Hz; 30-s random tests, default noise): the table carrying
/// the mode is read from 1 Hz, and the oil column behind it keeps its stiffness. Before,
/// no carried fit placed the mode, the mass taken was the sines' 9.1 t and the oil column,
/// read behind the rigid compromise of the oil-column test's own apparent mass (5.6 t),
/// came out 58 % stiff. Tolerances: the bulk modulus within 4 % (measured -0.7 and
/// -1.2 %; -0.3 to -1.6 % on six such specimens at 1.8-2.7 Hz), the mass taken, table and
/// specimen, within 3 % (measured +1.2 and +1.9 %), the mode within 15 % (a mode at the
/// edge is seen on one side more than the other: measured -0.1 and -8.7 %; the diagnosis
/// refits it).
#[test]
fn oil_column_behind_a_mode_at_the_mass_bands_edge() {
    for (seed, mode_hz) in [(5704, 2.2), (3, 1.8)] {
        let mut truth = Params::trees_lab();
        truth.table.mass_kg = 6000.0;
        let spec = format!("specimen:mass_kg=3000,frequency_hz={mode_hz},damping_ratio=0.03");
        truth.apply_effect_spec(&spec).unwrap();
        let opts = SynthOptions {
            seed,
            random_duration_s: 30.0,
            ..SynthOptions::default()
        };
        let id = identify_screened(&screen(&synthesise(&truth, &opts, None)));
        let what = format!("seed {seed}, 3 t at {mode_hz} Hz");
        let carried = (id.mass_random.as_ref())
            .and_then(|m| m.carried.as_ref())
            .unwrap_or_else(|| panic!("{what}: no table carrying modes"));
        assert_eq!(carried.modes.len(), 1, "{what}: {carried:?}");
        assert!(
            carried.band_hz[0] < 2.0,
            "{what}: read from {:?}",
            carried.band_hz
        );
        let mode_err = carried.modes[0].frequency_hz / mode_hz - 1.0;
        assert!(mode_err.abs() < 0.15, "{what}: {carried:?}");
        let mass_kg = id.mass_kg.unwrap();
        assert!(
            (mass_kg / 9000.0 - 1.0).abs() < 0.03,
            "{what}: mass {mass_kg}"
        );
        let bulk = id.params.actuator.bulk_modulus_pa / truth.actuator.bulk_modulus_pa - 1.0;
        assert!(
            bulk.abs() < 0.04,
            "{what}: bulk modulus {:+.1} %",
            100.0 * bulk
        );
    }
}
