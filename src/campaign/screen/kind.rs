//! Does a periodic test's data agree with its declaration (issue 14, item 9)? A declared
//! `sine` whose reference is not a sine at its frequency, a declared `triangle` whose
//! reference does not move at one constant speed between reversals or reverses at
//! another frequency, and a force channel whose sign contradicts the energy balance of
//! a periodic test: each excludes the test from estimation with the reason.

use super::{finding, Action, Finding};
use crate::campaign::{Record, TestKind, TestSpec};
use std::f64::consts::PI;

/// A `sine` test's reference must be explained to this fraction of its variance by a
/// sine at the declared frequency (the ramps cost a few percent).
pub const SINE_EXPLAINED_MIN: f64 = 0.8;
/// A triangle moves at one speed between reversals: at least this fraction of its
/// moving samples lie within [`RAMP_SPEED_TOLERANCE`] of their median speed. A sine puts
/// about 15 % of them there, random motion fewer, a triangle with rounded reversals over
/// 85 %: half separates them with a wide margin on both sides.
pub const TRIANGLE_CONSTANT_SPEED_MIN: f64 = 0.5;
/// "The ramp speed": within 10 % of the median speed (the reversal blends and the
/// speed estimate's window take a few percent of the samples out of it).
const RAMP_SPEED_TOLERANCE: f64 = 0.1;
/// A sample moves when its speed exceeds this fraction of the 90th-percentile speed:
/// the rest at either end of a test is left out, the ramps are in.
const MOVING_FRACTION: f64 = 0.2;
/// The reversals of a declared triangle must give its frequency to within 30 %: the
/// count of reversals over the moving time is off by one reversal at most, 25 % for
/// two cycles.
pub const TRIANGLE_FREQUENCY_TOLERANCE: f64 = 0.3;
/// Speeds are differences over 1 % of the declared period: the reference's and the
/// LVDT's noise average out, the reversals blur over 2 % of a cycle.
const SPEED_WINDOW_PERIODS: f64 = 0.01;
/// A periodic test that starts and ends at rest cannot take energy from the table: the
/// net work of the actuator force on the table's motion is what friction and damping
/// dissipate. A force whose net work is negative by more than this fraction of its
/// gross work (sum of |F v|) has the opposite sign convention: a flipped slow test
/// gives -0.5 to -1; a fast, inertia-dominated sine stays near zero either way and is
/// not judged (the random tests' force-acceleration check covers inertia).
pub const NET_WORK_SIGN_MIN: f64 = 0.1;

/// Checks a periodic test's declared kind and its force sign; false to exclude it.
pub fn check_periodic(spec: &TestSpec, r: &Record, fs: f64, out: &mut Vec<Finding>) -> bool {
    let Some(f) = spec.frequency_hz.filter(|f| f.is_finite() && *f > 0.0) else {
        return true;
    };
    let ok = match spec.kind {
        TestKind::Random | TestKind::Record => return true,
        TestKind::Sine => check_sine(&r.ref_displacement_m, f, fs, out),
        TestKind::Triangle => check_triangle(&r.ref_displacement_m, f, fs, out),
    };
    ok && check_force_work(r, f, fs, out)
}

/// A declared `sine` whose reference is not a sine at `f`.
fn check_sine(x: &[f64], f: f64, fs: f64, out: &mut Vec<Finding>) -> bool {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let (mut s, mut c, mut ss, mut cc, mut sc, mut var) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (k, v) in x.iter().enumerate() {
        let ph = 2.0 * PI * f * k as f64 / fs;
        let (a, b) = (ph.sin(), ph.cos());
        let y = v - mean;
        s += y * a;
        c += y * b;
        ss += a * a;
        cc += b * b;
        sc += a * b;
        var += y * y;
    }
    // least squares on [sin, cos]: explained variance
    let det = ss * cc - sc * sc;
    let explained = if det > 0.0 && var > 0.0 {
        let (p, q) = ((cc * s - sc * c) / det, (ss * c - sc * s) / det);
        (p * s + q * c) / var
    } else {
        0.0
    };
    if explained < SINE_EXPLAINED_MIN {
        let msg = format!(
            "declared a sine at {f} Hz but such a sine explains {:.0} % of the reference (at least {:.0} % needed)",
            100.0 * explained.max(0.0),
            100.0 * SINE_EXPLAINED_MIN
        );
        out.push(finding("ref_displacement_m", Action::TestExcluded, msg));
        return false;
    }
    true
}

