//! One cell of the heat map (a test and a channel) and what it holds: no figure, a run
//! that predicts nothing there, or a figure in noise units.

use super::channels::PerChannel;

/// A figure of one test and channel, in one of three states kept apart by type rather
/// than by NaN or infinity: the pipeline ranks and averages figures, and the reports and
/// the JSON show them, each reading the state it needs.
///
/// - [`Cell::Absent`]: nothing to score (the channel is not recorded, has no noise
///   estimate, or the part is too short). It counts nowhere, like a channel the campaign
///   lacks.
/// - [`Cell::Diverged`]: the model predicts nothing here (its run stopped inside the
///   part, its residual or spread is not finite, or a trial model held to the operating
///   envelope left it where the measured table did not). It is infinitely bad, never left
///   out as if absent: a model cannot improve its score by diverging.
/// - [`Cell::Scored`]: a figure (which may itself be infinite where a model predicts no
///   power at all, [`super::band_score`]).
///
/// [`Cell::figure`] is the one place the states become numbers.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum Cell {
    #[default]
    Absent,
    Diverged,
    Scored(f64),
}

impl Cell {
    /// The number the pipeline ranks and averages: none for an absent cell, infinity for
    /// a diverged one (it scores infinitely bad), the figure otherwise.
    pub fn figure(self) -> Option<f64> {
        match self {
            Cell::Absent => None,
            Cell::Diverged => Some(f64::INFINITY),
            Cell::Scored(x) => Some(x),
        }
    }

    /// A finite figure, `None` for an absent or diverged cell or an infinite or NaN
    /// figure: what the JSON and the "anything scored" tests read.
    pub fn finite(self) -> Option<f64> {
        self.figure().filter(|x| x.is_finite())
    }
}

/// One [`Cell`] per channel of a test.
pub type Cells = PerChannel<Cell>;

#[cfg(test)]
mod tests {
    use super::*;

    /// The three states stay apart, and each becomes the number the pipeline reads.
    #[test]
    fn absent_diverged_and_scored_cells_are_distinct_and_read_as_numbers() {
        assert_eq!(Cell::default(), Cell::Absent);
        assert_eq!(Cell::Absent.figure(), None);
        assert_eq!(Cell::Diverged.figure(), Some(f64::INFINITY));
        assert_eq!(Cell::Scored(1.5).figure(), Some(1.5));
        assert_eq!(Cell::Diverged.finite(), None);
        assert_eq!(Cell::Scored(f64::INFINITY).finite(), None);
        assert_eq!(Cell::Scored(0.5).finite(), Some(0.5));
    }
}
