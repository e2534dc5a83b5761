//! Synthesis of the paper's test program (campaign-format.md; issue 3 part 6): program
//! length, reference consistency and levels, determinism, sensor noise inside the loop,
//! and the `campaign synth` / `simulate` commands.

use realfft::RealFftPlanner;
use shaketable::campaign::format::{read_campaign, read_record};
use shaketable::campaign::synth::{
    self, paper_program, reference, synthesise, synthesise_test, test_duration_s, NoiseLevels,
    SynthOptions, BLEND_S, FADE_S, REST_S, SAMPLE_RATE_HZ,
};
use shaketable::campaign::{Control, TestKind, TestSpec};
use shaketable::Params;
use std::path::Path;
use std::process::Command;

const FS: f64 = SAMPLE_RATE_HZ;

fn program_test(name: &str) -> (usize, TestSpec) {
    paper_program(90.0)
        .into_iter()
        .enumerate()
        .find(|(_, t)| t.name == name)
        .expect("test in the paper program")
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

#[test]
fn paper_program_is_906_s_in_the_papers_order() {
    let p = paper_program(90.0);
    let names: Vec<&str> = p.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "R1", "R2", "R3", "S1", "S2", "S3", "S4", "S5", "S6", "S7", "S8", "S9", "T1", "T2",
            "T3", "T4", "T5", "T6"
        ]
    );
    let total: f64 = p.iter().map(|t| test_duration_s(t, 90.0)).sum();
    assert_eq!(total, 906.0);
    let samples: usize = p.iter().map(|t| synth::test_samples(t, 90.0, FS)).sum();
    assert_eq!(samples, 906 * 512);
    let durations: Vec<f64> = p.iter().map(|t| test_duration_s(t, 90.0)).collect();
    assert_eq!(
        durations,
        [
            92.0, 92.0, 92.0, 62.0, 32.0, 22.0, 62.0, 32.0, 22.0, 62.0, 32.0, 22.0, 62.0, 32.0,
            62.0, 32.0, 62.0, 32.0
        ]
    );
    // levels of the format page's table
    assert_eq!(
        (p[0].control, p[0].rms, p[0].band_hz),
        (Control::Displacement, Some(0.005), Some([0.0, 125.0]))
    );
    assert_eq!(p[0].controller.fv, Some(0.0));
    assert_eq!(
        (p[1].control, p[1].rms, p[1].band_hz),
        (Control::Acceleration, Some(0.981), Some([0.5, 50.0]))
    );
    assert_eq!(
        (p[2].control, p[2].rms, p[2].band_hz),
        (Control::Acceleration, Some(0.4905), Some([0.5, 125.0]))
    );
    let sines: Vec<(f64, f64)> = p[3..12]
        .iter()
        .map(|t| (t.frequency_hz.unwrap(), t.amplitude_m.unwrap()))
        .collect();
    assert_eq!(
        sines,
        [
            (0.05, 0.05),
            (0.1, 0.05),
            (0.5, 0.05),
            (0.05, 0.1),
            (0.1, 0.1),
            (0.5, 0.1),
            (0.05, 0.2),
            (0.1, 0.2),
            (0.5, 0.2)
        ]
    );
    let tri: Vec<(f64, f64)> = p[12..]
        .iter()
        .map(|t| (t.frequency_hz.unwrap(), t.amplitude_m.unwrap()))
        .collect();
    assert_eq!(
        tri,
        [
            (0.05, 0.05),
            (0.1, 0.05),
            (0.05, 0.1),
            (0.1, 0.1),
            (0.05, 0.2),
            (0.1, 0.2)
        ]
    );
    assert!(p[3..12].iter().all(|t| t.kind == TestKind::Sine));
    assert!(p[12..].iter().all(|t| t.kind == TestKind::Triangle));
}

/// Fourth-order central difference `(-f[k+2] + 8 f[k+1] - 8 f[k-1] + f[k-2]) / (12 h)`.
fn derivative_error(f: &[f64], df: &[f64], h: f64, skip: &dyn Fn(usize) -> bool) -> f64 {
    let mut worst: f64 = 0.0;
    for k in 2..f.len() - 2 {
        if skip(k) {
            continue;
        }
        let d = (-f[k + 2] + 8.0 * f[k + 1] - 8.0 * f[k - 1] + f[k - 2]) / (12.0 * h);
        worst = worst.max((d - df[k]).abs());
    }
    let scale = df.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    worst / scale
}

