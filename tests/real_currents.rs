//! The UTFSM actuator with its MR damper across the damper's currents (issue 16, part 6;
//! `tests/data/utfsm`, MIT licence): the closed-loop actuator fitted on each current's
//! chirp predicts that current's 15-Hz run and the other currents' recordings; the
//! damper's force grows with the current.

#[path = "common/utfsm.rs"]
mod utfsm;

use shaketable::campaign::Measured;
use shaketable::identify::greybox::{ClosedLoopFit, Role};
use shaketable::identify::{identify, DeviceFit};
use utfsm::{CHIRP_0A, CHIRP_1A, RUN_15HZ_0A, RUN_15HZ_0X5A, RUN_15HZ_1A};

/// What the closed-loop fit of a campaign predicts for another campaign's tests: the
/// displacement fit % of `p` on each test of `on`.
fn predicted(p: &shaketable::Params, on: &shaketable::campaign::Campaign) -> Vec<(String, f64)> {
    use shaketable::identify::greybox::compare::compare;
    let tests: Vec<(usize, Role)> = (0..on.records.len())
        .map(|i| (i, Role::Validation))
        .collect();
    let c = compare(p, on, &tests, &[Measured::Displacement]);
    assert!(c.stopped.is_empty(), "{:?}", c.stopped);
    c.fits
        .iter()
        .map(|f| (f.test.clone(), f.fit_percent))
        .collect()
}

/// The closed-loop actuator (reference to displacement) fitted on one current's chirp.
fn actuator_loop(chirp: &str, run: &str) -> ClosedLoopFit {
    let (_tmp, c) = utfsm::campaign(&[("chirp", chirp), ("15Hz", run)], false);
    let id = identify(&c);
    let cl = id.closed_loop.unwrap_or_else(|| panic!("{:?}", id.missing));
    assert_eq!(
        (
            cl.estimation_tests.as_slice(),
            cl.validation_tests.as_slice()
        ),
        (&["chirp".to_string()][..], &["15Hz".to_string()][..])
    );
    cl
}

/// Every UTFSM recording: the chirps of one session, the 15-Hz runs of the other.
const EVERY_RECORDING: [(&str, &str); 5] = [
    ("chirp-0A", CHIRP_0A),
    ("chirp-1A", CHIRP_1A),
    ("15Hz-0A", RUN_15HZ_0A),
    ("15Hz-0.5A", RUN_15HZ_0X5A),
    ("15Hz-1A", RUN_15HZ_1A),
];

/// Points of displacement fit % the assertions below leave under what was measured: the
/// fits stop at a relative cost change of 1e-7 from starts read off the data, so a change
/// of solver or start rules moves them by tenths; a loss of a point and a half is a
/// worse method.
const FIT_MARGIN_POINTS: f64 = 1.5;

/// The actuator loop (reference to displacement, the load cell not mapped: the table
/// model's load is a rigid mass with Bouc-Wen friction, which cannot hold the damper's
/// viscous force, and fitting that force as well costs the displacement six points, see
/// `closed_loop_predicts_the_random_run`) fitted on each current's chirp predicts the same
/// current's 15-Hz run of the other session and every other current's recordings: the
/// damper's force, ten times larger at 1 A, hardly moves a servo-hydraulic actuator's
/// displacement loop.
#[test]
fn the_actuator_loop_fitted_on_each_chirp_predicts_its_15hz_run_and_the_other_currents() {
    let (at_0a, at_1a) = std::thread::scope(|s| {
        let a = s.spawn(|| actuator_loop(CHIRP_0A, RUN_15HZ_0A));
        let b = s.spawn(|| actuator_loop(CHIRP_1A, RUN_15HZ_1A));
        (a.join().unwrap(), b.join().unwrap())
    });
    let (_tmp, every) = utfsm::campaign(&EVERY_RECORDING, false);
    let (from_0a, from_1a) = (
        predicted(&at_0a.params, &every),
        predicted(&at_1a.params, &every),
    );
    for (current, cl, pred) in [("0 A", &at_0a, &from_0a), ("1 A", &at_1a, &from_1a)] {
        for c in &cl.combinations {
            eprintln!(
                "loop fitted at {current}: {} = {:.4} +- {:?} {}",
                c.name, c.value, c.sigma, c.unit
            );
        }
        eprintln!("loop fitted at {current}, displacement fit %: {pred:?}");
    }
    // measured (fit %): fitted on its chirp 95.73 (0 A) and 96.16 (1 A); the 15-Hz run of
    // the same current, predicted, 97.74 and 97.77
    let own = |cl: &ClosedLoopFit, role: Role| {
        cl.fits
            .iter()
            .find(|f| f.role == role && f.channel == "displacement_m")
            .unwrap()
            .fit_percent
    };
    for (cl, chirp, run) in [(&at_0a, 95.73, 97.74), (&at_1a, 96.16, 97.77)] {
        assert!(
            own(cl, Role::Estimation) > chirp - FIT_MARGIN_POINTS,
            "{:?}",
            cl.fits
        );
        assert!(
            own(cl, Role::Validation) > run - FIT_MARGIN_POINTS,
            "{:?}",
            cl.fits
        );
    }
    // measured, fitted at 0 A / at 1 A: chirp-0A 95.73 / 95.71, chirp-1A 96.13 / 96.16,
    // 15Hz-0A 97.74 / 97.90, 15Hz-0.5A 97.78 / 97.92, 15Hz-1A 97.59 / 97.77
    let measured = [
        (95.73, 95.71),
        (96.13, 96.16),
        (97.74, 97.90),
        (97.78, 97.92),
        (97.59, 97.77),
    ];
    for (((test, a), (_, b)), (ma, mb)) in from_0a.iter().zip(&from_1a).zip(measured) {
        assert!(
            *a > ma - FIT_MARGIN_POINTS && *b > mb - FIT_MARGIN_POINTS,
            "{test}: {a} {b}"
        );
        // the loop does not depend on the current: each current's model predicts the other's
        // records as well as that current's own model (measured: within 0.2 points)
        assert!((a - b).abs() < 1.0, "{test}: fitted at 0 A {a}, at 1 A {b}");
    }
}