/// Speed by a centred difference over [`SPEED_WINDOW_PERIODS`] of a period at `f`.
fn speed(x: &[f64], f: f64, fs: f64) -> Vec<f64> {
    let h = ((SPEED_WINDOW_PERIODS * fs / f).round() as usize).clamp(1, x.len() / 4 + 1);
    (0..x.len())
        .map(|k| {
            let (a, b) = (k.saturating_sub(h), (k + h).min(x.len() - 1));
            (x[b] - x[a]) * fs / (b - a).max(1) as f64
        })
        .collect()
}

fn percentile(v: &[f64], q: f64) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return 0.0;
    }
    s.sort_by(f64::total_cmp);
    s[((s.len() - 1) as f64 * q).round() as usize]
}

/// A declared `triangle` whose reference does not ramp at one speed, or reverses at
/// another frequency than `f`.
fn check_triangle(x: &[f64], f: f64, fs: f64, out: &mut Vec<Finding>) -> bool {
    let v = speed(x, f, fs);
    let abs: Vec<f64> = v.iter().map(|s| s.abs()).collect();
    let moving_min = MOVING_FRACTION * percentile(&abs, 0.9);
    let moving: Vec<usize> = (0..v.len()).filter(|&k| abs[k] > moving_min).collect();
    let (Some(&first), Some(&last)) = (moving.first(), moving.last()) else {
        return true; // a flat reference is the flat-channel check's to report
    };
    let speeds: Vec<f64> = moving.iter().map(|&k| abs[k]).collect();
    let ramp = percentile(&speeds, 0.5);
    let on_ramp = speeds
        .iter()
        .filter(|s| (*s / ramp - 1.0).abs() <= RAMP_SPEED_TOLERANCE)
        .count() as f64
        / speeds.len() as f64;
    if on_ramp < TRIANGLE_CONSTANT_SPEED_MIN {
        let msg = format!(
            "declared a triangle but only {:.0} % of its moving samples ramp at one speed (at least {:.0} % needed)",
            100.0 * on_ramp,
            100.0 * TRIANGLE_CONSTANT_SPEED_MIN
        );
        out.push(finding("ref_displacement_m", Action::TestExcluded, msg));
        return false;
    }
    let reversals = reversals(&v[first..=last], 0.5 * ramp);
    let duration_s = (last - first) as f64 / fs;
    if reversals >= 2 && duration_s > 0.0 {
        let f_seen = reversals as f64 / (2.0 * duration_s);
        if (f_seen / f - 1.0).abs() > TRIANGLE_FREQUENCY_TOLERANCE {
            let msg = format!(
                "declared a triangle at {f} Hz but its reference reverses {reversals} times in {duration_s:.1} s ({f_seen:.3} Hz)"
            );
            out.push(finding("ref_displacement_m", Action::TestExcluded, msg));
            return false;
        }
    }
    true
}

/// Sign changes of `v`, with hysteresis at `+-threshold`.
fn reversals(v: &[f64], threshold: f64) -> usize {
    let mut sign = 0.0;
    let mut count = 0;
    for &s in v {
        let now = if s > threshold {
            1.0
        } else if s < -threshold {
            -1.0
        } else {
            continue;
        };
        if sign != 0.0 && now != sign {
            count += 1;
        }
        sign = now;
    }
    count
}

