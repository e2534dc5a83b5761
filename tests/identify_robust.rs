//! Issue 14, items 1, 7, 8 and 9 (first sentence): estimators that never panic, never
//! report a start value or a default as an estimate, refuse records too short, and
//! search the validation peak in the validation band. Campaigns from the project's own
//! synthesiser (seeded), corrupted the way the issue found them.

use shaketable::campaign::screen::{screen, Action};
use shaketable::campaign::synth::{synthesise, SynthOptions};
use shaketable::campaign::{Campaign, Record};
use shaketable::identify::{identify, lsq, Identification, VALIDATION_BAND_HZ};
use shaketable::Params;

const TRUE_MASS_KG: f64 = 41_258.0;

fn small(tests: &str, seed: u64) -> Campaign {
    let opts = SynthOptions {
        seed,
        random_duration_s: 20.0,
        tests: Some(tests.split(',').map(String::from).collect()),
        ..SynthOptions::default()
    };
    synthesise(&Params::default(), &opts, None)
}

fn rec<'a>(c: &'a mut Campaign, name: &str) -> &'a mut Record {
    let i = c.info.tests.iter().position(|t| t.name == name).unwrap();
    &mut c.records[i]
}

/// Every number in the JSON is finite (serde writes non-finite as null anyway: check
/// the physical blocks hold null or a plausible value).
fn assert_sane(id: &Identification) {
    let j = id.to_json();
    if let Some(m) = j["table"]["mass_kg"].as_f64() {
        assert!(m > 1.0 && m < 2e6, "mass {m}");
    }
    if id.mass_kg.is_none() {
        assert!(j["table"]["mass_kg"].is_null());
        // without a section-4 mass the closed-loop fit estimates it (with a force channel)
        // or the parameter file's value is listed as a default
        let fitted = id
            .closed_loop
            .as_ref()
            .is_some_and(|cl| cl.estimates.iter().any(|e| e.key == "table.mass_kg"));
        assert!(fitted || id.defaults().iter().any(|(k, _)| *k == "table.mass_kg"));
    }
}

#[test]
fn flipped_force_in_r2_is_screened_not_a_panic() {
    let mut c = small("R2,S3", 5);
    rec(&mut c, "R2")
        .force_n
        .iter_mut()
        .flatten()
        .for_each(|x| *x = -*x);
    let id = identify(&c);
    assert!(id.mass_random.is_none());
    assert!(id
        .screening
        .iter()
        .any(|f| f.test == "R2" && f.channel == "force_n" && f.action == Action::TestExcluded));
    assert!(id
        .missing
        .iter()
        .any(|m| m.contains("R2") && m.contains("R2.csv")));
    // the loop approach still gives the mass from S3 (within its usual 5 %)
    let m = id.mass_kg.unwrap();
    assert!((m / TRUE_MASS_KG - 1.0).abs() < 0.05, "{m}");
    assert_sane(&id);
}

#[test]
fn all_zero_or_all_flipped_campaign_gives_no_estimate_and_no_default() {
    for mutate in [
        (|r: &mut Record| r.force_n.iter_mut().flatten().for_each(|x| *x = -*x)) as fn(&mut Record),
        |r: &mut Record| {
            r.acceleration_m_s2
                .iter_mut()
                .flatten()
                .for_each(|x| *x = -*x)
        },
        |r: &mut Record| {
            for ch in [
                &mut r.ref_displacement_m,
                &mut r.ref_velocity_m_s,
                &mut r.ref_acceleration_m_s2,
                r.valve_command.as_mut().unwrap(),
                r.displacement_m.as_mut().unwrap(),
                r.acceleration_m_s2.as_mut().unwrap(),
                r.force_n.as_mut().unwrap(),
            ] {
                ch.iter_mut().for_each(|x| *x = 0.0);
            }
        },
    ] {
        let mut c = small("R1,R2,R3", 6);
        c.records.iter_mut().for_each(mutate);
        let id = identify(&c);
        assert!(id.mass_kg.is_none() && id.servovalve.is_none() && id.oil_column.is_none());
        assert_sane(&id);
        let j = id.to_json();
        assert!(j["servovalve"]["gain"].is_null());
        assert!(!j["defaults"].as_array().unwrap().is_empty());
    }
}

#[test]
fn one_huge_sample_is_repaired_with_a_note() {
    let c0 = small("R1,R2,S3", 7);
    let clean = identify(&c0).mass_random.unwrap().mass_kg;
    for (test, ch) in [
        ("R2", "force_n"),
        ("R2", "acceleration_m_s2"),
        ("R2", "ref_acceleration_m_s2"),
        ("S3", "acceleration_m_s2"),
        ("R1", "spool_position"),
    ] {
        let mut c = c0.clone();
        let r = rec(&mut c, test);
        let x = match ch {
            "force_n" => r.force_n.as_mut().unwrap(),
            "acceleration_m_s2" => r.acceleration_m_s2.as_mut().unwrap(),
            "ref_acceleration_m_s2" => &mut r.ref_acceleration_m_s2,
            _ => r.spool_position.as_mut().unwrap(),
        };
        let k = x.len() / 3;
        x[k] = 1e300;
        let id = identify(&c);
        assert!(
            id.screening
                .iter()
                .any(|f| f.test == test && f.channel == ch && f.action == Action::Repaired),
            "{test} {ch}: {:?}",
            id.screening
        );
        // one interpolated sample moves the mass by far less than its uncertainty
        let m = id.mass_random.as_ref().unwrap().mass_kg;
        assert!(
            (m / clean - 1.0).abs() < 1e-3,
            "{test} {ch}: {m} vs {clean}"
        );
        assert!(id.servovalve.is_some());
        assert_sane(&id);
    }
}

