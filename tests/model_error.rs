//! The model-error response (issue 17 part 4) finds physics the model lacks: on a
//! campaign synthesised with a 15-t specimen at 5 Hz, the response from the reference to
//! the force residual of the truth without its specimen peaks at the specimen's
//! frequency (the specimen's force on the table per unit table acceleration, its apparent
//! mass, peaks there), and the truth itself leaves no coherent residual.

use shaketable::campaign::synth::{synthesise, SynthOptions};
use shaketable::diagnose::{model_error_response, Channel};
use shaketable::report::plot::{gain_band_png, GainBand};
use shaketable::Params;

const SPECIMEN_HZ: f64 = 5.0;

/// The truth (TREES Lab with the specimen), and the campaign R1-R3 it gives.
fn campaign() -> (Params, shaketable::campaign::Campaign) {
    let mut truth = Params::trees_lab();
    truth
        .apply_effect_spec("specimen:mass_kg=15000,frequency_hz=5,damping_ratio=0.05")
        .unwrap();
    let opts = SynthOptions {
        seed: 7,
        random_duration_s: 20.0,
        tests: Some(vec!["R1".into(), "R2".into(), "R3".into()]),
        ..SynthOptions::default()
    };
    let c = synthesise(&truth, &opts, None);
    (truth, c)
}

#[test]
fn a_missing_specimen_shows_as_a_peak_at_its_frequency() {
    let (truth, c) = campaign();
    let mut without = truth;
    without.specimen.enabled = false;
    let r2 = c.info.tests.iter().position(|t| t.name == "R2").unwrap();
    let m = model_error_response(&without, &c, r2, Channel::Force).unwrap();
    assert_eq!(m.input, "ref_acceleration_m_s2");
    assert_eq!(m.unit, "N/(m/s^2)");
    let (f, gain, coherence) = m.estimate.peak().unwrap();
    eprintln!(
        "force: peak {f} Hz, gain {gain:.4e} {}, coherence {coherence:.3}",
        m.unit
    );
    assert!((f / SPECIMEN_HZ - 1.0).abs() <= 0.1, "peak at {f} Hz");
    // the apparent mass at resonance, 15 t / (2 zeta) = 150 t, give or take the
    // resolution's smoothing of a peak 0.5 Hz wide
    assert!(gain > 5e4 && gain < 3e5, "{gain}");
    // the report's figure of it draws (kept in cargo's scratch folder to look at)
    let png = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("model_error_R2_force.png");
    gain_band_png(
        &png,
        "R2: model-error response without the specimen",
        &format!("gain ({})", m.unit),
        "2-sigma band",
        &GainBand::from(&m.estimate),
    )
    .unwrap();
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
    // the truth itself leaves only noise: no coherent peak stands out like the specimen's
    let m = model_error_response(&truth, &c, r2, Channel::Force).unwrap();
    let largest_coherence = m.estimate.coherence.iter().fold(0.0, |a: f64, &b| a.max(b));
    eprintln!("truth: largest coherence {largest_coherence:.3}");
    assert!(largest_coherence < 0.5, "{largest_coherence}");
}
