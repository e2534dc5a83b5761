//! The cells a model misses on one quarter of the tests, the RMS over them that ranks
//! candidates, and whether a model explains them.

use super::residuals::{Cells, PerChannel};
use super::{EXPLAINED_RATIO, MISS_RATIO};

/// The cells a model misses ([`MISS_RATIO`]) on one quarter; candidates are scored on
/// them, so an effect that lives in a few tests is not diluted by the many it does not
/// touch.
#[derive(Debug, Clone, Default)]
pub(super) struct Missed {
    pub cells: Vec<PerChannel<bool>>,
    pub any: bool,
}

impl Missed {
    pub fn of(residual_rows: &[Cells]) -> Missed {
        let cells: Vec<PerChannel<bool>> = residual_rows
            .iter()
            .map(|r| r.map(|x| x.figure().is_some_and(|x| x > MISS_RATIO)))
            .collect();
        let any = cells.iter().any(|m| m.values().any(|&m| m));
        Missed { cells, any }
    }

    /// RMS over the missed cells (over every cell when none is missed).
    pub fn rms(&self, rows: &[Cells]) -> f64 {
        let v: Vec<f64> = rows
            .iter()
            .zip(&self.cells)
            .flat_map(|(r, m)| {
                r.values()
                    .zip(m.values())
                    .filter(|(_, &m)| m || !self.any)
                    .filter_map(|(x, _)| x.figure())
            })
            // absent channels and NaN figures do not count; a diverged run's cells are
            // infinite and count
            .filter(|x| !x.is_nan())
            .collect();
        (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
    }

    /// Whether some cell of `rows` is beyond [`EXPLAINED_RATIO`] (a diverged run's cell
    /// is): what a further search looks for a cause of. A cell between [`MISS_RATIO`] and
    /// it is missed but explained by the rule of `explained`, so it calls for no further
    /// cause (after a first cause, such cells were single marginal ones, 1.56-1.86 on
    /// seeds 452, 456 and 458, and every search for them came back empty).
    pub fn unexplained_remains(rows: &[Cells]) -> bool {
        rows.iter().any(|r| {
            r.values()
                .any(|x| x.figure().is_some_and(|x| x > EXPLAINED_RATIO))
        })
    }

    /// Whether every missed cell is explained by a model whose rows are `rows`: its
    /// residual there is within [`EXPLAINED_RATIO`] (the rule of `explained`, judged cell
    /// by cell so that the many cells one effect fixes cannot dilute the few another
    /// leaves).
    pub fn all_explained_by(&self, rows: &[Cells]) -> bool {
        rows.iter().zip(&self.cells).all(|(r, m)| {
            r.values()
                .zip(m.values())
                .all(|(x, &m)| !m || x.figure().is_some_and(|x| x <= EXPLAINED_RATIO))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::residuals::Cell;

    /// An absent channel in [`rows`].
    const NAN: f64 = f64::NAN;

    /// Rows of cells in channel order, NaN marking an absent channel and infinity a
    /// diverged run.
    fn rows<const N: usize>(r: [[f64; 5]; N]) -> Vec<Cells> {
        let cell = |x: f64| match x {
            x if x.is_nan() => Cell::Absent,
            f64::INFINITY => Cell::Diverged,
            x => Cell::Scored(x),
        };
        r.into_iter()
            .map(|row| Cells::from(row.map(cell)))
            .collect()
    }

    #[test]
    fn a_missed_cell_is_one_above_the_miss_ratio_and_absent_cells_never_are() {
        let cells = rows([
            [1.0, MISS_RATIO, MISS_RATIO * 1.01, NAN, 0.5],
            [0.2, 0.3, NAN, NAN, 1.4],
        ]);
        let m = Missed::of(&cells);
        assert!(m.any);
        assert_eq!(m.cells[0], [false, false, true, false, false].into());
        assert_eq!(m.cells[1], PerChannel::filled(false));
        // candidates are scored on that cell alone
        let trial = rows([[9.0, 9.0, 3.0, NAN, 9.0], [9.0, 9.0, NAN, NAN, 9.0]]);
        assert_eq!(m.rms(&trial), 3.0);
    }

    #[test]
    fn with_nothing_missed_every_present_cell_counts_and_a_divergence_is_not_hidden() {
        let m = Missed::of(&rows([[1.0, 1.2, NAN, 0.9, 1.1]]));
        assert!(!m.any);
        let trial = rows([[2.0, 2.0, NAN, 2.0, 2.0]]);
        assert_eq!(m.rms(&trial), 2.0);
        // a diverged run's infinite cells count: they do not vanish like absent ones
        let diverged = rows([[2.0, f64::INFINITY, NAN, 2.0, 2.0]]);
        assert_eq!(m.rms(&diverged), f64::INFINITY);
    }

    /// A further search needs a cell beyond the explained ratio; one between the miss
    /// ratio and it, or an absent one, calls for none; a diverged run does.
    #[test]
    fn only_a_cell_beyond_the_explained_ratio_calls_for_a_further_cause() {
        let within = rows([[1.9, 1.6, NAN, 1.0, EXPLAINED_RATIO]]);
        assert!(Missed::of(&within).any);
        assert!(!Missed::unexplained_remains(&within));
        assert!(Missed::unexplained_remains(&rows([[
            1.0, 2.1, NAN, 1.0, 1.0
        ]])));
        assert!(Missed::unexplained_remains(&rows([[
            1.0,
            1.0,
            f64::INFINITY,
            1.0,
            1.0
        ]])));
    }

    /// `explained` is judged cell by cell: one missed cell left at 2.5 is not explained
    /// however many others the model fixes (the RMS over them would be below 2).
    #[test]
    fn one_cell_still_missed_leaves_the_data_unexplained() {
        let baseline = rows([[5.0, 5.0, 5.0, NAN, 1.0], [5.0, 5.0, 5.0, NAN, 4.0]]);
        let m = Missed::of(&baseline);
        let fixed = rows([[1.0, 1.0, 1.0, NAN, 9.0], [1.0, 1.0, 1.0, NAN, 1.5]]);
        assert!(m.all_explained_by(&fixed));
        let one_left = rows([[1.0, 1.0, 1.0, NAN, 1.0], [1.0, 1.0, 1.0, NAN, 2.5]]);
        assert!(m.rms(&one_left) < EXPLAINED_RATIO);
        assert!(!m.all_explained_by(&one_left));
    }
}