#[test]
fn degenerate_r1_gives_no_servovalve_and_diagnose_uses_the_closed_loop() {
    let mut c = small("R1,R2", 8);
    let r = rec(&mut c, "R1");
    r.valve_command.iter_mut().flatten().for_each(|x| *x = 0.0);
    r.spool_position
        .as_mut()
        .unwrap()
        .iter_mut()
        .for_each(|x| *x = 0.0);
    // without R2's spool, R1 is the only test that could give the valve
    rec(&mut c, "R2").spool_position = None;
    let id = identify(&c);
    assert!(id.servovalve.is_none());
    assert!(id.to_json()["servovalve"]["natural_frequency_hz"].is_null());
    assert!(id
        .missing
        .iter()
        .any(|m| m.contains("R1") && m.contains("R1.csv")));
    // the closed-loop fit of the motion stands in for the valve section 4 could not give,
    // and the diagnosis runs on it. (What it names here is not asserted: on 8 s of one
    // usable test the closed-loop baseline stays 7-20 floor RMS off, and stick-slip, whose
    // fit gives no covariance to judge it by, absorbs part of that; the note of issue 16
    // says so.)
    assert!(id.closed_loop.is_some(), "{:?}", id.missing);
    let d = shaketable::diagnose::diagnose(&c, shaketable::diagnose::Effort::Full, None)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(d.baseline_from().starts_with("closed-loop fit"));
    assert!(d.baseline_from().contains("servovalve"));
    assert!(d.gain.is_finite(), "{}", d.gain);
}

#[test]
fn records_too_short_are_refused_by_name() {
    for n in [2usize, 100, 2000] {
        let mut c = small("R1,R2,R3,S3,T1", 9);
        for r in &mut c.records {
            let keep = n.min(r.len());
            r.time_s.truncate(keep);
            for ch in [
                &mut r.ref_displacement_m,
                &mut r.ref_velocity_m_s,
                &mut r.ref_acceleration_m_s2,
                r.valve_command.as_mut().unwrap(),
                r.displacement_m.as_mut().unwrap(),
                r.acceleration_m_s2.as_mut().unwrap(),
                r.force_n.as_mut().unwrap(),
            ] {
                ch.truncate(keep);
            }
            if let Some(x) = r.spool_position.as_mut() {
                x.truncate(keep);
            }
            r.extra.iter_mut().for_each(|(_, x)| x.truncate(keep));
        }
        let id = identify(&c);
        // 2000 samples = 3.9 s: still below every estimator's minimum
        assert!(id.mass_random.is_none(), "{n}: {:?}", id.mass_random);
        assert!(id.servovalve.is_none() && id.oil_column.is_none(), "{n}");
        assert!(id.mass_kg.is_none(), "{n}");
        if n == 2000 {
            assert!(
                id.missing
                    .iter()
                    .any(|m| m.starts_with("R2: ") && m.contains("needs at least")),
                "{:?}",
                id.missing
            );
        }
        assert_sane(&id);
    }
}

#[test]
fn validation_peak_is_searched_in_the_validation_band() {
    let c = small("R2", 10);
    let v = identify(&c).validation.unwrap();
    let p = v.measured_figures.unwrap().peak_hz;
    assert!(
        (VALIDATION_BAND_HZ[0]..=VALIDATION_BAND_HZ[1]).contains(&p),
        "measured peak {p} Hz"
    );
    // the table's peak (oil column, 14.2 Hz for the defaults) within a few bins
    assert!((p - 14.2).abs() < 1.0, "{p}");
}

#[test]
fn random_data_declared_a_sine_is_excluded() {
    let mut c = small("R2,S3", 11);
    let s3 = c.info.tests.iter().position(|t| t.name == "S3").unwrap();
    let r2 = c.info.tests.iter().position(|t| t.name == "R2").unwrap();
    let mut r = c.records[r2].clone();
    r.extra.clear();
    c.records[s3] = r;
    let s = screen(&c);
    assert!(s
        .findings
        .iter()
        .any(|f| f.test == "S3" && f.action == Action::TestExcluded));
    assert!(identify(&c).mass_periodic.is_none());
}

#[test]
fn clean_campaign_has_no_finding() {
    let c = small("R1,R2,R3,S1,S3,T1", 12);
    assert!(screen(&c).findings.is_empty(), "{:?}", screen(&c).findings);
}

#[test]
fn minimise_refuses_unsound_bounds_instead_of_panicking() {
    let r = |p: &[f64]| Some(vec![p[0] - 1.0]);
    let o = lsq::LsqOptions::default();
    assert!(lsq::minimise(r, &[1.0], &[f64::NAN], &[2.0], &[1.0], o).is_none());
    assert!(lsq::minimise(r, &[1.0], &[3.0], &[2.0], &[1.0], o).is_none());
    assert!(lsq::minimise(r, &[f64::NAN], &[0.0], &[2.0], &[1.0], o).is_none());
}
