//! Identification of the model parameters from a campaign (paper section 4).

pub mod frf;
