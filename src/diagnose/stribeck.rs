//! The friction-velocity (Stribeck) curve read off slow tests: the data start of the
//! `stick_slip` fit (spec section 7).
//!
//! In a slow sine or triangle the table's own equation (paper eq. 4.13) gives the friction
//! from the measured channels: `F_D = F_A - M a - K x`. Once the table has slid a few
//! yield displacements in one direction the Bouc-Wen variable is saturated (`|Z| = 1`,
//! eq. 4.15), so `F_D sign(v)` is the friction amplitude at that speed,
//! `F_mu (1 + (r_s - 1) exp(-(v/v_s)^2))`. Averaged in speed bins over every slow cycle
//! it is the curve itself, and a three-parameter fit gives `(F_mu, r_s, v_s)`. The
//! predictive score sees the static ratio and the Stribeck velocity mostly through the
//! chatter, where they trade off; the curve separates them (the level at rest against the
//! width), so the score's fit starts in the right valley.

use super::Part;
use crate::campaign::{Campaign, TestKind};
use crate::identify::lsq::{minimise, LsqOptions};
use crate::params::Params;

/// Speed bin edges, m/s: fine below 6 mm/s, where the plausible Stribeck velocities
/// (1-10 mm/s) put the curve's knee, coarser up to 60 mm/s for the kinetic level.
const BIN_EDGES_M_S: [f64; 18] = [
    0.0, 5e-4, 1e-3, 1.5e-3, 2e-3, 3e-3, 4e-3, 5e-3, 6e-3, 8e-3, 1e-2, 1.2e-2, 1.5e-2, 2e-2,
    2.5e-2, 3e-2, 4e-2, 6e-2,
];
/// A bin needs this many samples to count (its mean is then good to a few percent of
/// the sensor noise).
const MIN_BIN_SAMPLES: usize = 20;
/// Half-width of the velocity estimator, samples: the slope of a straight line fitted
/// over 41 samples (80 ms at 512 Hz), which is also the first derivative of a local
/// quadratic (Savitzky-Golay). With the LVDT's 20 um noise it reads the speed to about
/// 0.5 mm/s.
const SLOPE_HALF_WIDTH: usize = 20;
/// Sliding, in yield displacements, after which `|Z|` counts as saturated.
const SATURATED_YIELDS: f64 = 4.0;

/// Fewest speed bins a curve needs for its three-parameter fit.
const MIN_CURVE_BINS: usize = 4;
/// The fit's start of the Stribeck velocity, m/s: 5 mm/s, mid-range of the plausible
/// knees (1-10 mm/s, [`BIN_EDGES_M_S`]).
const START_STRIBECK_M_S: f64 = 5e-3;
/// The friction amplitude's range in the fit, as multiples of the fastest bin's level
/// (the kinetic friction the curve reaches there): wide, the curve's start is only read
/// off two bins.
const AMPLITUDE_RANGE: [f64; 2] = [0.2, 5.0];
/// The static ratio's range in the fit (and of its start): the `stick_slip` effect's
/// fitting bounds ([`crate::effects::stick_slip`]).
const RATIO_RANGE: [f64; 2] = [1.0, 6.0];
/// The Stribeck velocity's range in the fit, m/s: the effect's fitting bounds.
const STRIBECK_RANGE_M_S: [f64; 2] = [1e-4, 0.05];
/// Iteration cap of the curve's fit: three parameters on at most 17 bins, each
/// evaluation a closed form, so the cap only stops a fit that does not converge.
const FIT_ITERATIONS: usize = 50;
/// The fit stops at a step gaining less than this share of its cost (the least-squares
/// default: the fit is cheap, so it runs to convergence).
const FIT_TOLERANCE: f64 = 1e-10;
/// Relative finite-difference step of the fit's Jacobian.
const FIT_STEP: f64 = 1e-6;

/// One speed bin of the measured curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// Mean speed in the bin, m/s.
    pub speed_m_s: f64,
    /// Mean friction amplitude `F_D sign(v)`, N.
    pub friction_n: f64,
    pub samples: usize,
}

/// The measured friction-velocity curve over the fitting halves of the sine and triangle
/// tests among `tests`, with `base`'s mass, stiffness and yield displacement. Empty when
/// the tests never slide slowly.
pub fn measured_curve(c: &Campaign, base: &Params, tests: &[usize]) -> Vec<CurvePoint> {
    let mut bins = SpeedBins::new();
    let saturated_m = SATURATED_YIELDS * base.friction.yield_displacement_m;
    for &i in tests {
        if c.info.tests[i].kind == TestKind::Random {
            continue;
        }
        if let Some(test) = SlowTest::read(c, i) {
            test.add_to(&mut bins, base, saturated_m);
        }
    }
    bins.points()
}

