//! Which samples of a test a residual uses: fitting half, held-out half, whole.

/// Which samples of a test a residual uses: every test is split in time, its first half
/// fits, its second half (never seen by any fit) scores. Every test type, and so every
/// effect's signature, is on both sides of the split.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    Whole,
    Fit,
    HeldOut,
}

impl Part {
    /// The part a simulation must run over to cover this one (from the start).
    pub fn simulated(self) -> Part {
        match self {
            Part::HeldOut => Part::Whole,
            p => p,
        }
    }

    pub fn range(self, n: usize) -> std::ops::Range<usize> {
        match self {
            Part::Whole => 0..n,
            Part::Fit => 0..n / 2,
            Part::HeldOut => n / 2..n,
        }
    }
}
