//! Estimation and validation tests of the closed-loop fit: validation data is not
//! estimation data (MATLAB's System Identification practice). With one usable test it is
//! fitted and nothing is predicted; with several, the tests are ranked by how richly
//! their reference excites the loop and dealt in turn, the richest to estimation, the
//! next to validation, and so on: both sets then span the same kinds of test, and the
//! fit sees the broadest excitation.

use crate::campaign::{Campaign, TestKind};

/// How richly a test's reference excites the loop: broadband references (random,
/// chirps, earthquakes) before periodic ones, then the longer first.
fn richness(c: &Campaign, i: usize) -> (u8, usize) {
    let broadband = matches!(c.info.tests[i].kind, TestKind::Random | TestKind::Record);
    (u8::from(broadband), c.records[i].len())
}

/// `(estimation, validation)` test indices from the usable `tests`, each in campaign order.
pub fn split(c: &Campaign, tests: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut ranked = tests.to_vec();
    // stable: equal richness keeps campaign order
    ranked.sort_by_key(|&a| std::cmp::Reverse(richness(c, a)));
    let (mut est, mut val): (Vec<usize>, Vec<usize>) = (Vec::new(), Vec::new());
    for (k, i) in ranked.into_iter().enumerate() {
        if k % 2 == 0 {
            est.push(i);
        } else {
            val.push(i);
        }
    }
    est.sort_unstable();
    val.sort_unstable();
    (est, val)
}
