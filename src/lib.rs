//! shaketable: a servo-hydraulic uni-axial shake table (EUCENTRE TREES Lab) as a model,
//! a simulator, an FMI 2.0 Co-Simulation FMU, and an identification/diagnosis toolkit.
//!
//! Flow: parameters -> model -> solver -> (FMU | CLI); campaign -> identification ->
//! diagnosis -> report.

pub mod benchmark;
pub mod campaign;
pub mod diagnose;
pub mod effects;
pub mod fmi;
pub mod identify;
pub mod linear;
pub mod model;
pub mod motion;
pub mod output;
pub mod params;
pub mod report;
pub mod solver;

pub use model::{Inputs, Model, Outputs, Reference, SensorNoise};
pub use params::Params;
pub use solver::{simulate_record, Diverged, Simulator};
