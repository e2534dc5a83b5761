//! The oil column from the spool-to-force FRF of the oil-column test (paper 4.1.3).

use super::error::IdentifyError;
use super::frf::FrfEstimate;
use super::lsq::{minimise, LsqOptions};
use super::mass::fit_mass;
use super::results::{FrfData, OilColumnFit};
use super::signals::{channel, spool_channel, welch_for};
use super::{
    check_bounds, check_random_length, lsq, DAMPING_BOUNDS, FREQUENCY_BOUNDS_HZ, MASS_BOUNDS_KG,
    OIL_BAND_HZ,
};
use crate::campaign::{Measured, Record};
use num_complex::Complex64;
use std::f64::consts::PI;

/// `F / x_v` of the ideal actuator on a table of apparent stiffness `Z(s) = M s^2 + c s + k`:
/// The geometry the oil-column fit needs, all known.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OilGeometry {
    pub piston_area_m2: f64,
    pub total_oil_volume_m3: f64,
    pub flow_gain_m3_s: f64,
}

impl OilGeometry {
    /// From the campaign's `[geometry]`, or the error naming the keys nobody gave: the
    /// spool-to-force FRF fixes `Kq A` and `A^2 / k_oil` together, so without the piston
    /// area, the flow gain and the oil volume the bulk modulus and leakage cannot be told.
    pub fn from_campaign(g: &crate::campaign::Geometry) -> Result<OilGeometry, IdentifyError> {
        match (g.piston_area_m2, g.total_oil_volume_m3, g.flow_gain_m3_s) {
            (Some(a), Some(v), Some(q)) => Ok(OilGeometry {
                piston_area_m2: a,
                total_oil_volume_m3: v,
                flow_gain_m3_s: q,
            }),
            _ => {
                let unknown: Vec<&str> = [
                    ("geometry.piston_area_m2", g.piston_area_m2),
                    ("geometry.total_oil_volume_m3", g.total_oil_volume_m3),
                    ("geometry.flow_gain_m3_s", g.flow_gain_m3_s),
                ]
                .iter()
                .filter(|(_, v)| v.is_none())
                .map(|(k, _)| *k)
                .collect();
                Err(IdentifyError::NeedsUpstream {
                    what: "oil column (bulk modulus, leakage)".into(),
                    needs: format!("{} in campaign.toml (unknown)", unknown.join(", ")),
                })
            }
        }
    }
}

/// `g Kq A / ((A^2/k_oil) s + A^2 s / Z(s) + C_l)` (spec section 4).
pub(super) fn spool_to_force_model(
    s: Complex64,
    kq_a: f64,
    area: f64,
    k_oil: f64,
    leak: f64,
    z: Complex64,
) -> Complex64 {
    kq_a / (area * area / k_oil * s + area * area * s / z + leak)
}

