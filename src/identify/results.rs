//! What each estimator of identification returns (paper section 4).

use super::frf::{band_indices, WelchOptions};
use super::mass_mode::TableWithModes;
use crate::campaign::screen::Finding;
use crate::linear::TfFigures;
use crate::params::{Params, ServovalveModel};
use num_complex::Complex64;
use serde::Serialize;

/// A sampled FRF kept for the report's figures.
#[derive(Debug, Clone, Default, Serialize)]
pub struct FrfData {
    pub frequency_hz: Vec<f64>,
    pub re: Vec<f64>,
    pub im: Vec<f64>,
    pub coherence: Vec<f64>,
}

impl FrfData {
    pub(super) fn from(f: &[f64], h: &[Complex64], coh: &[f64], band: [f64; 2]) -> FrfData {
        let idx = band_indices(f, band[0], band[1]);
        FrfData {
            frequency_hz: idx.iter().map(|&i| f[i]).collect(),
            re: idx.iter().map(|&i| h[i].re).collect(),
            im: idx.iter().map(|&i| h[i].im).collect(),
            coherence: idx
                .iter()
                .map(|&i| coh.get(i).copied().unwrap_or(f64::NAN))
                .collect(),
        }
    }

    pub fn complex(&self) -> Vec<Complex64> {
        self.re
            .iter()
            .zip(&self.im)
            .map(|(a, b)| Complex64::new(*a, *b))
            .collect()
    }
}

/// Servovalve fits (paper 4.1.1, eqs. 4.1 and 4.2) on `valve_command -> spool_position`.
#[derive(Debug, Clone, Serialize)]
pub struct ServovalveFit {
    pub test: String,
    pub gain: f64,
    pub time_constant_s: f64,
    pub natural_frequency_hz: f64,
    pub damping_ratio: f64,
    pub first_order_gain: f64,
    pub sigma_natural_frequency_hz: f64,
    pub sigma_damping_ratio: f64,
    pub sigma_time_constant_s: f64,
    /// RMS complex relative error of each fit over the band.
    pub first_order_error: f64,
    pub second_order_error: f64,
    /// Highest frequency up to which the first-order phase is within 5 degrees.
    pub first_order_phase_valid_to_hz: f64,
    pub chosen: ServovalveModel,
    pub band_hz: [f64; 2],
    pub measured: FrfData,
}

/// Apparent mass `F/a = M + c/(j w) - k/w^2` fitted over [`MASS_BAND_HZ`] (paper 4.1.2).
#[derive(Debug, Clone, Serialize)]
pub struct MassFit {
    pub test: String,
    pub mass_kg: f64,
    pub sigma_mass_kg: f64,
    /// Viscous-like term, N s/m.
    pub viscous_n_s_m: f64,
    /// Stiffness-like term, N/m (the friction's pre-sliding stiffness at this amplitude).
    pub stiffness_like_n_m: f64,
    /// A plain average of Re(F/a) over 1-5 Hz, to show the friction's bias.
    pub plain_average_kg: f64,
    /// RMS over the band of `|F/a - fit| / M`: how far the apparent mass is from a rigid
    /// body's with friction ([`MassFit::not_rigid`]).
    pub rigid_misfit: f64,
    /// Where that misfit is largest, Hz.
    pub rigid_misfit_peak_hz: f64,
    /// When the apparent mass is not a rigid body's: the table carrying modes that fits
    /// it, whose total mass is then [`MassFit::mass_kg`].
    pub carried: Option<TableWithModes>,
    pub measured: FrfData,
}

/// Oil column (paper 4.1.3) from the force against the valve command through the
/// identified servovalve, or against the spool instrumented by the valve command.
#[derive(Debug, Clone, Serialize)]
pub struct OilColumnFit {
    pub test: String,
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub bulk_modulus_pa: f64,
    pub leakage_m3_s_pa: f64,
    pub stiffness_n_m: f64,
    /// Fitted scale of the flow gain (1 when the geometry's `Kq` is right).
    pub flow_gain_scale: f64,
    pub sigma_frequency_hz: f64,
    pub sigma_damping_ratio: f64,
    pub sigma_bulk_modulus_pa: f64,
    /// The same fit on H1 from the noisy spool, to show its bias.
    pub h1_frequency_hz: f64,
    pub h1_damping_ratio: f64,
    /// `spool -> force` with the valve command as instrument (paper Figure 6).
    pub measured: FrfData,
    pub mass_used_kg: f64,
    /// What the fit took as the force's input.
    pub input: super::oil_column::OilColumnInput,
}

/// Triangles (eqs. 4.9-4.10): elastic force vs displacement away from reversals.
#[derive(Debug, Clone, Serialize)]
pub struct TriangleFit {
    pub tests: Vec<String>,
    pub stiffness_n_m: f64,
    pub sigma_stiffness_n_m: f64,
    pub sliding_friction_n: f64,
    /// Elastic force points (displacement, force) for Figure 7 (decimated).
    pub displacement_m: Vec<f64>,
    pub elastic_force_n: Vec<f64>,
}

/// Bouc-Wen friction (eqs. 4.13-4.15) fitted to the dissipative force of the sines.
#[derive(Debug, Clone, Serialize)]
pub struct FrictionFit {
    pub tests: Vec<String>,
    pub force_n: f64,
    pub yield_displacement_m: f64,
    pub shape: f64,
    pub sigma_force_n: f64,
    /// One-sigma uncertainties of `Y` and `b` (Levenberg-Marquardt covariance).
    pub sigma_yield_displacement_m: f64,
    pub sigma_shape: f64,
    pub rms_error_n: f64,
    /// Figure 9 data (decimated): displacement, velocity, dissipative force, fitted force.
    pub displacement_m: Vec<f64>,
    pub velocity_m_s: Vec<f64>,
    pub dissipative_force_n: Vec<f64>,
    pub fitted_force_n: Vec<f64>,
}

