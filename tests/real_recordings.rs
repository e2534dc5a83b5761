//! A laboratory's real recording read in place (issue 16): the UTFSM actuator with an MR
//! damper (`tests/data/utfsm`, MIT licence): its DAQ's own text export, volts, 1000 Hz,
//! displacement, force and reference only, no geometry and no controller gains.

use shaketable::campaign::format::read_campaign;
use shaketable::campaign::{Measured, TestKind};
use shaketable::identify::identify;

const CAMPAIGN_TOML: &str = r#"
name = "UTFSM MTS actuator with MR damper at 0 A (2022)"
sample_rate_hz = 1000.0

[read]
delimiter = ","
header_line = 7

[columns]
ref_displacement_m = { column = "CHANNEL2", scale = 0.01 }
displacement_m = { column = "CHANNEL0", scale = 0.01 }
force_n = { column = "CHANNEL1", scale = 9806.65 }

[[test]]
name = "15Hz-0A"
file = "validation_15Hz_0A.txt"
kind = "record"
control = "displacement"
"#;

/// The campaign folder: the committed recording and this campaign.toml.
fn campaign() -> (tempfile::TempDir, shaketable::campaign::Campaign) {
    let tmp = tempfile::tempdir().unwrap();
    let data = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/utfsm/validation_15Hz_0A.txt"
    );
    std::fs::copy(data, tmp.path().join("validation_15Hz_0A.txt")).unwrap();
    std::fs::write(tmp.path().join("campaign.toml"), CAMPAIGN_TOML).unwrap();
    let c = read_campaign(tmp.path()).unwrap();
    (tmp, c)
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

#[test]
fn the_daq_export_reads_with_what_it_recorded() {
    let (_tmp, c) = campaign();
    let (spec, r) = c.test("15Hz-0A").unwrap();
    assert_eq!(spec.kind, TestKind::Record);
    // 46 800 samples at 1 kHz (the preamble's sample count), the last with its
    // two-event note
    assert_eq!(r.len(), 46_800);
    assert!((r.time_s[1] - 1e-3).abs() < 1e-15);
    for m in [
        Measured::Acceleration,
        Measured::ValveCommand,
        Measured::Spool,
    ] {
        assert!(r.measured(m).is_none(), "{m:?} was not recorded");
    }
    let x = r.measured(Measured::Displacement).unwrap();
    let f = r.measured(Measured::Force).unwrap();
    // millimetres of stroke, a damper force of kN, the table following its reference
    assert!(rms(x) > 1e-4 && rms(x) < 0.05, "{}", rms(x));
    assert!(rms(f) > 10.0 && rms(f) < 1e5, "{}", rms(f));
    let err: Vec<f64> = x
        .iter()
        .zip(&r.ref_displacement_m)
        .map(|(a, b)| a - b)
        .collect();
    assert!(
        rms(&err) < 0.5 * rms(&r.ref_displacement_m),
        "tracking {}",
        rms(&err)
    );
    // nobody wrote the geometry or the gains down: unknown, not defaults
    assert_eq!(c.info.geometry.piston_area_m2, None);
    assert!(c.controller_for(spec).is_err());
}

#[test]
fn identification_says_what_it_cannot_tell_and_why() {
    let (_tmp, c) = campaign();
    let id = identify(&c);
    assert!(id.servovalve.is_none() && id.mass_kg.is_none() && id.oil_column.is_none());
    let keys: Vec<&str> = id.defaults().iter().map(|(k, _)| *k).collect();
    for k in ["actuator.piston_area_m2", "controller.kp", "table.mass_kg"] {
        assert!(keys.contains(&k), "{k} not listed as a default: {keys:?}");
    }
    assert!(!id.missing.is_empty());
    // the diagnosis needs the gains to simulate: a clear refusal, not a default
    let e = shaketable::diagnose::diagnose(&c, None).unwrap_err();
    assert!(e.contains("kp") && e.contains("[controller]"), "{e}");
}
