//! Property test of issue 14: a valid small campaign (the project's synthesiser, seeded)
//! mutated at random (cells, rows, signs, scales, spikes, truncation, campaign.toml keys,
//! a missing file). For reading, screening, `identify` and `diagnose`: no panic, bounded
//! time, and either an error naming a file or estimates that are finite and physical or
//! absent with a reason.

use proptest::prelude::*;
use shaketable::campaign::format::{read_campaign, write_campaign};
use shaketable::campaign::screen::screen;
use shaketable::campaign::synth::{synthesise, SynthOptions};
use shaketable::campaign::{Campaign, Record, TestKind};
use shaketable::identify::{identify, Identification, MASS_BOUNDS_KG};
use shaketable::Params;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Longest an identification of the small campaign may take (it takes about 0.1 s).
const IDENTIFY_LIMIT: Duration = Duration::from_secs(30);
/// Longest a diagnosis of the small campaign may take (about 10 s on 2 busy cores).
const DIAGNOSE_LIMIT: Duration = Duration::from_secs(180);

fn base() -> &'static Campaign {
    static C: OnceLock<Campaign> = OnceLock::new();
    C.get_or_init(|| {
        let opts = SynthOptions {
            seed: 21,
            random_duration_s: 10.0,
            tests: Some(
                ["R1", "R2", "R3", "S1", "S3", "T1"]
                    .map(String::from)
                    .to_vec(),
            ),
            ..SynthOptions::default()
        };
        synthesise(&Params::default(), &opts, None)
    })
}

fn channel(r: &mut Record, k: usize) -> &mut Vec<f64> {
    match k % 7 {
        0 => &mut r.ref_displacement_m,
        1 => &mut r.ref_acceleration_m_s2,
        2 => r.valve_command.as_mut().unwrap(),
        3 => r.displacement_m.as_mut().unwrap(),
        4 => r.acceleration_m_s2.as_mut().unwrap(),
        5 => r.force_n.as_mut().unwrap(),
        _ => r.spool_position.as_mut().unwrap(),
    }
}

#[derive(Debug, Clone)]
enum Mutation {
    Cell(usize, usize, f64, f64),
    Sign(usize, usize),
    Scale(usize, usize, i32),
    Spikes(usize, usize, usize, f64),
    Truncate(usize, f64),
    Zero(usize, usize),
    Frequency(usize, f64),
    Kind(usize, u8),
    Amplitude(usize, f64),
}

fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(1e300),
        Just(-1e300),
        Just(0.0),
        -1e6..1e6f64,
    ]
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (0..6usize, 0..7usize, 0.0..1.0f64, value())
            .prop_map(|(t, c, p, v)| Mutation::Cell(t, c, p, v)),
        (0..6usize, 0..7usize).prop_map(|(t, c)| Mutation::Sign(t, c)),
        (0..6usize, 0..7usize, -12..12i32).prop_map(|(t, c, e)| Mutation::Scale(t, c, e)),
        (0..6usize, 0..7usize, 1..50usize, value())
            .prop_map(|(t, c, n, v)| Mutation::Spikes(t, c, n, v)),
        (0..6usize, 0.0..1.0f64).prop_map(|(t, f)| Mutation::Truncate(t, f)),
        (0..6usize, 0..7usize).prop_map(|(t, c)| Mutation::Zero(t, c)),
        (0..6usize, value()).prop_map(|(t, v)| Mutation::Frequency(t, v)),
        (0..6usize, 0..3u8).prop_map(|(t, k)| Mutation::Kind(t, k)),
        (0..6usize, value()).prop_map(|(t, v)| Mutation::Amplitude(t, v)),
    ]
}