/// r' and r'' are the derivatives of r: checked by finite differences on the same
/// continuous reference sampled 16x faster (the random reference's bins do not depend on
/// the sample rate, checked too), away from the corners of r'' (where its slope jumps).
#[test]
fn reference_derivatives_are_consistent() {
    let fine = 16.0 * FS;
    let h = 1.0 / fine;
    for name in ["R1", "R2", "R3", "S3", "S7", "T2", "T5"] {
        let (i, spec) = program_test(name);
        let d = 6.0; // short random records keep the test quick; the generator is the same
        let r = reference(&spec, i, 7, d, fine).unwrap();
        let coarse = reference(&spec, i, 7, d, FS).unwrap();
        // the 512 Hz record samples the same continuous signal (up to the RMS scaling,
        // which is computed on the record's own samples)
        let sub: Vec<f64> = (0..coarse.len())
            .map(|k| r.displacement_m[16 * k])
            .collect();
        let c = coarse
            .displacement_m
            .iter()
            .zip(&sub)
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / sub.iter().map(|b| b * b).sum::<f64>();
        assert!((c - 1.0).abs() < 1e-3, "{name}: scale {c}");
        let peak = sub.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (k, &v) in coarse.displacement_m.iter().enumerate() {
            assert!(
                (v - c * sub[k]).abs() <= 1e-9 * peak,
                "{name}: sample {k} differs between 512 Hz and 8192 Hz"
            );
        }
        // where r'' has a corner (its derivative jumps): fade, ramp and blend ends
        let corners: Vec<f64> = match spec.kind {
            TestKind::Random => vec![REST_S, REST_S + FADE_S, REST_S + d - FADE_S, REST_S + d],
            TestKind::Sine => {
                let f = spec.frequency_hz.unwrap();
                let motion = (synth::sine_cycles(f) + 1) as f64 / f;
                let half = 0.5 / f;
                vec![
                    REST_S,
                    REST_S + half,
                    REST_S + motion - half,
                    REST_S + motion,
                ]
            }
            TestKind::Triangle => {
                let period = 1.0 / spec.frequency_hz.unwrap();
                let mut c = vec![REST_S, REST_S + 3.0 * period];
                for j in 0..6 {
                    c.push(REST_S + period / 4.0 + j as f64 * period / 2.0);
                }
                c.iter()
                    .flat_map(|t| [t - BLEND_S / 2.0, t + BLEND_S / 2.0])
                    .collect()
            }
            TestKind::Record => unreachable!("the paper's program has no record test"),
        };
        let skip = |k: usize| {
            let t = k as f64 * h;
            corners.iter().any(|c| (t - c).abs() <= 3.0 * h)
        };
        let e1 = derivative_error(&r.displacement_m, &r.velocity_m_s, h, &skip);
        let e2 = derivative_error(&r.velocity_m_s, &r.acceleration_m_s2, h, &skip);
        println!("{name}: relative FD error r' {e1:.2e}, r'' {e2:.2e}");
        assert!(e1 < 2e-5, "{name}: r' inconsistent with r ({e1:.2e})");
        assert!(e2 < 2e-5, "{name}: r'' inconsistent with r' ({e2:.2e})");
        // every record starts and ends at rest
        for ch in [&r.displacement_m, &r.velocity_m_s, &r.acceleration_m_s2] {
            assert_eq!(ch[0], 0.0);
            assert_eq!(*ch.last().unwrap(), 0.0);
        }
    }
}

/// Power spectrum (one-sided, bins k/T) of a record.
fn power_spectrum(x: &[f64]) -> Vec<f64> {
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(x.len());
    let mut input = x.to_vec();
    let mut out = fft.make_output_vec();
    fft.process(&mut input, &mut out).unwrap();
    out.iter().map(|c| c.norm_sqr()).collect()
}