/// Oil column from R3 (4.1.3): `spool -> force` with the valve command as instrument,
/// fitted with the actuator model for `k_oil`, `C_l` and a flow-gain scale; the table's
/// `Z(s) = F/x` uses the final mass plus R3's own measured non-inertial part of the
/// apparent mass (the friction at R3's amplitude, bin by bin).
pub fn fit_oil_column(
    name: &str,
    rec: &Record,
    fs: f64,
    geometry: &OilGeometry,
    mass_kg: f64,
) -> Result<OilColumnFit, IdentifyError> {
    let x = spool_channel(rec).ok_or_else(|| IdentifyError::MissingChannel {
        test: name.to_string(),
        channel: "spool_position",
        consequence: "oil column not identified",
    })?;
    const WITHOUT: &str = "oil column not identified";
    let u = channel(name, rec, Measured::ValveCommand, WITHOUT)?;
    let force = channel(name, rec, Measured::Force, WITHOUT)?;
    let acceleration = channel(name, rec, Measured::Acceleration, WITHOUT)?;
    check_random_length(name, rec, fs, "oil-column fit")?;
    check_bounds(
        name,
        "mass used by the oil-column fit (kg)",
        mass_kg,
        MASS_BOUNDS_KG,
    )?;
    let w = welch_for(fs, rec.len()).map_err(|e| IdentifyError::failed(name, e))?;
    let iv = w
        .frf_instrumental(u, x, force)
        .map_err(|e| IdentifyError::failed(name, e))?;
    let area = geometry.piston_area_m2;
    let kq_a = geometry.flow_gain_m3_s * area;
    // the table's own dissipative/elastic part at R3's amplitude, measured: the apparent
    // mass of R3 less its fitted mass (friction is amplitude dependent, so R2's would not do)
    let own = fit_mass(name, rec, fs)?;
    let apparent = w
        .frf_instrumental(&rec.ref_acceleration_m_s2, acceleration, force)
        .map_err(|e| IdentifyError::failed(name, e))?;
    let fit_on = |h: &[Complex64], e: &FrfEstimate| -> Option<(lsq::LsqFit, Vec<usize>)> {
        let idx = e.band(OIL_BAND_HZ[0], OIL_BAND_HZ[1]);
        let k0 = mass_kg * (2.0 * PI * 14.0f64).powi(2);
        let l0 = 1e-10;
        let resid = |p: &[f64]| -> Option<Vec<f64>> {
            let mut r = Vec::with_capacity(2 * idx.len());
            for &i in &idx {
                let s = Complex64::new(0.0, 2.0 * PI * e.frequency_hz[i]);
                // Z(s) = F/x = s^2 (M + (F/a - M_R3))
                let z = s * s * (mass_kg + apparent.h1[i] - own.mass_kg);
                let m = spool_to_force_model(s, p[2] * kq_a, area, p[0], p[1], z);
                let d = (m - h[i]) / h[i].norm().max(1e-9) * e.coherence[i].sqrt();
                r.push(d.re);
                r.push(d.im);
            }
            Some(r)
        };
        let (t0, scale) = ([k0, l0, 1.0], [k0, l0, 1.0]);
        minimise(
            resid,
            &t0,
            &[k0 * 0.05, 0.0, 0.1],
            &[k0 * 20.0, 1e-7, 10.0],
            &scale,
            LsqOptions::default(),
        )
        .filter(|f| f.moved_from(&t0, &scale))
        .map(|f| (f, idx))
    };
    let (fit, _) = fit_on(&iv.h1, &iv).ok_or_else(|| {
        IdentifyError::failed(
            name,
            "oil-column fit failed or did not move from its start values",
        )
    })?;
    // H1 from the noisy spool, for the report's comparison
    let plain = w
        .frf(x, force)
        .map_err(|e| IdentifyError::failed(name, e))?;
    let h1fit = fit_on(&plain.h1, &plain).map(|(f, _)| f);
    let figures = |k_oil: f64, leak: f64| {
        let beta = k_oil * geometry.total_oil_volume_m3 / (4.0 * area * area);
        let f = (k_oil / mass_kg).sqrt() / (2.0 * PI);
        let zeta = leak / area * (beta * mass_kg / geometry.total_oil_volume_m3).sqrt();
        (f, zeta, beta)
    };
    let (f_oil, zeta, beta) = figures(fit.theta[0], fit.theta[1]);
    check_bounds(
        name,
        "oil-column frequency (Hz)",
        f_oil,
        FREQUENCY_BOUNDS_HZ,
    )?;
    check_bounds(name, "oil-column damping ratio", zeta, DAMPING_BOUNDS)?;
    check_bounds(name, "bulk modulus (Pa)", beta, [1e6, 1e11])?;
    let (h1f, h1z) = h1fit
        .map(|f| {
            let (a, b, _) = figures(f.theta[0], f.theta[1]);
            (a, b)
        })
        .unwrap_or((f64::NAN, f64::NAN));
    let rel_k = fit.sigma[0] / fit.theta[0];
    Ok(OilColumnFit {
        test: name.to_string(),
        frequency_hz: f_oil,
        damping_ratio: zeta,
        bulk_modulus_pa: beta,
        leakage_m3_s_pa: fit.theta[1],
        stiffness_n_m: fit.theta[0],
        flow_gain_scale: fit.theta[2],
        sigma_frequency_hz: 0.5 * rel_k * f_oil,
        sigma_damping_ratio: zeta * (fit.sigma[1] / fit.theta[1].max(1e-300)).hypot(0.5 * rel_k),
        sigma_bulk_modulus_pa: rel_k * beta,
        h1_frequency_hz: h1f,
        h1_damping_ratio: h1z,
        measured: FrfData::from(&iv.frequency_hz, &iv.h1, &iv.coherence, [1.0, 60.0]),
        mass_used_kg: mass_kg,
    })
}
