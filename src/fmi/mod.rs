//! The FMI 2.0 Co-Simulation boundary: a thin, strict layer over the model.
