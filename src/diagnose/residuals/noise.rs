//! The noise floor per channel, estimated from the data (rest segments and the
//! high-frequency content), never from a generator's settings.

use super::channels::{Channel, PerChannel};
use crate::campaign::Campaign;
use crate::identify::signals::{centred_rms, fourth_difference_rms};
use crate::SensorNoise;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;

/// Noise per channel, estimated from the data (never from a generator's settings).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct NoiseFloor {
    /// The floor, in which residuals are counted: what a noise-free simulation cannot
    /// predict at rest, i.e. the sensor noise plus the loop's response to it (the
    /// oil-column resonance makes the latter several times the former in acceleration
    /// and force). Displacement (LVDT), m. `None` (JSON `null`) for a channel no test
    /// recorded.
    pub displacement_m: Option<f64>,
    pub acceleration_m_s2: Option<f64>,
    pub force_n: Option<f64>,
    pub spool: Option<f64>,
    /// The command at rest: the controller's response to the feedback noise (the
    /// command itself is recorded without measurement noise).
    pub valve_command: Option<f64>,
    /// The sensor noise alone (white), which the noisy runs of [`predict`] feed into the
    /// loop and which bounds every window's predicted spread from below.
    pub sensor: SensorLevels,
    /// How it was estimated.
    pub method: &'static str,
}

/// White sensor-noise RMS of the measured channels, `None` (JSON `null`) for a sensor no
/// test recorded.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SensorLevels {
    pub displacement_m: Option<f64>,
    pub acceleration_m_s2: Option<f64>,
    pub force_n: Option<f64>,
    pub spool: Option<f64>,
}

impl NoiseFloor {
    /// Noise floor of channel `ch` (the residual's unit); `None` when no test recorded
    /// the channel.
    pub fn of(&self, ch: Channel) -> Option<f64> {
        let floor = match ch {
            Channel::Displacement => self.displacement_m,
            Channel::Acceleration => self.acceleration_m_s2,
            Channel::Force => self.force_n,
            Channel::Spool => self.spool,
            Channel::ValveCommand => self.valve_command,
        };
        floor.filter(|x| x.is_finite())
    }

    /// Measurement noise of channel `ch` alone (the command has none: its spread is the
    /// loop's response, which the noisy run predicts); `None` for a sensor no test
    /// recorded.
    pub fn measurement(&self, ch: Channel) -> Option<f64> {
        let s = &self.sensor;
        match ch {
            Channel::Displacement => s.displacement_m,
            Channel::Acceleration => s.acceleration_m_s2,
            Channel::Force => s.force_n,
            Channel::Spool => s.spool,
            Channel::ValveCommand => Some(0.0),
        }
    }

    /// Seeded sensor noise at the sensor levels for a record of `n` samples (the feedback
    /// channels only, as on the table; spec section 2).
    pub fn loop_noise(&self, n: usize, seed: u64) -> Vec<SensorNoise> {
        let s = &self.sensor;
        white_loop_noise([s.displacement_m, s.acceleration_m_s2, s.force_n], n, seed)
    }
}

/// `n` samples of seeded white noise of RMS `[LVDT, accelerometer, force]` on the
/// feedback sensors. A sensor without a level (no test recorded it) feeds the loop none,
/// rather than a guess (a campaign without an accelerometer, issue 16 part 5).
pub(super) fn white_loop_noise(rms: [Option<f64>; 3], n: usize, seed: u64) -> Vec<SensorNoise> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let [d, a, f] = rms.map(|x| x.filter(|x| x.is_finite()).unwrap_or(0.0));
    (0..n)
        .map(|_| SensorNoise {
            displacement_m: d * normal.sample(&mut rng),
            acceleration_m_s2: a * normal.sample(&mut rng),
            force_n: f * normal.sample(&mut rng),
        })
        .collect()
}

/// [`NoiseFloor::method`]: the floor from the rest segments (a macro, so that the text
/// with the LVDT's inference can extend it: [`super::unrecorded`]).
macro_rules! from_rest {
    () => {
        "floor from the rest segments (the recorded references held) at the start of the tests; sensor noise from the high-frequency content"
    };
}
pub(super) use from_rest;
const FROM_REST: &str = from_rest!();

/// [`NoiseFloor::method`]: no rest segment in any test.
const FROM_HIGH_FREQUENCIES: &str =
    "floor and sensor noise from the high-frequency content (fourth difference; no rest segment)";

/// The median of the finite values of `v` (the upper middle of an even count); NaN when
/// none is finite.
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Lower bounds of the noise estimates, so that a noise-free record does not divide by
/// zero: orders of magnitude below any real sensor's noise (the TREES Lab LVDT's is 20 um),
/// so only a noise-free record reaches them.
mod lower_bound {
    /// LVDT, m (1 nm).
    pub const DISPLACEMENT_M: f64 = 1e-9;
    /// Accelerometer, m/s^2.
    pub const ACCELERATION_M_S2: f64 = 1e-6;
    /// Load cell, N (1 mN).
    pub const FORCE_N: f64 = 1e-3;
    /// Spool, of the rated opening.
    pub const SPOOL: f64 = 1e-7;
    /// The valve command's floor, in the command's unit.
    pub const VALVE_COMMAND: f64 = 1e-7;
}