/// Sum of `k^2` for `k = -h..=h` (`h` = [`SLOPE_HALF_WIDTH`]): the slope estimator's
/// normaliser.
const SLOPE_NORM: f64 =
    (SLOPE_HALF_WIDTH * (SLOPE_HALF_WIDTH + 1) * (2 * SLOPE_HALF_WIDTH + 1)) as f64 / 3.0;

/// The speed at sample `k` of `x` sampled at `fs_hz`: the slope of the straight line
/// fitted over [`SLOPE_HALF_WIDTH`] samples either side, m/s.
fn slope_speed(x: &[f64], k: usize, fs_hz: f64) -> f64 {
    let h = SLOPE_HALF_WIDTH;
    (1..=h)
        .map(|j| j as f64 * (x[k + j] - x[k - j]))
        .sum::<f64>()
        * fs_hz
        / SLOPE_NORM
}

/// The sums per speed bin ([`BIN_EDGES_M_S`]): speed, friction amplitude, samples.
struct SpeedBins {
    sum: Vec<(f64, f64, usize)>,
}

impl SpeedBins {
    fn new() -> SpeedBins {
        SpeedBins {
            sum: vec![(0.0, 0.0, 0usize); BIN_EDGES_M_S.len() - 1],
        }
    }

    /// Add a sample of speed `speed_m_s` (its magnitude) and friction amplitude
    /// `friction_n` (signed by the motion) to its bin; a speed beyond the bins is dropped.
    fn add(&mut self, speed_m_s: f64, friction_n: f64) {
        let Some(b) = BIN_EDGES_M_S
            .windows(2)
            .position(|e| (e[0]..e[1]).contains(&speed_m_s))
        else {
            return;
        };
        self.sum[b].0 += speed_m_s;
        self.sum[b].1 += friction_n;
        self.sum[b].2 += 1;
    }

    /// The mean of each bin with at least [`MIN_BIN_SAMPLES`].
    fn points(self) -> Vec<CurvePoint> {
        self.sum
            .into_iter()
            .filter(|s| s.2 >= MIN_BIN_SAMPLES)
            .map(|(v, f, n)| CurvePoint {
                speed_m_s: v / n as f64,
                friction_n: f / n as f64,
                samples: n,
            })
            .collect()
    }
}

/// The channels of one slow test the friction balance needs, and its fitting half.
struct SlowTest<'a> {
    displacement_m: &'a [f64],
    acceleration_m_s2: &'a [f64],
    force_n: &'a [f64],
    fs_hz: f64,
    fit: std::ops::Range<usize>,
}

impl<'a> SlowTest<'a> {
    /// Test `i` of `c`; `None` without displacement, acceleration and force (the friction
    /// balance needs the three) or with a fitting half too short for the slope.
    fn read(c: &'a Campaign, i: usize) -> Option<SlowTest<'a>> {
        let r = &c.records[i];
        let (Some(displacement_m), Some(acceleration_m_s2), Some(force_n)) = (
            r.displacement_m.as_deref(),
            r.acceleration_m_s2.as_deref(),
            r.force_n.as_deref(),
        ) else {
            return None;
        };
        let fit = Part::Fit.range(r.len());
        (fit.len() > 2 * SLOPE_HALF_WIDTH + 1).then_some(SlowTest {
            displacement_m,
            acceleration_m_s2,
            force_n,
            fs_hz: c.sample_rate_of(i),
            fit,
        })
    }

    /// Add the friction amplitude `F_D sign(v) = (F_A - M a - K x) sign(v)` (eq. 4.13) of
    /// every sample slid `saturated_m` past its last reversal (`|Z| = 1`, eq. 4.15) to
    /// `bins`, with `base`'s mass and stiffness.
    fn add_to(&self, bins: &mut SpeedBins, base: &Params, saturated_m: f64) {
        let h = SLOPE_HALF_WIDTH;
        let xs = self.displacement_m;
        let x = &xs[self.fit.clone()];
        let mut turned_at = x[h];
        let mut last_sign = 0.0;
        for k in h..x.len() - h {
            let v = slope_speed(x, k, self.fs_hz);
            let sign = v.signum();
            if sign != last_sign {
                turned_at = x[k];
                last_sign = sign;
            }
            if (x[k] - turned_at).abs() < saturated_m {
                continue;
            }
            let n = self.fit.start + k;
            let friction = self.force_n[n]
                - base.table.mass_kg * self.acceleration_m_s2[n]
                - base.table.stiffness_n_m * xs[n];
            bins.add(v.abs(), friction * sign);
        }
    }
}

/// The friction-velocity curve's parameters, `F_mu (1 + (r_s - 1) exp(-(v/v_s)^2))`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveFit {
    /// The kinetic friction amplitude `F_mu`, N.
    pub kinetic_n: f64,
    /// The static ratio `r_s`.
    pub static_ratio: f64,
    /// The Stribeck velocity `v_s`, m/s.
    pub stribeck_velocity_m_s: f64,
}

