//! Measured against simulated in the identification's terms (issue 16 part 3: NRMSE and
//! MATLAB's fit %): per test and channel, the baseline's and the extended model's fit on
//! each test's report quarter, the part that no fit and no decision saw ([`Part`]). The
//! gain says how much closer to the noise the extended model comes; these say how close
//! its simulation follows the records, in the figures a laboratory compares models by.

use super::part::Part;
use super::residuals::noise::median;
use crate::campaign::{Campaign, Measured};
use crate::identify::greybox::compare::{
    noise_ceiling, nrmse, simulate_test, simulated, SimulationStopped, COMPARED,
};
use crate::identify::signals::centred_rms;
use crate::params::Params;
use crate::Outputs;
use rayon::prelude::*;
use serde::Serialize;
use std::ops::Range;

/// The fit of one channel of one test on its report quarter, means removed.
#[derive(Debug, Clone, Serialize)]
pub struct ModelFit {
    pub test: String,
    pub channel: &'static str,
    /// `100 (1 - NRMSE)` of the refined baseline; `None` where its run stopped.
    pub baseline_fit_percent: Option<f64>,
    /// The same for the extended model.
    pub extended_fit_percent: Option<f64>,
    /// The most a noise-free simulation of the true table reaches with the noise the
    /// channel shows at rest: the identification's ceiling, over the quarter's RMS where
    /// the identification takes the whole test's.
    pub noise_ceiling_percent: Option<f64>,
}

/// Fit % of `run` against the measured channel `m` (`meas`) over `range`.
fn quarter_fit(
    run: &Result<Vec<Outputs>, SimulationStopped>,
    meas: &[f64],
    range: Range<usize>,
    m: Measured,
) -> Option<f64> {
    let run = run.as_ref().ok()?.get(range.clone())?;
    let sim: Vec<f64> = run.iter().map(|o| simulated(o, m)).collect();
    nrmse(&meas[range], &sim).map(|(e, _)| 100.0 * (1.0 - e))
}

/// [`ModelFit`]s of test `i` of `c`, every channel it recorded.
fn test_fits(baseline: &Params, extended: &Params, c: &Campaign, i: usize) -> Vec<ModelFit> {
    let base = simulate_test(baseline, c, i);
    // without a cause the extended model is the baseline: one run serves both
    let ext = (extended != baseline).then(|| simulate_test(extended, c, i));
    let r = &c.records[i];
    let range = Part::Report.range(r.len());
    let rest = c.rest_segment(i);
    COMPARED
        .into_iter()
        .filter_map(|m| {
            let meas = r.measured(m)?;
            let rms = centred_rms(&meas[range.clone()]);
            let fit = |run| quarter_fit(run, meas, range.clone(), m);
            Some(ModelFit {
                test: c.info.tests[i].name.clone(),
                channel: m.name(),
                baseline_fit_percent: fit(&base),
                extended_fit_percent: fit(ext.as_ref().unwrap_or(&base)),
                noise_ceiling_percent: rest
                    .clone()
                    .and_then(|rest| noise_ceiling(centred_rms(&meas[rest]), rms)),
            })
        })
        .collect()
}

/// [`ModelFit`] of every test of `c` and every channel it recorded, `baseline` against
/// `extended` (the runs as each test was run: its gains, from rest), one test's runs held
/// at a time.
pub fn report_quarter_fits(baseline: &Params, extended: &Params, c: &Campaign) -> Vec<ModelFit> {
    (0..c.records.len())
        .into_par_iter()
        .flat_map_iter(|i| test_fits(baseline, extended, c, i))
        .collect()
}

/// Per channel of `fits` (in [`COMPARED`] order), the median fit % over the tests each
/// model ran through.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelMedian {
    pub channel: &'static str,
    /// Median and tests counted, of the baseline; `None` when no run got through.
    pub baseline: Option<(f64, usize)>,
    pub extended: Option<(f64, usize)>,
    /// The same of the noise ceilings (the slow tests' acceleration is mostly noise, and
    /// pulls every median of it down).
    pub noise_ceiling: Option<(f64, usize)>,
}

/// [`ChannelMedian`] of every channel in `fits`.
pub fn medians_by_channel(fits: &[ModelFit]) -> Vec<ChannelMedian> {
    let of = |v: Vec<f64>| {
        (!v.is_empty())
            .then(|| (v.len(), median(v)))
            .map(|(n, m)| (m, n))
    };
    COMPARED
        .iter()
        .map(|m| m.name())
        .filter_map(|channel| {
            let here: Vec<&ModelFit> = fits.iter().filter(|f| f.channel == channel).collect();
            (!here.is_empty()).then(|| ChannelMedian {
                channel,
                baseline: of(here.iter().filter_map(|f| f.baseline_fit_percent).collect()),
                extended: of(here.iter().filter_map(|f| f.extended_fit_percent).collect()),
                noise_ceiling: of(here
                    .iter()
                    .filter_map(|f| f.noise_ceiling_percent)
                    .collect()),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::synth::short_campaign;

    /// On a campaign of a table with a specimen, the model with it follows the report
    /// quarters at their noise ceiling and the table alone does not; the medians are
    /// the middle of the tests' figures.
    #[test]
    fn the_extended_model_follows_the_records_and_the_baseline_does_not() {
        let mut truth = Params::trees_lab();
        let base = truth;
        truth
            .apply_effect_spec("specimen:mass_kg=20000,frequency_hz=5,damping_ratio=0.03")
            .unwrap();
        let c = short_campaign(&truth, &["R1", "R2", "R3"], 8.0);
        let fits = report_quarter_fits(&base, &truth, &c);
        let acc: Vec<&ModelFit> = fits
            .iter()
            .filter(|f| f.channel == "acceleration_m_s2")
            .collect();
        assert_eq!(acc.len(), 3);
        for f in &acc {
            let (b, e) = (
                f.baseline_fit_percent.unwrap(),
                f.extended_fit_percent.unwrap(),
            );
            let ceiling = f.noise_ceiling_percent.unwrap();
            // the truth within two points of its ceiling (the noise's own draw), the
            // table alone misses the specimen's resonance by tens of percent
            assert!(e > ceiling - 2.0 && e < ceiling + 2.0, "{f:?}");
            assert!(b < e - 10.0, "{f:?}");
        }
        let medians = medians_by_channel(&fits);
        let acc = medians
            .iter()
            .find(|m| m.channel == "acceleration_m_s2")
            .unwrap();
        let mut ext: Vec<f64> = fits
            .iter()
            .filter(|f| f.channel == "acceleration_m_s2")
            .map(|f| f.extended_fit_percent.unwrap())
            .collect();
        ext.sort_by(f64::total_cmp);
        assert_eq!(acc.extended, Some((ext[1], 3)));
        assert!(acc.baseline.unwrap().0 < ext[1]);
    }
}
