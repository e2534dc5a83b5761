//! The mass by the loop approach from the periodic tests (paper 4.2.2, eqs. 4.5-4.12).

use super::error::IdentifyError;
use super::friction::{bouc_wen_path, sine_data, slow_list};
use super::results::{FrictionFit, PeriodicMassFit};
use super::{check_bounds, lsq, MASS_BOUNDS_KG};
use crate::campaign::Campaign;
use nalgebra::{DMatrix, DVector};

/// Mass by the loop approach (eqs. 4.11-4.12) from the fast sines `fast` ([`super::select`]): pairing `t` with `T/2 - t`
/// cancels the dissipative force; over whole steady cycles that is the least squares
/// `F_A - F_D - k x = M a` with the identified friction removed first.
pub fn fit_mass_periodic(
    c: &Campaign,
    fast: &[String],
    stiffness: f64,
    friction: Option<&FrictionFit>,
) -> Result<PeriodicMassFit, IdentifyError> {
    let names: Vec<&str> = fast.iter().map(String::as_str).collect();
    let (data, short) = sine_data(c, &names);
    if data.is_empty() {
        return Err(IdentifyError::not_usable(format!(
            "no fast sine test ({}) usable: mass not identified by the loop approach{}",
            slow_list(
                fast,
                "a sine whose inertia force exceeds twice the friction"
            ),
            short.iter().map(|s| format!("; {s}")).collect::<String>()
        )));
    }
    let mut per = Vec::new();
    let mut sig = Vec::new();
    for d in &data {
        let fd: Vec<f64> = match friction {
            Some(fr) => bouc_wen_path(&d.x, fr.yield_displacement_m, fr.shape, d.v[0].signum())
                .iter()
                .map(|z| fr.force_n * z)
                .collect(),
            None => vec![0.0; d.x.len()],
        };
        // F - F_D - k x = M a + c0 (offset)
        let a = DMatrix::from_fn(d.a.len(), 2, |i, j| if j == 0 { d.a[i] } else { 1.0 });
        let b = DVector::from_iterator(
            d.a.len(),
            (0..d.a.len()).map(|i| d.f[i] - fd[i] - stiffness * d.x[i]),
        );
        let (x, s) = lsq::linear(&a, &b)
            .ok_or_else(|| IdentifyError::failed(&d.name, "loop-approach fit failed"))?;
        check_bounds(
            &d.name,
            "mass by the loop approach (kg)",
            x[0],
            MASS_BOUNDS_KG,
        )?;
        per.push(x[0]);
        sig.push(s[0]);
    }
    let mass = per.iter().sum::<f64>() / per.len() as f64;
    let spread = if per.len() > 1 {
        (per.iter().map(|m| (m - mass).powi(2)).sum::<f64>()
            / (per.len() as f64 * (per.len() - 1) as f64))
            .sqrt()
    } else {
        sig[0]
    };
    let d0 = &data[0];
    let step = (d0.a.len() / 1500).max(1);
    Ok(PeriodicMassFit {
        tests: data.iter().map(|d| d.name.clone()).collect(),
        per_test_kg: per,
        mass_kg: mass,
        sigma_mass_kg: spread,
        acceleration_m_s2: d0.a.iter().step_by(step).copied().collect(),
        inertial_force_n: (0..d0.a.len())
            .step_by(step)
            .map(|i| d0.f[i] - stiffness * d0.x[i])
            .collect(),
    })
}