/// The damper's force at each current, each recording fitted on its own. The MR fluid's
/// yield stress grows with the coil's field: the Bouc-Wen amplitude (the damper's yield
/// force) and the viscous coefficient grow with the current in both sessions.
#[test]
fn the_damper_force_grows_with_the_current() {
    use shaketable::identify::{fit_device, select::DeviceRoles};
    let (_tmp, c) = utfsm::campaign(&EVERY_RECORDING, true);
    let fits: Vec<DeviceFit> = (0..EVERY_RECORDING.len())
        .map(|fit| {
            fit_device(
                &c,
                &DeviceRoles {
                    fit,
                    others: vec![],
                },
            )
            .unwrap()
        })
        .collect();
    for d in &fits {
        eprintln!(
            "device {}: F_mu {:.1} +- {:.1} N, Y {:.3e} +- {:.1e} m, b {:.3}, c {:.1} +- {:.1} N s/m, \
             k {:.0} +- {:.0} N/m, m {:.2} +- {:.2} kg; fit {:.2} %",
            d.test, d.force_n, d.sigma[0], d.yield_displacement_m, d.sigma[1], d.shape,
            d.viscous_n_s_m, d.sigma[3], d.stiffness_n_m, d.sigma[4], d.mass_kg, d.sigma[5],
            d.fit.fit_percent
        );
    }
    // measured force fit %, in EVERY_RECORDING's order
    for (d, fit) in fits.iter().zip([72.83, 84.47, 85.03, 86.32, 81.63]) {
        assert!(
            d.fit.fit_percent > fit - FIT_MARGIN_POINTS,
            "{}: {}",
            d.test,
            d.fit.fit_percent
        );
    }
    let [chirp_0a, chirp_1a, run_0a, run_0x5a, run_1a] = &fits[..] else {
        unreachable!()
    };
    // measured F_mu: chirps 128 +- 2 N and 1240 +- 37 N (x 9.7); 15-Hz runs 813 +- 15,
    // 5327 +- 306 and 9136 +- 900 N (x 6.6 and x 11.2). Asserted: at 1 A more than 5
    // times 0 A in each session (half the smaller measured ratio: the Bouc-Wen amplitude
    // trades with the viscous term, whose own ratios are 3.3 and 6.8), and every step up
    // in current beyond three sigma of both.
    for (low, high) in [(chirp_0a, chirp_1a), (run_0a, run_1a)] {
        assert!(
            high.force_n > 5.0 * low.force_n,
            "{} {}",
            low.force_n,
            high.force_n
        );
        assert!(
            high.viscous_n_s_m > 2.0 * low.viscous_n_s_m,
            "{} {}",
            low.viscous_n_s_m,
            high.viscous_n_s_m
        );
    }
    for (low, high) in [(run_0a, run_0x5a), (run_0x5a, run_1a), (chirp_0a, chirp_1a)] {
        let three_sigma = 3.0 * low.sigma[0].hypot(high.sigma[0]);
        assert!(
            high.force_n - low.force_n > three_sigma,
            "{} {} {three_sigma}",
            low.test,
            high.test
        );
        assert!(
            high.viscous_n_s_m > low.viscous_n_s_m,
            "{} {}",
            low.test,
            high.test
        );
    }
}
