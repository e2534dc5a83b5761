//! FMI 3.0 Co-Simulation (`target/fmu/ShakeTable3.fmu`): the same instance, variables and
//! binary as the FMI 2.0 FMU, behind the `fmi3*` C functions and an FMI 3.0 description.

pub mod export;
pub mod model_description;