/// The device's force on one test: force-fit NRMSE (`RMS(meas - model) /
/// RMS(meas - mean(meas))`) and fit % (`100 (1 - NRMSE)`), and a window of its hysteresis
/// loop around the peak stroke for the report.
#[derive(Debug, Clone, Serialize)]
pub struct DeviceTestFit {
    pub test: String,
    pub nrmse: f64,
    pub fit_percent: f64,
    /// The load cell's zero used on this test, N (re-estimated on a checked test).
    pub offset_n: f64,
    pub displacement_m: Vec<f64>,
    pub measured_force_n: Vec<f64>,
    pub model_force_n: Vec<f64>,
}

/// A device between actuator and reaction (or the table's own force balance) from a test
/// with displacement and force: `F = F_mu Z(x) + c v + k x + m a + F_0`, Bouc-Wen `Z` of
/// eqs. 4.14-4.15 ([`super::fit_device`]).
#[derive(Debug, Clone, Serialize)]
pub struct DeviceFit {
    /// The test it was fitted on.
    pub test: String,
    pub force_n: f64,
    pub yield_displacement_m: f64,
    pub shape: f64,
    pub viscous_n_s_m: f64,
    pub stiffness_n_m: f64,
    /// Inertia of what moves between displacement sensor and load cell, kg.
    pub mass_kg: f64,
    pub offset_n: f64,
    /// One-sigma uncertainties in the order `F_mu, Y, b, c, k, m, F_0`, from the
    /// Levenberg-Marquardt covariance scaled by the residual's correlation factor.
    pub sigma: Vec<f64>,
    /// `1 + 2 sum rho_k` of the residual (the sigma above are scaled by its root).
    pub sigma_correlation_factor: f64,
    /// Pass-band corner of the zero-phase velocity and acceleration, Hz.
    pub corner_hz: f64,
    /// Whether `m a` used a measured acceleration (else the displacement's second
    /// derivative).
    pub measured_acceleration: bool,
    /// The fit on its own test.
    pub fit: DeviceTestFit,
    /// The same parameters on every other test with displacement and force.
    pub validation: Vec<DeviceTestFit>,
    /// Other tests that could not be checked, with the reason.
    pub not_validated: Vec<String>,
}

/// Mass by the loop approach (eqs. 4.11-4.12) per sine test.
#[derive(Debug, Clone, Serialize)]
pub struct PeriodicMassFit {
    pub tests: Vec<String>,
    pub per_test_kg: Vec<f64>,
    pub mass_kg: f64,
    pub sigma_mass_kg: f64,
    /// Figure 8 data of the first test: acceleration, inertial force.
    pub acceleration_m_s2: Vec<f64>,
    pub inertial_force_n: Vec<f64>,
}

/// Validation of the table TF (section 5, Figure 10).
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    pub test: String,
    /// RMS of the complex relative error over [`VALIDATION_BAND_HZ`], ideal actuator.
    pub table_tf_error: f64,
    /// The same for the nonlinear actuator (simulated test, Welch).
    pub table_tf_error_nonlinear: f64,
    pub measured_figures: Option<TfFigures>,
    pub model_figures: Option<TfFigures>,
    pub peak_hz: f64,
    pub measured: FrfData,
    pub ideal: FrfData,
    pub nonlinear: FrfData,
}

/// Everything identification found, and what it could not do.
#[derive(Debug, Clone, Serialize)]
pub struct Identification {
    pub campaign: String,
    /// What was read: every test before screening, each channel's unit and source.
    pub read: crate::campaign::provenance::CampaignRead,
    pub servovalve: Option<ServovalveFit>,
    pub triangles: Option<TriangleFit>,
    pub mass_random: Option<MassFit>,
    pub friction: Option<FrictionFit>,
    pub mass_periodic: Option<PeriodicMassFit>,
    pub oil_column: Option<OilColumnFit>,
    pub validation: Option<Validation>,
    /// The device force from a test with displacement and force (`None` as well when
    /// not asked for, [`super::Scope::Parameters`]).
    pub device: Option<DeviceFit>,
    /// The final mass: inverse-variance mean of the random and periodic estimates, `None`
    /// when neither exists (the parameter file then keeps the default, marked as such).
    pub mass_kg: Option<f64>,
    /// The identified model, usable by `simulate` and the FMU.
    #[serde(skip)]
    pub params: Params,
    /// What could not be identified, and why.
    pub missing: Vec<super::Missing>,
    /// What the screening of the records found and did.
    pub screening: Vec<Finding>,
    pub welch: WelchOptions,
    /// Parameter-file keys of geometry and gains the campaign does not give (kept at the
    /// defaults in `params` and listed by [`Identification::defaults`]).
    #[serde(skip)]
    pub unknown_inputs: Vec<&'static str>,
    /// The grey-box output-error fit of the closed loop, when the campaign left gains,
    /// geometry or section-4 estimates unknown (issue 16, part 3).
    pub closed_loop: Option<super::greybox::ClosedLoopFit>,
    /// Per test and channel, the identified model's simulation against the measurement
    /// (empty when not asked for, [`super::Scope::Parameters`], and no closed-loop fit
    /// made one).
    pub comparison: Vec<super::greybox::ChannelFit>,
}