fn apply(c: &mut Campaign, m: &Mutation) {
    match *m {
        Mutation::Cell(t, k, p, v) => {
            let x = channel(&mut c.records[t], k);
            let i = ((x.len() - 1) as f64 * p) as usize;
            x[i] = v;
        }
        Mutation::Sign(t, k) => channel(&mut c.records[t], k)
            .iter_mut()
            .for_each(|x| *x = -*x),
        Mutation::Scale(t, k, e) => channel(&mut c.records[t], k)
            .iter_mut()
            .for_each(|x| *x *= 10f64.powi(e)),
        Mutation::Spikes(t, k, n, v) => {
            let x = channel(&mut c.records[t], k);
            let step = (x.len() / n).max(1);
            x.iter_mut().step_by(step).for_each(|x| *x = v);
        }
        Mutation::Truncate(t, f) => {
            let r = &mut c.records[t];
            let keep = (r.len() as f64 * f) as usize;
            r.time_s.truncate(keep);
            for k in 0..7 {
                channel(r, k).truncate(keep);
            }
            r.ref_velocity_m_s.truncate(keep);
            r.extra.iter_mut().for_each(|(_, x)| x.truncate(keep));
        }
        Mutation::Zero(t, k) => channel(&mut c.records[t], k)
            .iter_mut()
            .for_each(|x| *x = 0.0),
        Mutation::Frequency(t, v) => c.info.tests[t].frequency_hz = Some(v),
        Mutation::Kind(t, k) => {
            c.info.tests[t].kind =
                [TestKind::Random, TestKind::Sine, TestKind::Triangle][k as usize]
        }
        Mutation::Amplitude(t, v) => c.info.tests[t].amplitude_m = Some(v),
    }
}

/// Every estimate is finite and physical, or absent with a reason in `missing`.
fn check(id: &Identification) {
    let j = id.to_json();
    for (block, key) in [
        ("servovalve", "gain"),
        ("servovalve", "natural_frequency_hz"),
        ("servovalve", "damping_ratio"),
        ("table", "mass_kg"),
        ("table", "mass_random_kg"),
        ("table", "mass_periodic_kg"),
        ("table", "stiffness_n_m"),
        ("oil_column", "frequency_hz"),
        ("oil_column", "damping_ratio"),
        ("oil_column", "bulk_modulus_pa"),
        ("friction", "force_n"),
    ] {
        let v = &j[block][key];
        assert!(
            v.is_null() || v.as_f64().is_some_and(f64::is_finite),
            "{block}.{key}: {v}"
        );
    }
    for key in ["mass_kg", "mass_random_kg", "mass_periodic_kg"] {
        if let Some(m) = j["table"][key].as_f64() {
            assert!(
                (MASS_BOUNDS_KG[0]..=MASS_BOUNDS_KG[1]).contains(&m),
                "{key} {m}"
            );
        }
    }
    if let Some(f) = j["oil_column"]["frequency_hz"].as_f64() {
        assert!(f > 0.0, "{f}");
    }
    // nothing is absent without a reason
    let absent = [
        id.servovalve.is_none(),
        id.mass_kg.is_none(),
        id.oil_column.is_none(),
        id.friction.is_none(),
    ];
    if absent.iter().any(|&a| a) {
        assert!(!id.missing.is_empty());
    }
    for m in &id.missing {
        assert!(!m.is_empty());
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_campaign_is_screened_and_identified_sanely(ms in prop::collection::vec(mutation(), 1..4)) {
        let mut c = base().clone();
        for m in &ms {
            apply(&mut c, m);
        }
        let _ = screen(&c);
        let t0 = Instant::now();
        let id = identify(&c);
        prop_assert!(t0.elapsed() < IDENTIFY_LIMIT, "{:?}", t0.elapsed());
        check(&id);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, failure_persistence: None, ..ProptestConfig::default() })]

    /// Fewer cases: a diagnosis that runs takes seconds.
    #[test]
    fn mutated_campaign_is_diagnosed_or_refused(m in mutation()) {
        let mut c = base().clone();
        apply(&mut c, &m);
        let t0 = Instant::now();
        match shaketable::diagnose::diagnose(&c, shaketable::diagnose::Effort::Full, None) {
            Ok(d) => {
                check(&d.identification);
                prop_assert!(d.gain.is_finite() || d.cause().is_none());
            }
            Err(e) => prop_assert!(e.contains("refused"), "{e}"),
        }
        prop_assert!(t0.elapsed() < DIAGNOSE_LIMIT, "{:?}", t0.elapsed());
    }
}