#[test]
fn r2_has_its_rms_and_band() {
    let (i, spec) = program_test("R2");
    let r = reference(&spec, i, 7, 90.0, FS).unwrap();
    assert_eq!(r.len(), 92 * 512);
    let steady = |x: &[f64]| {
        let a = ((REST_S + FADE_S) * FS) as usize;
        let b = ((REST_S + 90.0 - FADE_S) * FS) as usize;
        x[a..=b].to_vec()
    };
    let acc = steady(&r.acceleration_m_s2);
    let level = rms(&acc);
    assert!((level - 0.981).abs() < 1e-9, "R2 steady RMS {level}");
    // band: the 90 s segment's spectrum sits in 0.5-50 Hz (the fades leak a little)
    let seg = &r.acceleration_m_s2[512..512 + 90 * 512];
    let p = power_spectrum(seg);
    let df = 1.0 / 90.0;
    let total: f64 = p.iter().sum();
    let outside: f64 = p
        .iter()
        .enumerate()
        .filter(|(k, _)| {
            let f = *k as f64 * df;
            !(0.3..=52.0).contains(&f)
        })
        .map(|(_, v)| v)
        .sum();
    println!("R2 power outside 0.3-52 Hz: {:.2e}", outside / total);
    assert!(
        outside / total < 1e-3,
        "R2 leaks {:.2e} of its power",
        outside / total
    );
    // flat: equal power in each 5 Hz sub-band from 5 to 50 Hz
    let band = |lo: f64, hi: f64| -> f64 {
        p.iter()
            .enumerate()
            .filter(|(k, _)| (lo..hi).contains(&(*k as f64 * df)))
            .map(|(_, v)| v)
            .sum()
    };
    let parts: Vec<f64> = (1..10)
        .map(|j| band(5.0 * j as f64, 5.0 * (j + 1) as f64))
        .collect();
    let mean = parts.iter().sum::<f64>() / parts.len() as f64;
    for (j, v) in parts.iter().enumerate() {
        assert!(
            (v / mean - 1.0).abs() < 0.05,
            "R2 sub-band {j} power {:.3} of the mean",
            v / mean
        );
    }
    // the displacement of an acceleration-controlled test is the double integral: no drift
    assert!(r.displacement_m.iter().all(|x| x.abs() < 0.1));
}

#[test]
fn r1_and_r3_have_their_rms() {
    for (name, level) in [("R1", 0.005), ("R3", 0.4905)] {
        let (i, spec) = program_test(name);
        let r = reference(&spec, i, 3, 90.0, FS).unwrap();
        let a = ((REST_S + FADE_S) * FS) as usize;
        let b = ((REST_S + 90.0 - FADE_S) * FS) as usize;
        let ch = match spec.control {
            Control::Displacement => &r.displacement_m,
            Control::Acceleration => &r.acceleration_m_s2,
        };
        let got = rms(&ch[a..=b]);
        assert!((got / level - 1.0).abs() < 1e-9, "{name}: {got}");
    }
}

#[test]
fn triangle_peaks_at_the_amplitude_with_rounded_reversals() {
    for name in ["T1", "T2", "T3", "T4", "T5", "T6"] {
        let (i, spec) = program_test(name);
        let (f, amp) = (spec.frequency_hz.unwrap(), spec.amplitude_m.unwrap());
        let r = reference(&spec, i, 1, 90.0, FS).unwrap();
        let peak = r.displacement_m.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(
            (peak - amp).abs() < 1e-9 * amp,
            "{name}: peak {peak} vs {amp}"
        );
        let max = r.displacement_m.iter().cloned().fold(f64::MIN, f64::max);
        let min = r.displacement_m.iter().cloned().fold(f64::MAX, f64::min);
        assert!((max - amp).abs() < 1e-9 * amp && (min + amp).abs() < 1e-9 * amp);
        // plateau velocity and zero acceleration away from the steps
        let period = 1.0 / f;
        let v = amp / (period / 4.0 - BLEND_S * (0.5 - 1.0 / std::f64::consts::PI));
        let mut steps = vec![REST_S, REST_S + 3.0 * period];
        for j in 0..6 {
            steps.push(REST_S + period / 4.0 + j as f64 * period / 2.0);
        }
        let mut in_blend = 0;
        for k in 0..r.len() {
            let t = k as f64 / FS;
            let near = steps.iter().any(|s| (t - s).abs() < BLEND_S / 2.0);
            if near {
                in_blend += 1;
                continue;
            }
            assert_eq!(r.acceleration_m_s2[k], 0.0, "{name}: r'' at t = {t}");
            let moving = t > REST_S && t < REST_S + 3.0 * period;
            let expect = if moving { v } else { 0.0 };
            assert!(
                (r.velocity_m_s[k].abs() - expect).abs() < 1e-12,
                "{name}: |r'| = {} at t = {t}, expected {expect}",
                r.velocity_m_s[k]
            );
        }
        assert!(in_blend > 0);
        // the acceleration stays finite: peak 2V (pi/2) / Tb at a reversal
        let amax = r
            .acceleration_m_s2
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        assert!((amax / (v * std::f64::consts::PI / BLEND_S) - 1.0).abs() < 1e-3);
    }
}

