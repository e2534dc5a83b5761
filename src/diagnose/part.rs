//! Which samples of a test a residual uses: the split of every test in time into the part
//! that fits, the part that selects and the part that reports (issue 17 part 5).

/// Which samples of a test a residual uses. Every test is split in time, so every test
/// type, and so every effect's signature, is on each side of the split:
/// - [`Part::Fit`], the first half: every least-squares fit (baseline refinement, the
///   candidates, polishing);
/// - [`Part::Select`], the third quarter: every decision (which cells the baseline misses,
///   the candidates' ranking, whether a polish or the other actuator variant is kept,
///   whether a cause is accepted, whether to search for another);
/// - [`Part::Report`], the last quarter: the gain and `explained`, and nothing else. No
///   fit and no decision has seen it, so the gain it measures is not optimistic: a
///   candidate that was picked because it happened to fit the selection quarter's noise
///   gains nothing there.
///
/// Why a quarter is enough to report on: the scores are per octave band in windows of 8
/// degrees of freedom, and the paper's shortest test keeps several windows in every band
/// above 1 Hz in a quarter; a residual's estimate over a cell then has a spread of a few
/// percent, far below the factor between `MISS_RATIO` and a model that misses.
/// [`Part::HeldOut`] (the whole second half) remains for the scoring studies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    Whole,
    Fit,
    HeldOut,
    Select,
    Report,
}

impl Part {
    /// The part a simulation must run over to cover this one (from the start).
    pub fn simulated(self) -> Part {
        match self {
            Part::Fit => Part::Fit,
            _ => Part::Whole,
        }
    }

    pub fn range(self, n: usize) -> std::ops::Range<usize> {
        match self {
            Part::Whole => 0..n,
            Part::Fit => 0..n / 2,
            Part::HeldOut => n / 2..n,
            Part::Select => n / 2..3 * n / 4,
            Part::Report => 3 * n / 4..n,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_select_and_report_tile_every_test_without_overlap() {
        for n in [0, 1, 7, 4096, 4099] {
            let (f, s, r) = (
                Part::Fit.range(n),
                Part::Select.range(n),
                Part::Report.range(n),
            );
            assert_eq!(f.start, 0);
            assert_eq!(f.end, s.start);
            assert_eq!(s.end, r.start);
            assert_eq!(r.end, n);
            assert_eq!(Part::HeldOut.range(n), s.start..r.end);
        }
    }
}
