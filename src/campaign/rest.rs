//! Where a test is at rest: the start of a record, while every reference the laboratory
//! recorded holds its first value. The diagnosis' noise floor and the identification's
//! noise-limited fit are read there.

use super::Campaign;
use std::ops::Range;

/// Rest samples a test needs before its rest segment counts: 1/8 s at 512 Hz, one or two
/// periods of the oil-column chatter the floor holds, the least that gives its variance
/// (a synthetic rest is a second long).
const MIN_REST_SAMPLES: usize = 64;

impl Campaign {
    /// Samples at rest at the start of test `i`: while every reference the laboratory
    /// recorded holds its first value exactly (a controller's command at rest is a
    /// constant; a reference computed here from the recorded one is skipped, since its
    /// spectral derivatives or integrals ring about rest). A reference recorded through an
    /// ADC, noisy at rest, gives no rest segment.
    pub fn rest_samples(&self, i: usize) -> usize {
        let r = &self.records[i];
        let computed = |name: &str| self.computed_here(&self.info.tests[i].name, name);
        let recorded: Vec<&[f64]> = [
            ("ref_displacement_m", &r.ref_displacement_m),
            ("ref_velocity_m_s", &r.ref_velocity_m_s),
            ("ref_acceleration_m_s2", &r.ref_acceleration_m_s2),
        ]
        .into_iter()
        .filter(|(name, _)| !computed(name))
        .map(|(_, x)| x.as_slice())
        .collect();
        (0..r.len())
            .take_while(|&k| recorded.iter().all(|x| x[k] == x[0]))
            .count()
    }

    /// Test `i`'s rest segment ([`Campaign::rest_samples`]) where it is long enough to
    /// count ([`MIN_REST_SAMPLES`]).
    pub fn rest_segment(&self, i: usize) -> Option<Range<usize>> {
        let rest = self.rest_samples(i);
        (rest >= MIN_REST_SAMPLES).then_some(0..rest)
    }
}