/// The curve fitted to the measured one (each bin weighted by its samples), or None when
/// the curve has too few bins or no fit converges. A curve without a static peak gives
/// `r_s` near 1.
pub fn fit_curve(curve: &[CurvePoint]) -> Option<CurveFit> {
    if curve.len() < MIN_CURVE_BINS {
        return None;
    }
    let model = |t: &[f64], v: f64| t[0] * (1.0 + (t[1] - 1.0) * (-(v / t[2]).powi(2)).exp());
    let kinetic = curve.last()?.friction_n;
    let at_rest = curve[0].friction_n;
    if !(kinetic > 0.0 && at_rest.is_finite()) {
        return None;
    }
    let [ratio_lo, ratio_hi] = RATIO_RANGE;
    let start = [
        kinetic,
        (at_rest / kinetic).clamp(ratio_lo, ratio_hi),
        START_STRIBECK_M_S,
    ];
    let [amplitude_lo, amplitude_hi] = AMPLITUDE_RANGE;
    let [stribeck_lo, stribeck_hi] = STRIBECK_RANGE_M_S;
    let fit = minimise(
        |t| {
            Some(
                curve
                    .iter()
                    .map(|p| (p.friction_n - model(t, p.speed_m_s)) * (p.samples as f64).sqrt())
                    .collect(),
            )
        },
        &start,
        &[amplitude_lo * kinetic, ratio_lo, stribeck_lo],
        &[amplitude_hi * kinetic, ratio_hi, stribeck_hi],
        &[kinetic, 1.0, START_STRIBECK_M_S],
        LsqOptions {
            max_iterations: FIT_ITERATIONS,
            tolerance: FIT_TOLERANCE,
            step: FIT_STEP,
            parallel: false,
        },
    )?;
    // the least-squares vector's layout: the start's above
    Some(CurveFit {
        kinetic_n: fit.theta[0],
        static_ratio: fit.theta[1],
        stribeck_velocity_m_s: fit.theta[2],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::{synthesise, SynthOptions};

    /// The curve of a synthetic campaign with a known stick-slip (default sensor noise)
    /// gives the kinetic amplitude within 3 % and the static ratio within 20 % (measured
    /// 1.94 for 2.2: the 80-ms speed estimate and the chatter at rest blur the peak, so
    /// the ratio reads low; it is only the score fit's start); the bare table's curve is
    /// flat (ratio below 1.1).
    #[test]
    fn reads_the_stribeck_curve_of_a_synthetic_table() {
        let opts = SynthOptions {
            random_duration_s: 10.0,
            seed: 11,
            ..SynthOptions::default()
        };
        let mut truth = Params::trees_lab();
        let mut sticky = truth;
        sticky
            .apply_effect_spec("stick_slip:static_ratio=2.2,stribeck_velocity_m_s=0.005")
            .unwrap();
        let sig: Vec<usize> = (0..18).collect();
        let c = synthesise(&sticky, &opts, None);
        let fit = fit_curve(&measured_curve(&c, &truth, &sig)).unwrap();
        let (f, r, v) = (fit.kinetic_n, fit.static_ratio, fit.stribeck_velocity_m_s);
        assert!((f / 4000.0 - 1.0).abs() < 0.03, "F_mu {f}");
        assert!((r / 2.2 - 1.0).abs() < 0.2, "r_s {r}");
        assert!((v / 0.005 - 1.0).abs() < 0.5, "v_s {v}");
        truth.stick_slip.enabled = false;
        let c = synthesise(&truth, &opts, None);
        let fit = fit_curve(&measured_curve(&c, &truth, &sig)).unwrap();
        let (f, r) = (fit.kinetic_n, fit.static_ratio);
        assert!((f / 4000.0 - 1.0).abs() < 0.03, "F_mu {f}");
        assert!(r < 1.1, "bare table r_s {r}");
    }
}