#[test]
fn sine_reaches_its_amplitude_and_rests() {
    for name in ["S1", "S3", "S9"] {
        let (i, spec) = program_test(name);
        let amp = spec.amplitude_m.unwrap();
        let r = reference(&spec, i, 1, 90.0, FS).unwrap();
        let peak = r.displacement_m.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!((peak / amp - 1.0).abs() < 1e-9, "{name}: peak {peak}");
        let rest = (REST_S * FS) as usize;
        assert!(r.displacement_m[..=rest].iter().all(|&x| x == 0.0));
        assert!(r.displacement_m[r.len() - rest..].iter().all(|&x| x == 0.0));
    }
}

/// The whole default program on the TREES Lab table: 906 s, the valve never saturates
/// (R1 runs with its feed-forward off for this), the stroke stays inside +-0.5 m, and the
/// progress callback reaches the total.
#[test]
fn whole_program_stays_inside_the_tables_limits() {
    let params = Params::trees_lab();
    let last = std::sync::Mutex::new((0u64, 0u64));
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let cb = |done: u64, total: u64| {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let mut l = last.lock().unwrap();
        l.0 = l.0.max(done);
        l.1 = total;
    };
    let c = synthesise(&params, &SynthOptions::default(), Some(&cb));
    assert_eq!(c.records.len(), 18);
    let samples: usize = c.records.iter().map(|r| r.len()).sum();
    assert_eq!(samples as f64 / FS, 906.0);
    assert_eq!(*last.lock().unwrap(), (samples as u64, samples as u64));
    assert_eq!(calls.load(std::sync::atomic::Ordering::Relaxed), 18);
    for (t, r) in c.info.tests.iter().zip(&c.records) {
        let umax = r
            .valve_command
            .as_deref()
            .unwrap()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let xmax = r
            .displacement_m
            .as_deref()
            .unwrap()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(umax < 0.5, "{}: valve command reaches {umax}", t.name);
        assert!(xmax < 0.25, "{}: stroke reaches {xmax} m", t.name);
        if let Some(a) = t.amplitude_m {
            // displacement-controlled periodic tests follow their amplitude within 2 %
            assert!(
                (xmax / a - 1.0).abs() < 0.02,
                "{}: {xmax} m for {a} m",
                t.name
            );
        }
    }
}

fn small_opts(seed: u64, tests: &[&str]) -> SynthOptions {
    SynthOptions {
        seed,
        random_duration_s: 4.0,
        tests: Some(tests.iter().map(|s| s.to_string()).collect()),
        ..SynthOptions::default()
    }
}

fn files_of(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

#[test]
fn same_seed_same_bytes_other_seed_other_bytes() {
    let params = Params::trees_lab();
    let dirs: Vec<tempfile::TempDir> = (0..3).map(|_| tempfile::tempdir().unwrap()).collect();
    for (d, seed) in dirs.iter().zip([7, 7, 8]) {
        let opts = small_opts(seed, &["R2", "S3"]);
        synth::synthesise_to_dir(&params, &opts, d.path(), None).unwrap();
    }
    let a = files_of(dirs[0].path());
    let b = files_of(dirs[1].path());
    let c = files_of(dirs[2].path());
    assert_eq!(
        a.len(),
        5,
        "campaign.toml, truth.toml, synthesis.toml, R2.csv, S3.csv"
    );
    assert!(a == b, "same seed gave different bytes");
    for ((na, ba), (nc, bc)) in a.iter().zip(&c) {
        assert_eq!(na, nc);
        if na.ends_with(".csv") {
            assert_ne!(ba, bc, "{na}: another seed gave the same record");
        }
    }
    // a subset gives the same record as a larger program (independent streams)
    let both = synthesise(&params, &small_opts(7, &["R1", "R2"]), None);
    let alone = synthesise(&params, &small_opts(7, &["R2"]), None);
    assert_eq!(both.test("R2").unwrap().1, alone.test("R2").unwrap().1);
    // and it reads back bit for bit
    let back = read_campaign(dirs[0].path()).unwrap();
    let mem = synthesise(&params, &small_opts(7, &["R2", "S3"]), None);
    assert_eq!(back.records, mem.records);
    assert_eq!(back.info, mem.info);
}

/// Noise estimate from rest: white noise of variance s^2 gives third differences of
/// variance 20 s^2, while the table's own slow motion hardly has any.
fn third_difference_rms(x: &[f64]) -> f64 {
    let d: Vec<f64> = x
        .windows(4)
        .map(|w| w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0])
        .collect();
    rms(&d) / 20f64.sqrt()
}