/// The net work of the force on the measured motion against its gross work
/// ([`NET_WORK_SIGN_MIN`]).
fn check_force_work(r: &Record, f: f64, fs: f64, out: &mut Vec<Finding>) -> bool {
    let (Some(x), Some(force_n)) = (r.displacement_m.as_deref(), r.force_n.as_deref()) else {
        return true; // no force or no displacement: no work to check
    };
    let v = speed(x, f, fs);
    let n = force_n.len().min(v.len());
    if n == 0 {
        return true;
    }
    let mean = force_n[..n].iter().sum::<f64>() / n as f64;
    let (mut net, mut gross) = (0.0, 0.0);
    for (force, speed) in force_n[..n].iter().zip(&v) {
        let p = (force - mean) * speed;
        net += p;
        gross += p.abs();
    }
    if gross > 0.0 && net < -NET_WORK_SIGN_MIN * gross {
        let msg = format!(
            "the force's net work on the table's motion is {:.0} % of its gross work: a periodic test from rest to rest must dissipate, so the sign convention is opposite",
            100.0 * net / gross
        );
        out.push(finding("force_n", Action::TestExcluded, msg));
        return false;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::{paper_program, triangle_reference};

    const FS: f64 = 512.0;

    /// The paper program's test `name` (T1: a 0.05 m triangle at 0.05 Hz).
    fn paper_test(name: &str) -> TestSpec {
        paper_program(30.0)
            .into_iter()
            .find(|t| t.name == name)
            .unwrap()
    }

    fn triangle(spec: &TestSpec) -> Vec<f64> {
        triangle_reference(spec, FS).unwrap().displacement_m
    }

    /// Table motion `x` driven by a force of mass, friction and spring (or its negative).
    fn record(x: Vec<f64>, force_sign: f64, frequency_hz: f64) -> Record {
        let v = speed(&x, frequency_hz, FS);
        let a = speed(&v, frequency_hz, FS);
        let force_n = (0..x.len())
            .map(|k| force_sign * (41_000.0 * a[k] + 4000.0 * v[k].signum() + 1e5 * x[k]))
            .collect();
        Record {
            ref_displacement_m: x.clone(),
            displacement_m: Some(x),
            force_n: Some(force_n),
            ..Record::default()
        }
    }

    fn sine(frequency_hz: f64, amplitude_m: f64, seconds: f64) -> Vec<f64> {
        let n = (seconds * FS) as usize;
        (0..n)
            .map(|k| amplitude_m * (2.0 * PI * frequency_hz * k as f64 / FS).sin())
            .collect()
    }

    #[test]
    fn a_triangle_is_a_triangle_and_a_sine_is_not() {
        for name in ["T1", "T4", "T6"] {
            let t = paper_test(name);
            let f = t.frequency_hz.unwrap();
            let mut out = Vec::new();
            assert!(check_triangle(&triangle(&t), f, FS, &mut out), "{out:?}");
            assert!(!check_triangle(&sine(f, 0.1, 3.0 / f), f, FS, &mut out));
            assert!(out[0].message.contains("ramp at one speed"), "{out:?}");
        }
    }

    #[test]
    fn a_triangle_at_another_frequency_is_refused() {
        let t = paper_test("T2");
        let f = t.frequency_hz.unwrap();
        let mut out = Vec::new();
        assert!(!check_triangle(&triangle(&t), 2.0 * f, FS, &mut out));
        assert!(out[0].message.contains("reverses 6 times"), "{out:?}");
        assert!(!check_triangle(&triangle(&t), 0.6 * f, FS, &mut out));
    }

    #[test]
    fn random_motion_declared_a_triangle_is_refused() {
        // a smooth random walk: sum of a few incommensurate sines
        let x: Vec<f64> = (0..(60.0 * FS) as usize)
            .map(|k| {
                let t = k as f64 / FS;
                0.02 * (1.3 * t).sin() + 0.01 * (4.1 * t + 1.0).sin() + 0.005 * (11.7 * t).sin()
            })
            .collect();
        let mut out = Vec::new();
        assert!(!check_triangle(&x, 0.1, FS, &mut out));
    }

    #[test]
    fn a_flipped_force_in_a_slow_test_is_refused_a_fast_sine_is_not_judged() {
        let t = paper_test("T3");
        let f = t.frequency_hz.unwrap();
        let mut out = Vec::new();
        assert!(check_force_work(
            &record(triangle(&t), 1.0, f),
            f,
            FS,
            &mut out
        ));
        assert!(!check_force_work(
            &record(triangle(&t), -1.0, f),
            f,
            FS,
            &mut out
        ));
        assert!(out[0].message.contains("net work"), "{out:?}");
        // a slow sine (0.1 Hz, 0.1 m): friction dominates the work
        let slow = sine(0.1, 0.1, 30.0);
        assert!(check_force_work(
            &record(slow.clone(), 1.0, 0.1),
            0.1,
            FS,
            &mut out
        ));
        assert!(!check_force_work(
            &record(slow, -1.0, 0.1),
            0.1,
            FS,
            &mut out
        ));
        // 8 Hz, 5 mm: inertia's work cancels over cycles and friction's is small: the
        // check cannot tell, so it says nothing rather than guess
        let fast = sine(8.0, 0.005, 5.0);
        let mut out = Vec::new();
        assert!(check_force_work(
            &record(fast.clone(), 1.0, 8.0),
            8.0,
            FS,
            &mut out
        ));
        let flipped = record(fast, -1.0, 8.0);
        assert!(check_force_work(&flipped, 8.0, FS, &mut out), "{out:?}");
    }
}
