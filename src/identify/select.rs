//! Which tests each estimator of section 4 uses, chosen by kind and content, never by
//! name: a laboratory names its tests as it likes. On the paper's program (R1-R3, S1-S9,
//! T1-T6) the rules pick the paper's tests:
//! - **valve** (4.1.1): a random test recording the valve command and the spool;
//!   displacement control first (a small displacement over a wide band keeps the loop
//!   linear: the paper's R1), then the widest band.
//! - **mass** (4.1.2): acceleration control first (the apparent mass needs the
//!   acceleration well above its noise), then the strongest measured acceleration
//!   (friction matters least: the paper's R2, 0.1 g).
//! - **oil column** (4.1.3): a test other than the mass test with the spool first, then
//!   acceleration control, then the widest band (the oil column at 14 Hz needs excitation
//!   well above it: R3, 125 Hz).
//! - **validation** (5): the mass test, else the oil-column test.
//! - **Bouc-Wen friction** (4.2.3): the sines whose inertia force `M A (2 pi f)^2` is at
//!   most [`SLOW_SINE_INERTIA_RATIO`] times the friction (S1, S2, S4, S5, S7, S8).
//! - **loop mass** (4.2.2): the other sines, where inertia dominates (S3, S6, S9).
//! - **stiffness and sliding friction** (4.2.1): every triangle test.
//! - **device force** (eqs. 4.14-4.15 plus viscous, elastic and inertia terms): fitted on
//!   a test with displacement and force, broadband first (a random or recorded motion
//!   holds many amplitudes and speeds: friction and viscosity separate), then the longest;
//!   checked on every other test with both channels.

use crate::campaign::{Campaign, Control, Measured, TestKind, TestSpec};
use std::f64::consts::PI;

/// A sine is slow (friction shows, inertia does not) when its inertia force amplitude is
/// at most this many times the friction force: the paper's slow sines reach 0.8, its fast
/// ones 5 and more; 2 sits between with margin on both sides.
pub const SLOW_SINE_INERTIA_RATIO: f64 = 2.0;

/// The channels each random-test estimator needs (a test without them cannot take the
/// role): the valve's FRF command -> spool; the apparent mass force over acceleration; the
/// oil column command -> force (with the spool as instrument) and the apparent mass.
pub const VALVE_NEEDS: &[Measured] = &[Measured::ValveCommand, Measured::Spool];
pub const MASS_NEEDS: &[Measured] = &[Measured::Acceleration, Measured::Force];
pub const OIL_COLUMN_NEEDS: &[Measured] = &[
    Measured::ValveCommand,
    Measured::Acceleration,
    Measured::Force,
];

/// The device estimator's channels.
pub const DEVICE_NEEDS: &[Measured] = &[Measured::Displacement, Measured::Force];

/// The device tests (indices into the campaign): the one fitted, the ones checked.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DeviceRoles {
    pub fit: usize,
    pub others: Vec<usize>,
}

/// The device tests of `c` (see the module doc), `None` when no test records
/// displacement and force.
pub fn device_roles(c: &Campaign) -> Option<DeviceRoles> {
    let with: Vec<usize> = (0..c.info.tests.len())
        .filter(|&i| c.records[i].has_all(DEVICE_NEEDS))
        .collect();
    let broadband = |i: usize| matches!(c.info.tests[i].kind, TestKind::Random | TestKind::Record);
    let fit = best_by(&with, |i| (broadband(i), true, c.records[i].len() as f64))?;
    Some(DeviceRoles {
        fit,
        others: with.into_iter().filter(|&i| i != fit).collect(),
    })
}

/// The random tests' roles (indices into the campaign).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RandomRoles {
    pub valve: Option<usize>,
    pub mass: Option<usize>,
    pub oil_column: Option<usize>,
}

impl RandomRoles {
    /// The validation test: the mass test, else the oil-column test.
    pub fn validation(&self) -> Option<usize> {
        self.mass.or(self.oil_column)
    }

    /// The test taking `role`, if one does.
    pub fn of(&self, role: RandomRole) -> Option<usize> {
        match role {
            RandomRole::Valve => self.valve,
            RandomRole::Mass => self.mass,
            RandomRole::OilColumn => self.oil_column,
        }
    }
}