#[test]
fn noise_is_inside_the_loop() {
    let params = Params::trees_lab();
    let opts = SynthOptions::default();
    let quiet = SynthOptions {
        noise: NoiseLevels::none(),
        ..SynthOptions::default()
    };
    let n = opts.noise;
    let mut rest_samples = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
    for name in ["S3", "S6", "S9", "T2"] {
        let (i, spec) = program_test(name);
        let noisy = synthesise_test(&params, &spec, i, &opts, FS).unwrap();
        let clean = synthesise_test(&params, &spec, i, &quiet, FS).unwrap();
        let rec = &noisy.record;
        // the controller acted on the noise: its command is not the noise-free one
        let du: Vec<f64> = rec
            .valve_command
            .as_deref()
            .unwrap()
            .iter()
            .zip(clean.record.valve_command.as_deref().unwrap())
            .map(|(a, b)| a - b)
            .collect();
        let du_rms = rms(&du);
        // at least the displacement feedback of the LVDT noise, Kp * 2e-5 = 2e-4
        println!("{name}: valve command response to noise {du_rms:.3e}");
        assert!(
            du_rms > 0.8 * params.controller.kp * n.displacement_m,
            "{name}: {du_rms}"
        );
        assert!(
            du_rms < 10.0 * params.controller.kp * n.displacement_m,
            "{name}: {du_rms}"
        );
        // the recorded channels are the truth plus exactly the noise the controller saw
        for k in 0..rec.len() {
            assert_eq!(
                rec.displacement_m.as_deref().unwrap()[k],
                noisy.truth[k].displacement_m + noisy.noise[k].displacement_m
            );
            assert_eq!(
                rec.force_n.as_deref().unwrap()[k],
                noisy.truth[k].actuator_force_n + noisy.noise[k].force_n
            );
        }
        // the reference channels carry no noise
        assert_eq!(rec.ref_displacement_m, clean.record.ref_displacement_m);
        // rest segments: the first 0.9 s and the last 0.9 s
        let m = (0.9 * FS) as usize;
        let len = rec.len();
        for (j, ch) in [
            rec.spool_position.as_ref().unwrap(),
            rec.displacement_m.as_ref().unwrap(),
            rec.acceleration_m_s2.as_ref().unwrap(),
            rec.force_n.as_ref().unwrap(),
        ]
        .into_iter()
        .enumerate()
        {
            rest_samples[j].push(ch[..m].to_vec());
            rest_samples[j].push(ch[len - m..].to_vec());
        }
    }
    for (j, (name, level)) in [
        ("spool", n.spool),
        ("displacement", n.displacement_m),
        ("acceleration", n.acceleration_m_s2),
        ("force", n.force_n),
    ]
    .into_iter()
    .enumerate()
    {
        let parts: Vec<f64> = rest_samples[j]
            .iter()
            .map(|s| third_difference_rms(s).powi(2))
            .collect();
        let est = (parts.iter().sum::<f64>() / parts.len() as f64).sqrt();
        println!("{name}: noise RMS from rest {est:.4e}, option {level:.4e}");
        assert!((est / level - 1.0).abs() < 0.06, "{name}: {est} vs {level}");
    }
}

#[test]
fn spool_noise_is_measurement_only() {
    let params = Params::trees_lab();
    let (i, spec) = program_test("S3");
    let spool_only = SynthOptions {
        noise: NoiseLevels {
            spool: 0.002,
            ..NoiseLevels::none()
        },
        ..SynthOptions::default()
    };
    let quiet = SynthOptions {
        noise: NoiseLevels::none(),
        ..SynthOptions::default()
    };
    let a = synthesise_test(&params, &spec, i, &spool_only, FS).unwrap();
    let b = synthesise_test(&params, &spec, i, &quiet, FS).unwrap();
    assert_eq!(a.record.valve_command, b.record.valve_command);
    assert_eq!(a.record.displacement_m, b.record.displacement_m);
    let e: Vec<f64> = a
        .record
        .spool_position
        .as_ref()
        .unwrap()
        .iter()
        .zip(b.record.spool_position.as_ref().unwrap())
        .map(|(x, y)| x - y)
        .collect();
    assert!(
        (rms(&e) / 0.002 - 1.0).abs() < 0.03,
        "spool noise RMS {}",
        rms(&e)
    );
}

