//! The rigid mass from a random test's apparent mass F/a (paper 4.1.2, eq. 4.4).

use super::error::IdentifyError;
use super::friction::bouc_wen_path;
use super::results::{FrfData, FrictionFit, MassFit};
use super::signals::{channel, smooth, welch_for};
use super::{check_bounds, check_random_length, lsq, MASS_BAND_HZ, MASS_BOUNDS_KG};
use crate::campaign::{Measured, Record};
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;

/// Apparent mass from a random test (4.1.2): `acceleration -> force` instrumented by the
/// noise-free reference acceleration (`S_rF / S_ra`), then the linear least squares
/// `Re = M - k/w^2`, `Im = -c/w` over [`MASS_BAND_HZ`].
pub fn fit_mass(name: &str, rec: &Record, fs: f64) -> Result<MassFit, IdentifyError> {
    fit_mass_corrected(name, rec, fs, None)
}

/// [`fit_mass`] on the force less the identified friction and stiffness,
/// `F_A - F_mu Z(x) - k x` (eqs. 4.4, 4.14-4.15 with `Z` along the measured path): the
/// hysteretic friction is not exactly a viscous plus a stiffness term, and removing it in
/// the time domain leaves the three-term fit only the residue.
pub fn fit_mass_corrected(
    name: &str,
    rec: &Record,
    fs: f64,
    friction: Option<(&FrictionFit, f64)>,
) -> Result<MassFit, IdentifyError> {
    const WITHOUT: &str = "mass not identified";
    let measured_force = channel(name, rec, Measured::Force, WITHOUT)?;
    let acceleration = channel(name, rec, Measured::Acceleration, WITHOUT)?;
    check_random_length(name, rec, fs, "apparent-mass fit")?;
    let w = welch_for(fs, rec.len()).map_err(|e| IdentifyError::failed(name, e))?;
    let force: Vec<f64> = match (friction, rec.displacement_m.as_deref()) {
        (Some((fr, k)), Some(x_measured)) => {
            let x = smooth(x_measured, 8);
            let z = bouc_wen_path(&x, fr.yield_displacement_m, fr.shape, 0.0);
            (0..rec.len())
                .map(|i| measured_force[i] - fr.force_n * z[i] - k * x_measured[i])
                .collect()
        }
        // no friction to remove, or no displacement to drive it along
        _ => measured_force.to_vec(),
    };
    let e = w
        .frf_instrumental(&rec.ref_acceleration_m_s2, acceleration, &force)
        .map_err(|e| IdentifyError::failed(name, e))?;
    let idx = e.band(MASS_BAND_HZ[0], MASS_BAND_HZ[1]);
    if idx.len() < 5 {
        return Err(IdentifyError::failed(
            name,
            format!("too few bins in {MASS_BAND_HZ:?} Hz"),
        ));
    }
    let mut a = DMatrix::zeros(2 * idx.len(), 3);
    let mut b = DVector::zeros(2 * idx.len());
    for (r, &i) in idx.iter().enumerate() {
        let om = 2.0 * PI * e.frequency_hz[i];
        a[(2 * r, 0)] = 1.0;
        a[(2 * r, 2)] = -1.0 / (om * om);
        b[2 * r] = e.h1[i].re;
        a[(2 * r + 1, 1)] = -1.0 / om;
        b[2 * r + 1] = e.h1[i].im;
    }
    let (x, sigma) =
        lsq::linear(&a, &b).ok_or_else(|| IdentifyError::failed(name, "mass fit failed"))?;
    check_bounds(name, "mass (kg)", x[0], MASS_BOUNDS_KG)?;
    let low = e.band(1.0, 5.0);
    let plain = low.iter().map(|&i| e.h1[i].re).sum::<f64>() / low.len().max(1) as f64;
    Ok(MassFit {
        test: name.to_string(),
        mass_kg: x[0],
        sigma_mass_kg: sigma[0],
        viscous_n_s_m: x[1],
        stiffness_like_n_m: x[2],
        plain_average_kg: plain,
        measured: FrfData::from(&e.frequency_hz, &e.h1, &e.coherence, [0.5, 50.0]),
    })
}
