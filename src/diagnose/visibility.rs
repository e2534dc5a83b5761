//! What the recorded motion could not have shown (issue 16's held-out check): without a
//! force channel a specimen enters the records only through the table's motion, and a
//! stiff displacement loop holds that motion to its reference whatever rides on the
//! table. A `none` is then no evidence of a bare table. For each of a few specimen
//! frequencies this finds the lightest specimen whose effect on the recorded channels the
//! diagnosis would have seen: the extended model with and without it differ, in some test
//! and channel of the specimen's signature, by enough that a model lacking it would miss
//! that cell ([`MISS_RATIO`]). Lighter specimens are invisible in these records.

use super::effect::Effect;
use super::effect_values::EffectValues;
use super::residuals::{simulate_test, Whitening};
use super::MISS_RATIO;
use crate::campaign::Campaign;
use crate::params::Params;
use rayon::prelude::*;
use serde::Serialize;

/// Specimen frequencies probed, Hz: one per octave over the band where a specimen
/// interacts with a table (below 1 Hz the loop follows any load; above 16 Hz the oil
/// column and the valve filter the reference away on most tables).
pub const PROBE_FREQUENCIES_HZ: [f64; 5] = [1.0, 2.0, 4.0, 8.0, 16.0];

/// Damping ratio of a probed specimen: a lightly damped structure (a few percent, like
/// the catalogue's starts), the most visible kind at its frequency.
pub const PROBE_DAMPING_RATIO: f64 = 0.03;

/// Halvings of the mass interval (logarithmic, over the specimen's fitting range of three
/// decades): the smallest visible mass to about 6 %, finer than the noise estimate that
/// sets the threshold.
const BISECTIONS: usize = 7;

/// A probe specimen is visible when it changes some cell by this much (difference power
/// over predicted noise power, [`Whitening::difference`]): the measured residual of a
/// model lacking it would then exceed [`MISS_RATIO`] noise RMS, and the cell be missed.
const VISIBLE_DIFFERENCE: f64 = MISS_RATIO * MISS_RATIO - 1.0;

/// The lightest visible specimen at one frequency. Without a force channel the model's
/// table mass is a convention (the motion sees only ratios of mass to stiffness), and a
/// specimen acts through its share of it: the share is the figure that carries over to
/// the real table; the mass in kilograms holds on the model's scale.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpecimenVisibility {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    /// `None` when even the heaviest specimen probed stays invisible.
    pub smallest_visible_mass_kg: Option<f64>,
    /// The same over the model's table mass.
    pub smallest_visible_mass_ratio: Option<f64>,
    /// The smallest visible mass is the lightest probed: the threshold may lie below.
    pub at_lightest_probed: bool,
    /// The lightest and heaviest specimens probed (the fitting range), kg.
    pub probed_mass_kg: [f64; 2],
}

/// What the records could show of a specimen, and on which tests.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Visibility {
    /// The specimen's signature tests, the ones probed (a specimen acts on every test).
    pub tests: Vec<String>,
    pub table_mass_kg: f64,
    pub specimens: Vec<SpecimenVisibility>,
    pub rule: String,
}

/// How visibility is judged, for the JSON.
fn rule() -> String {
    format!("a specimen (damping {PROBE_DAMPING_RATIO}) is visible when adding it to the extended model, the rest of the model held, changes some test and channel of the specimen's signature tests over their fitting halves by enough that a model lacking it would miss that cell: difference power over predicted noise power, averaged over octave bands, at least {VISIBLE_DIFFERENCE:.4} ({MISS_RATIO}^2 - 1). A refit of the rest of the model can absorb part of a specimen, so a specimen must weigh at least this to change the records; whether a fit would then name it is not promised")
}

