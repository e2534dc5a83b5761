//! The FMI 2.0 Co-Simulation boundary: a thin, strict layer over the model, as
//! modelica/Reference-FMUs separate `model.c` from `fmi2Functions.c`.
//!
//! `variables` is the one table of the FMU's variables; `model_description` generates
//! modelDescription.xml from it; `instance` is the state machine in safe Rust; `export`
//! the C ABI (built into the crate's cdylib, packaged as `binaries/linux64/ShakeTable.so`).

pub mod export;
pub mod export_me;
pub mod fmi3;
pub mod icon;
pub mod instance;
pub mod model_description;
pub mod model_exchange;
pub mod structure;
pub mod variables;
