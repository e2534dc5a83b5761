//! Figures (plotters) and report pages. Everything here reads results; nothing computes
//! physics.

pub mod diagnose;
pub mod identify;
pub mod plot;