/// The specimens the records of `c` could and could not show under the extended model `p`
/// (the diagnosis' whitening weighs the channels); `None` when no signature test of the
/// specimen is weighed or `p` cannot be simulated on them.
pub fn specimen_visibility(p: &Params, c: &Campaign, whitening: &Whitening) -> Option<Visibility> {
    let effect = Effect::of(&crate::effects::specimen::EFFECT);
    let tests: Vec<usize> = effect
        .signature_tests(c, p)
        .into_iter()
        .filter(|&i| whitening.weighs(c, i))
        .collect();
    let runs = |q: &Params| -> Option<Vec<Vec<crate::Outputs>>> {
        tests
            .par_iter()
            .map(|&i| simulate_test(q, c, i, super::Part::Fit).ok())
            .collect()
    };
    let without = runs(p).filter(|r| !r.is_empty())?;
    let bounds = effect.bounds(p);
    let (m_lo, m_hi) = (bounds.lower.get("mass_kg"), bounds.upper.get("mass_kg"));
    let table = p.table.mass_kg;
    let visible = |f: f64, m: f64| -> bool {
        let mut q = *p;
        let probe = [
            ("mass_kg", m),
            ("frequency_hz", f),
            ("damping_ratio", PROBE_DAMPING_RATIO),
        ];
        EffectValues::new(effect, &probe).apply(&mut q);
        let Some(with) = runs(&q) else {
            // a specimen that drives the table out of its envelope shows
            return true;
        };
        tests.iter().enumerate().any(|(k, &i)| {
            whitening
                .difference(c, i, &with[k], &without[k])
                .values()
                .any(|d| d.is_some_and(|d| d >= VISIBLE_DIFFERENCE))
        })
    };
    let specimens = PROBE_FREQUENCIES_HZ
        .iter()
        .map(|&f| {
            let m = smallest_visible(|m| visible(f, m), m_lo, m_hi);
            SpecimenVisibility {
                frequency_hz: f,
                damping_ratio: PROBE_DAMPING_RATIO,
                smallest_visible_mass_kg: m,
                smallest_visible_mass_ratio: m.map(|m| m / table),
                at_lightest_probed: m == Some(m_lo),
                probed_mass_kg: [m_lo, m_hi],
            }
        })
        .collect();
    Some(Visibility {
        tests: tests
            .iter()
            .map(|&i| c.info.tests[i].name.clone())
            .collect(),
        specimens,
        table_mass_kg: table,
        rule: rule(),
    })
}

/// The smallest `m` in `[lo, hi]` with `visible(m)`, by bisection in `ln m` (visibility
/// grows with the mass); `None` when `hi` is not visible or the interval is not a finite
/// positive one, `lo` when it is visible.
fn smallest_visible(visible: impl Fn(f64) -> bool, lo: f64, hi: f64) -> Option<f64> {
    if !(lo > 0.0 && hi.is_finite() && hi >= lo && visible(hi)) {
        return None;
    }
    if visible(lo) {
        return Some(lo);
    }
    let (mut a, mut b) = (lo.ln(), hi.ln());
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (a + b);
        if visible(mid.exp()) {
            b = mid;
        } else {
            a = mid;
        }
    }
    Some(b.exp())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::short_campaign;
    use crate::diagnose::residuals::estimate_noise;
    use crate::diagnose::Part;

    /// The test `test` (12 s) of `truth` as a lab without force, valve command or spool
    /// channels records it, and the whitening of `truth`'s prediction of it.
    fn motion_only(truth: &Params, test: &str) -> (Campaign, Whitening) {
        let mut c = short_campaign(truth, &[test], 12.0);
        for r in &mut c.records {
            r.force_n = None;
            r.spool_position = None;
            r.valve_command = None;
        }
        let noise = estimate_noise(&c);
        let whitening = Whitening::new(truth, &c, &[0], &noise, Part::Fit);
        (c, whitening)
    }

    /// On the TREES Lab table recorded without force, valve command or spool (the
    /// acceleration-controlled random test R2, 12 s, default noise), the accelerometer
    /// sees a specimen's reaction: a few percent of the table's mass shows at every probed
    /// frequency (measured 0.4-0.8 t below 16 Hz for 41 t), and the lightest near the oil
    /// column's 14-Hz resonance, where the specimen's reaction moves the table most
    /// (measured: the range's floor, 0.2 t).
    #[test]
    fn a_light_specimen_shows_in_the_acceleration() {
        let p = Params::trees_lab();
        let (c, whitening) = motion_only(&p, "R2");
        let v = specimen_visibility(&p, &c, &whitening).unwrap();
        let mass_at = |f: f64| {
            v.specimens
                .iter()
                .find(|s| s.frequency_hz == f)
                .unwrap()
                .smallest_visible_mass_kg
        };
        let table = p.table.mass_kg;
        for f in PROBE_FREQUENCIES_HZ {
            let m = mass_at(f).unwrap_or(f64::INFINITY);
            assert!(m < 0.05 * table, "{f} Hz: {m} kg");
        }
        let near_resonance = mass_at(16.0).unwrap();
        for f in [1.0, 2.0, 4.0, 8.0] {
            assert!(mass_at(f).unwrap() >= near_resonance, "{:?}", v.specimens);
        }
        assert_eq!(v.tests, ["R2"]);
    }

    /// The bisection brackets a threshold to its resolution and says so when none exists.
    #[test]
    fn the_bisection_finds_the_threshold_or_none() {
        let m = smallest_visible(|m| m >= 1234.0, 100.0, 1e5).unwrap();
        assert!(m >= 1234.0 && m / 1234.0 < 1.06, "{m}");
        assert_eq!(smallest_visible(|m| m >= 1e6, 100.0, 1e5), None);
        assert_eq!(smallest_visible(|_| true, 100.0, 1e5), Some(100.0));
        assert_eq!(smallest_visible(|_| true, 0.0, 1e5), None);
    }
}