/// R1 runs with the feed-forward off (per-test override): the recorded command is the
/// TVC law of spec section 2 with fv = 0 on the recorded (noise-free) channels.
#[test]
fn r1_runs_with_its_controller_override() {
    let params = Params::trees_lab();
    let opts = SynthOptions {
        noise: NoiseLevels::none(),
        ..small_opts(2, &["R1"])
    };
    let c = synthesise(&params, &opts, None);
    let (spec, rec) = c.test("R1").unwrap();
    let g = c.controller_for(spec).unwrap();
    assert_eq!(g.fv, 0.0);
    assert_eq!(c.info.controller.fv, Some(params.controller.fv));
    let mut worst: f64 = 0.0;
    for k in 0..rec.len() {
        let (x, f, uc) = (
            rec.displacement_m.as_deref().unwrap(),
            rec.force_n.as_deref().unwrap(),
            rec.valve_command.as_deref().unwrap(),
        );
        let u = (g.kp * (rec.ref_displacement_m[k] - x[k]) - g.kdp * f[k]).clamp(-1.0, 1.0);
        worst = worst.max((u - uc[k]).abs());
    }
    assert!(
        worst < 1e-12,
        "valve command differs from the TVC law with fv = 0 by {worst}"
    );
    assert!(rec
        .valve_command
        .as_deref()
        .unwrap()
        .iter()
        .any(|u| u.abs() > 1e-3));
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shaketable"))
}

/// `campaign synth` then `simulate` on one of its records (noise-free) reproduces the
/// record exactly, with the campaign's per-test override picked up from campaign.toml.
#[test]
fn cli_synth_then_simulate_reproduces_the_record() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("camp");
    let st = bin()
        .args([
            "campaign",
            "synth",
            "--seed",
            "3",
            "--no-noise",
            "--quiet",
            "--random-duration",
            "4",
        ])
        .args([
            "--tests",
            "R1,S3",
            "--effect",
            "specimen:mass_kg=20000,frequency_hz=6,damping_ratio=0.02",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let truth = Params::from_file(&out.join("truth.toml")).unwrap();
    assert!(truth.specimen.enabled);
    assert_eq!(truth.specimen.mass_kg, 20000.0);
    let truth_path = out.join("truth.toml");
    for name in ["R1", "S3"] {
        let sim = dir.path().join(format!("{name}-sim.csv"));
        let st = bin()
            .args(["simulate", "--params"])
            .arg(&truth_path)
            .arg("--reference")
            .arg(out.join(format!("{name}.csv")))
            .arg("--out")
            .arg(&sim)
            .output()
            .unwrap();
        assert!(
            st.status.success(),
            "{}",
            String::from_utf8_lossy(&st.stderr)
        );
        let a = read_record(&out.join(format!("{name}.csv")), FS).unwrap();
        let b = read_record(&sim, FS).unwrap();
        assert_eq!(a.valve_command, b.valve_command, "{name}");
        assert_eq!(a.displacement_m, b.displacement_m, "{name}");
        assert_eq!(a.force_n, b.force_n, "{name}");
        assert_eq!(a.extra, b.extra, "{name}");
    }
    // without the campaign, R1 runs with the feed-forward on: its 0-125 Hz reference
    // (2.2 m/s RMS) then saturates the valve and drives the load pressure past the
    // relief level (spec section 8), which the campaign's `fv = 0` override avoids
    let sim = dir.path().join("R1-nocamp.csv");
    let st = bin()
        .args(["simulate", "--no-campaign", "--params"])
        .arg(&truth_path)
        .arg("--reference")
        .arg(out.join("R1.csv"))
        .arg("--out")
        .arg(&sim)
        .output()
        .unwrap();
    assert!(!st.status.success());
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(err.contains("pressure limit"), "{err}");
    assert!(!sim.exists(), "a stopped run leaves no output");
    // the synthesis record names the seed
    let syn = std::fs::read_to_string(out.join("synthesis.toml")).unwrap();
    assert!(syn.contains("seed = 3"), "{syn}");
}

#[test]
fn cli_rejects_bad_options() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        vec!["--tests", "R9"],
        vec!["--noise-force", "-1"],
        vec!["--random-duration", "0.5"],
        vec!["--effect", "specimen:mass=3"],
    ] {
        let st = bin()
            .args(["campaign", "synth", "--quiet"])
            .args(&args)
            .arg(dir.path().join("x"))
            .output()
            .unwrap();
        assert!(!st.status.success(), "{args:?} accepted");
        let err = String::from_utf8_lossy(&st.stderr);
        assert!(err.starts_with("error:"), "{args:?}: {err}");
    }
}