/// A random test's role in section 4 (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RandomRole {
    /// 4.1.1: command to spool, a small displacement over a wide band (R1).
    Valve,
    /// 4.1.2: the apparent mass, under acceleration control (R2).
    Mass,
    /// 4.1.3: the oil column, excited well above 14 Hz (R3).
    OilColumn,
}

/// Upper edge of the `i`-th test's band: declared, else the Nyquist frequency of the
/// test's own rate (a lab's white noise to its controller's limit, which sampling bounds).
fn band_top_hz(c: &Campaign, i: usize) -> f64 {
    c.info.tests[i]
        .band_hz
        .map_or(c.sample_rate_of(i) / 2.0, |b| b[1])
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// The first of `candidates` by the ranking `key` (lexicographic, greater is better; ties:
/// campaign order).
fn best_by(candidates: &[usize], key: impl Fn(usize) -> (bool, bool, f64)) -> Option<usize> {
    candidates.iter().copied().fold(None, |best, i| match best {
        Some(b) if key(i).partial_cmp(&key(b)) != Some(std::cmp::Ordering::Greater) => Some(b),
        _ => Some(i),
    })
}

/// The random tests' roles in `c` (see the module doc). A test may take several roles
/// when the campaign has no other (one white-noise test gives the valve, the mass and
/// the oil column); the oil column avoids the mass test when another test can serve.
pub fn random_roles(c: &Campaign) -> RandomRoles {
    roles_recording(c, [VALVE_NEEDS, MASS_NEEDS, OIL_COLUMN_NEEDS])
}

/// The random tests' roles by what they excite alone (control, band, strength), whatever
/// channels they recorded: where an effect's signature lives in the diagnosis, which must
/// not move to other tests when a channel is missing (a clean table recorded by its
/// displacement alone lost the mass test from flow asymmetry's tests, and the fit on the
/// fast sines alone named an asymmetry of 0.94).
pub fn excitation_roles(c: &Campaign) -> RandomRoles {
    roles_recording(c, [&[], &[], &[]])
}

/// The random tests' roles among the tests recording what each role `needs` (valve, mass,
/// oil column).
fn roles_recording(c: &Campaign, needs: [&'static [Measured]; 3]) -> RandomRoles {
    let [valve_needs, mass_needs, oil_column_needs] = needs;
    let random: Vec<usize> = (0..c.info.tests.len())
        .filter(|&i| c.info.tests[i].kind == TestKind::Random)
        .collect();
    let has_spool = |i: usize| c.records[i].spool_position.is_some();
    let control = |i: usize| c.info.tests[i].control;
    let recording = |needs: &'static [Measured]| -> Vec<usize> {
        random
            .iter()
            .copied()
            .filter(|&i| c.records[i].has_all(needs))
            .collect()
    };
    let with_spool = recording(valve_needs);
    let valve = best_by(&with_spool, |i| {
        (control(i) == Control::Displacement, true, band_top_hz(c, i))
    });
    let mass = best_by(&recording(mass_needs), |i| {
        let strength = rms(c.records[i]
            .acceleration_m_s2
            .as_deref()
            .unwrap_or_default());
        (control(i) == Control::Acceleration, true, strength)
    });
    let oil_column = best_by(&recording(oil_column_needs), |i| {
        let band = band_top_hz(c, i);
        (
            Some(i) != mass && has_spool(i),
            control(i) == Control::Acceleration,
            band,
        )
    });
    RandomRoles {
        valve,
        mass,
        oil_column,
    }
}

/// The sine tests of `c` split into slow (friction) and fast (inertia) ones, by their
/// declared amplitude and frequency against a table of `mass_kg` with `friction_n`.
pub fn sine_roles(c: &Campaign, mass_kg: f64, friction_n: f64) -> (Vec<String>, Vec<String>) {
    let names = |v: Vec<usize>| {
        v.into_iter()
            .map(|i| c.info.tests[i].name.clone())
            .collect()
    };
    let (slow, fast) = sine_split(c, mass_kg, friction_n);
    (names(slow), names(fast))
}

/// [`sine_roles`] as indices into the campaign, in campaign order.
pub fn sine_split(c: &Campaign, mass_kg: f64, friction_n: f64) -> (Vec<usize>, Vec<usize>) {
    let sines = (0..c.info.tests.len()).filter(|&i| c.info.tests[i].kind == TestKind::Sine);
    sines.partition(|&i| {
        let s = &c.info.tests[i];
        let w = 2.0 * PI * s.frequency_hz.unwrap_or(0.0);
        let inertia = mass_kg * s.amplitude_m.unwrap_or(0.0).abs() * w * w;
        inertia <= SLOW_SINE_INERTIA_RATIO * friction_n.abs()
    })
}

/// Peak velocity of a periodic test from its declared frequency and amplitude, m/s: `2 pi
/// f A` for a sine, `4 f A` for a triangle; `None` for other kinds or undeclared values.
pub fn peak_velocity_m_s(spec: &TestSpec) -> Option<f64> {
    let (f, a) = (spec.frequency_hz?, spec.amplitude_m?.abs());
    match spec.kind {
        TestKind::Sine => Some(2.0 * PI * f * a),
        TestKind::Triangle => Some(4.0 * f * a),
        _ => None,
    }
}

/// Two peak velocities this close (relative) are equal: the paper's 0.1 Hz x 5 cm and
/// 0.05 Hz x 10 cm differ only by rounding.
const SAME_VELOCITY: f64 = 1e-9;

/// `tests` (periodic, with declared frequency and amplitude) slowest first: by peak
/// velocity, and at the same velocity the lower frequency (the longer stroke) first.
/// Tests without a peak velocity are left out.
pub fn slowest_first(c: &Campaign, tests: &[usize]) -> Vec<usize> {
    let mut keyed: Vec<(f64, f64, usize)> = tests
        .iter()
        .filter_map(|&i| {
            let s = &c.info.tests[i];
            Some((peak_velocity_m_s(s)?, s.frequency_hz?, i))
        })
        .collect();
    keyed.sort_by(|a, b| {
        if (a.0 - b.0).abs() <= SAME_VELOCITY * a.0.abs().max(b.0.abs()) {
            a.1.total_cmp(&b.1)
        } else {
            a.0.total_cmp(&b.0)
        }
    });
    keyed.into_iter().map(|k| k.2).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::{synthesise, SynthOptions};
    use crate::params::Params;

    fn paper_campaign_renamed() -> Campaign {
        let opts = SynthOptions {
            random_duration_s: 12.0,
            ..SynthOptions::default()
        };
        let mut c = synthesise(&Params::trees_lab(), &opts, None);
        // a lab's names, in another order: the roles must not care
        for (k, t) in c.info.tests.iter_mut().enumerate() {
            t.name = format!("run_{:02}_{}", 17 - k, t.name.to_lowercase());
        }
        c
    }

    #[test]
    fn the_paper_tests_are_found_under_any_name() {
        let c = paper_campaign_renamed();
        let name = |i: Option<usize>| i.map(|i| c.info.tests[i].name.clone()).unwrap_or_default();
        let r = random_roles(&c);
        assert!(name(r.valve).ends_with("_r1"), "{}", name(r.valve));
        assert!(name(r.mass).ends_with("_r2"), "{}", name(r.mass));
        assert!(
            name(r.oil_column).ends_with("_r3"),
            "{}",
            name(r.oil_column)
        );
        assert_eq!(r.validation(), r.mass);
        let (slow, fast) = sine_roles(&c, 41_258.0, 4_000.0);
        let tail = |v: &[String]| {
            v.iter()
                .map(|n| n.rsplit('_').next().unwrap().to_string())
                .collect::<Vec<_>>()
        };
        assert_eq!(tail(&slow), ["s1", "s2", "s4", "s5", "s7", "s8"]);
        assert_eq!(tail(&fast), ["s3", "s6", "s9"]);
    }

    #[test]
    fn without_a_spool_there_is_no_valve_test_and_heavier_friction_makes_sines_slow() {
        let mut c = paper_campaign_renamed();
        for r in &mut c.records {
            r.spool_position = None;
        }
        let r = random_roles(&c);
        assert_eq!(r.valve, None);
        // R2 still takes the mass role, R3 the oil column (whose estimator then names
        // the missing spool)
        assert!(c.info.tests[r.mass.unwrap()].name.ends_with("_r2"));
        assert!(c.info.tests[r.oil_column.unwrap()].name.ends_with("_r3"));
        // ten times the friction: the 0.5-Hz, 5-cm sine (inertia 20 kN) becomes slow
        let (slow, _) = sine_roles(&c, 41_258.0, 40_000.0);
        assert!(slow.iter().any(|n| n.ends_with("_s3")));
    }
}