/// Lower bound of a sensor's noise estimate ([`lower_bound`]; `None` for the command,
/// which no sensor reads).
fn sensor_lower_bound(ch: Channel) -> Option<f64> {
    match ch {
        Channel::Displacement => Some(lower_bound::DISPLACEMENT_M),
        Channel::Acceleration => Some(lower_bound::ACCELERATION_M_S2),
        Channel::Force => Some(lower_bound::FORCE_N),
        Channel::Spool => Some(lower_bound::SPOOL),
        Channel::ValveCommand => None,
    }
}

/// Noise of every channel, from the data only. The floor: the rest segments at the start
/// of the tests ([`Campaign::rest_segment`]), median over tests.
/// The sensor noise: the high-frequency content (fourth difference, median over tests),
/// which the loop's response (below 50 Hz) does not reach. A channel without a rest
/// segment in any test has the sensor noise as its floor (the command's from the gains).
pub fn estimate_noise(c: &Campaign) -> NoiseFloor {
    use Channel::*;
    let (hf, rest) = median_estimates(c);
    // every recorded channel has its rest segments where any has (one reference)
    let have_rest = Channel::ALL.iter().any(|&ch| rest[ch].is_finite());
    let method = if have_rest {
        FROM_REST
    } else {
        FROM_HIGH_FREQUENCIES
    };
    // none where no test recorded the sensor
    let sensor = PerChannel::from_fn(|ch| match sensor_lower_bound(ch) {
        Some(lower) if hf[ch].is_finite() => Some(hf[ch].max(lower)),
        _ => None,
    });
    // the floor is never below the sensor noise (the command's: the loop's response to it)
    let floor = |ch: Channel, below: Option<f64>| {
        if rest[ch].is_finite() {
            Some(below.map_or(rest[ch], |b| rest[ch].max(b)))
        } else {
            below
        }
    };
    NoiseFloor {
        displacement_m: floor(Displacement, sensor[Displacement]),
        acceleration_m_s2: floor(Acceleration, sensor[Acceleration]),
        force_n: floor(Force, sensor[Force]),
        spool: floor(Spool, sensor[Spool]),
        valve_command: Some(
            floor(ValveCommand, command_from_gains(c, &sensor))
                .unwrap_or(lower_bound::VALVE_COMMAND)
                .max(lower_bound::VALVE_COMMAND),
        ),
        sensor: SensorLevels {
            displacement_m: sensor[Displacement],
            acceleration_m_s2: sensor[Acceleration],
            force_n: sensor[Force],
            spool: sensor[Spool],
        },
        method,
    }
}

/// Per channel, the median over tests of the high-frequency noise estimate (the sensors
/// only: fourth difference) and of the rest segments' RMS; NaN where no test gives one.
fn median_estimates(c: &Campaign) -> (PerChannel<f64>, PerChannel<f64>) {
    let mut rest_est: PerChannel<Vec<f64>> = Default::default();
    let mut hf_est: PerChannel<Vec<f64>> = Default::default();
    for (i, r) in c.records.iter().enumerate() {
        let rest = c.rest_segment(i);
        for ch in Channel::ALL {
            if let Some(m) = ch.measured(r) {
                if sensor_lower_bound(ch).is_some() {
                    hf_est[ch].push(fourth_difference_rms(m));
                }
                if let Some(rest) = rest.clone() {
                    rest_est[ch].push(centred_rms(&m[rest]));
                }
            }
        }
    }
    (hf_est.map(median), rest_est.map(median))
}

/// The command's noise from the gains: the controller's response to the feedback sensors'
/// noise (`sensor`), independent terms adding in power; `None` when a sensor it needs
/// has no level.
fn command_from_gains(c: &Campaign, sensor: &PerChannel<Option<f64>>) -> Option<f64> {
    use Channel::*;
    // the gains are known: `diagnose` refuses a campaign without them
    let k = &c.info.controller;
    let gain = |g: Option<f64>| g.unwrap_or(0.0);
    Some(
        ((gain(k.kp) * sensor[Displacement]?).powi(2)
            + (gain(k.ka) * sensor[Acceleration]?).powi(2)
            + (gain(k.kdp) * sensor[Force]?).powi(2))
        .sqrt(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::provenance::{ChannelSource, Source, Sources};
    use crate::campaign::synth::{short_campaign, REST_S, SAMPLE_RATE_HZ};
    use crate::campaign::Control;

    /// A test's rest segment is where its recorded references hold their first value:
    /// derivatives computed here ring about rest and do not end it, and a rest at an
    /// offset counts; the floor then comes from the rest segments.
    #[test]
    fn the_rest_segment_is_read_off_the_recorded_references() {
        let mut c = short_campaign(&crate::params::Params::trees_lab(), &["R1"], 2.0);
        assert_eq!(c.info.tests[0].control, Control::Displacement);
        let rest = (REST_S * SAMPLE_RATE_HZ) as usize;
        assert!(c.rest_samples(0) >= rest);
        let r = &mut c.records[0];
        r.ref_displacement_m.iter_mut().for_each(|x| *x += 0.01);
        r.ref_velocity_m_s[1] = 1e-9;
        assert_eq!(c.rest_samples(0), 1, "an uncomputed velocity that moves");
        let sources = Sources {
            channels: ["ref_velocity_m_s", "ref_acceleration_m_s2"]
                .map(|ch| ChannelSource {
                    channel: ch.into(),
                    source: Source::computed_reference(Control::Displacement, ch),
                })
                .into(),
            unread_columns: Vec::new(),
        };
        c.sources.insert(c.info.tests[0].name.clone(), sources);
        assert!(c.rest_samples(0) >= rest);
        assert_eq!(estimate_noise(&c).method, FROM_REST);
    }
}