/// A missing record is an error naming the file.
#[test]
fn missing_file_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("c");
    write_campaign(base(), &dir).unwrap();
    std::fs::remove_file(dir.join("S3.csv")).unwrap();
    let e = read_campaign(&dir).unwrap_err().to_string();
    assert!(e.contains("S3.csv"), "{e}");
}

/// The binary: a flipped force channel is screened (exit 0, finding printed) by
/// `identify` and `campaign check`; with an all-zero valve command in R1 and no spool
/// recorded elsewhere (no other test can give the servovalve) `diagnose` runs on the
/// closed-loop fit (exit 0, the finding printed); a missing record is an error naming
/// its file (exit 1).
#[test]
fn cli_exit_codes() {
    let bin = env!("CARGO_BIN_EXE_shaketable");
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("c");
    let mut c = base().clone();
    c.records[1]
        .force_n
        .as_mut()
        .unwrap()
        .iter_mut()
        .for_each(|x| *x = -*x);
    c.records[0]
        .valve_command
        .as_mut()
        .unwrap()
        .iter_mut()
        .for_each(|x| *x = 0.0);
    for r in c.records.iter_mut().skip(1) {
        r.spool_position = None;
    }
    write_campaign(&c, &dir).unwrap();
    let run = |args: &[&str]| std::process::Command::new(bin).args(args).output().unwrap();
    // exit 0 and the standard output
    let succeeds = |args: &[&str]| {
        let o = run(args);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let d = dir.to_str().unwrap();
    let out = succeeds(&["identify", d]);
    assert!(out.contains("R2 (R2.csv), force_n"), "{out}");
    for args in [&["campaign", "check", d][..], &["diagnose", d, "--quiet"]] {
        let out = succeeds(args);
        assert!(out.contains("screening: R2 (R2.csv), force_n"), "{out}");
    }
    std::fs::remove_file(dir.join("S3.csv")).unwrap();
    let o = run(&["diagnose", d, "--quiet"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("S3.csv"), "{err}");
}

/// A corruption that leaves the refined baseline unscorable on a report quarter (R1's
/// spool channel ten-thousandfold) leaves no gain to measure, so no cause is named, and
/// the diagnosis says why. Found by the property test above in CI with a thousandfold
/// spool, whose baseline's run stopped in R1's report quarter; since stop 51 the oil
/// column's further starts give that campaign a baseline that runs through (held-out
/// residual 3875, no cause, `explained: false`), and ten-thousandfold reaches this path,
/// its residual there not finite with no run stopped.
#[test]
fn a_baseline_unscorable_in_the_report_quarter_names_no_cause() {
    let mut c = base().clone();
    apply(&mut c, &Mutation::Scale(0, 6, 4));
    let d = shaketable::diagnose::diagnose(&c, shaketable::diagnose::Effort::Full, None).unwrap();
    assert!(!d.baseline_heldout.is_finite(), "{}", d.baseline_heldout);
    assert!(d.cause().is_none() && d.causes.is_empty());
    let why = d.baseline_unscorable.as_deref().unwrap_or_default();
    assert!(
        why.contains("report quarter") && why.contains("not finite"),
        "{why}"
    );
}

/// T1's valve command sign-flipped (found by the property test above): no catalogue
/// effect explains a corrupted channel. A deadband "explained" it by the spread it
/// predicts while its noise-free run left 95 times the residual as coherent
/// (deterministic) error; it must be refused (the spread rule), and no cause named.
#[test]
fn a_sign_flipped_valve_command_names_no_cause() {
    let mut c = base().clone();
    apply(&mut c, &Mutation::Sign(5, 2));
    let d = shaketable::diagnose::diagnose(&c, shaketable::diagnose::Effort::Full, None).unwrap();
    let named: Vec<_> = d.causes.iter().map(|c| c.effect.name()).collect();
    assert!(d.cause().is_none() && named.is_empty(), "{named:?}");
    assert!(!d.explained);
}
