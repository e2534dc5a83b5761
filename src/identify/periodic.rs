//! The mass by the loop approach from the periodic tests (paper 4.2.2, eqs. 4.5-4.12).

use super::error::IdentifyError;
use super::friction::{bouc_wen_path, sine_data, slow_list, SineData};
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
    let (per, sig): (Vec<f64>, Vec<f64>) = data
        .iter()
        .map(|d| loop_mass(d, stiffness, friction))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
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

/// The loop approach's mass of one sine `d` and its sigma: `F - F_D - k x = M a + c0`
/// (an offset `c0`), `F_D` the identified `friction` along the test's path (zero without).
fn loop_mass(
    d: &SineData,
    stiffness: f64,
    friction: Option<&FrictionFit>,
) -> Result<(f64, f64), IdentifyError> {
    let fd: Vec<f64> = match friction {
        Some(fr) => bouc_wen_path(&d.path, fr.yield_displacement_m, fr.shape, d.v[0].signum())
            .iter()
            .map(|z| fr.force_n * z)
            .collect(),
        None => vec![0.0; d.x.len()],
    };
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
    Ok((x[0], s[0]))
}

/// Start values of the yield displacement tried by the joint fit (the best by linear least
/// squares on `F_mu` and `M` starts it), m: from a stiff bearing to a soft one, so no
/// campaign's `Y` is far from a start.
const YIELD_STARTS_M: [f64; 4] = [1e-4, 3e-4, 1e-3, 3e-3];

/// Decimation of the joint fit's residuals: friction changes over `Y`, well resolved at a
/// quarter of the rate.
const JOINT_DECIMATION: usize = 4;

/// Bouc-Wen `Z` of every sine for `Y`, `b` (eq. 4.15), from the first steady peak in the
/// direction that reached it.
fn joint_paths(data: &[SineData], yield_m: f64, shape: f64) -> Vec<Vec<f64>> {
    data.iter()
        .map(|d| bouc_wen_path(&d.path, yield_m, shape, d.x[0].signum()))
        .collect()
}

/// Residuals `F_mu Z + M a - (F_A - k x)` of `p = [F_mu, Y, b, M]` over every sine.
fn joint_residuals(data: &[SineData], target: &[Vec<f64>], p: &[f64]) -> Vec<f64> {
    let z = joint_paths(data, p[1], p[2]);
    let mut r = Vec::new();
    for ((d, t), z) in data.iter().zip(target).zip(&z) {
        r.extend(
            (0..z.len())
                .step_by(JOINT_DECIMATION)
                .map(|i| p[0] * z[i] + p[3] * d.a[i] - t[i]),
        );
    }
    r
}

/// Start of the joint fit: `F_mu` and `M` by linear least squares for each of
/// [`YIELD_STARTS_M`] at `b = 0.5`, the best.
fn joint_start(data: &[SineData], target: &[Vec<f64>]) -> Option<Vec<f64>> {
    let start = |y: f64| -> Option<(Vec<f64>, f64)> {
        let z = joint_paths(data, y, 0.5);
        let (mut rows, mut rhs) = (Vec::new(), Vec::new());
        for ((d, t), z) in data.iter().zip(target).zip(&z) {
            for i in (0..z.len()).step_by(JOINT_DECIMATION) {
                rows.push([z[i], d.a[i]]);
                rhs.push(t[i]);
            }
        }
        let a = DMatrix::from_fn(rows.len(), 2, |i, j| rows[i][j]);
        let b = DVector::from_vec(rhs);
        let (x, _) = lsq::linear(&a, &b)?;
        Some((vec![x[0], y, 0.5, x[1]], (&a * &x - &b).norm_squared()))
    };
    YIELD_STARTS_M
        .iter()
        .filter_map(|&y| start(y))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(t, _)| t)
}

/// Bouc-Wen friction and mass from every sine at once, for a campaign without a random
/// test's mass (4.1.2) to start from: eq. 4.4 with eqs. 4.14-4.15,
/// `F_A - k x = M a + F_mu Z(x)`, by Levenberg-Marquardt on `F_mu, Y, b, M` (a fast sine
/// fixes `M`, a slow one `Y` and `b`; any frequencies and amplitudes). Returns the
/// friction and the mass (as a loop-approach result over all sines, Figure 8 data of the
/// first).
pub fn fit_friction_and_mass(
    c: &Campaign,
    stiffness: f64,
    f_mu0: f64,
) -> Result<(FrictionFit, PeriodicMassFit), IdentifyError> {
    let names: Vec<&str> = c
        .info
        .tests
        .iter()
        .filter(|s| s.kind == crate::campaign::TestKind::Sine)
        .map(|s| s.name.as_str())
        .collect();
    let (data, short) = sine_data(c, &names);
    if data.is_empty() {
        return Err(IdentifyError::not_usable(format!(
            "no sine test usable and no random test's mass: Bouc-Wen friction and mass not identified \
             from periodic tests{}",
            short.iter().map(|s| format!("; {s}")).collect::<String>()
        )));
    }
    let target: Vec<Vec<f64>> = data
        .iter()
        .map(|d| {
            (0..d.x.len())
                .map(|i| d.f[i] - stiffness * d.x[i])
                .collect()
        })
        .collect();
    let t0 = joint_start(&data, &target)
        .ok_or_else(|| IdentifyError::not_usable("periodic friction and mass: start fit failed"))?;
    let f_scale = if f_mu0.is_finite() && f_mu0 > 0.0 {
        f_mu0
    } else {
        t0[0].abs().max(1.0)
    };
    let (lower, upper) = (
        [0.0, 1e-5, 0.0, MASS_BOUNDS_KG[0]],
        [1e7, 0.05, 0.999, MASS_BOUNDS_KG[1]],
    );
    let t0: Vec<f64> = (0..4).map(|i| t0[i].clamp(lower[i], upper[i])).collect();
    let scale = [f_scale, t0[1], 0.5, t0[3].abs().max(1.0)];
    let residual = |p: &[f64]| Some(joint_residuals(&data, &target, p));
    let fit = lsq::minimise(residual, &t0, &lower, &upper, &scale, Default::default()).ok_or(
        IdentifyError::not_usable("periodic friction and mass: fit failed"),
    )?;
    let who = data
        .iter()
        .map(|d| d.name.as_str())
        .collect::<Vec<_>>()
        .join(", ");
    super::check_moved(&who, "periodic friction and mass fit", &fit, &t0, &scale)?;
    check_bounds(
        &who,
        "mass from the periodic tests (kg)",
        fit.theta[3],
        MASS_BOUNDS_KG,
    )?;
    Ok(joint_results(&data, &target, &fit))
}

/// The joint fit as a friction fit (Figure 9 data of the first sine) and a mass fit
/// (Figure 8 data of the first sine).
fn joint_results(
    data: &[SineData],
    target: &[Vec<f64>],
    fit: &lsq::LsqFit,
) -> (FrictionFit, PeriodicMassFit) {
    let p = &fit.theta;
    let (d0, t0) = (&data[0], &target[0]);
    let z = bouc_wen_path(&d0.path, p[1], p[2], d0.x[0].signum());
    let step = (d0.x.len() / 2000).max(1);
    let fd0: Vec<f64> = (0..d0.x.len()).map(|i| t0[i] - p[3] * d0.a[i]).collect();
    let tests: Vec<String> = data.iter().map(|d| d.name.clone()).collect();
    let friction = FrictionFit {
        tests: tests.clone(),
        force_n: p[0],
        yield_displacement_m: p[1],
        shape: p[2],
        sigma_force_n: fit.sigma[0],
        sigma_yield_displacement_m: fit.sigma[1],
        sigma_shape: fit.sigma[2],
        rms_error_n: (fit.cost / fit.residuals as f64).sqrt(),
        displacement_m: d0.x.iter().step_by(step).copied().collect(),
        velocity_m_s: d0.v.iter().step_by(step).copied().collect(),
        dissipative_force_n: fd0.iter().step_by(step).copied().collect(),
        fitted_force_n: z.iter().step_by(step).map(|z| p[0] * z).collect(),
    };
    let step = (d0.a.len() / 1500).max(1);
    let mass = PeriodicMassFit {
        tests,
        per_test_kg: vec![p[3]],
        mass_kg: p[3],
        sigma_mass_kg: fit.sigma[3],
        acceleration_m_s2: d0.a.iter().step_by(step).copied().collect(),
        inertial_force_n: t0.iter().step_by(step).copied().collect(),
    };
    (friction, mass)
}

/// Friction and loop mass from the periodic tests alone (no random test's mass): the
/// joint fit [`fit_friction_and_mass`], then the sines split by its mass and friction
/// ([`super::select::sine_roles`]) and the loop approach on the fast ones with its
/// friction removed; without a fast sine the joint fit's mass stands for the loop's.
pub fn periodic_without_random_mass(
    c: &Campaign,
    stiffness: f64,
    f_mu0: f64,
) -> (
    Result<FrictionFit, IdentifyError>,
    Result<PeriodicMassFit, IdentifyError>,
) {
    let (friction, joint) = match fit_friction_and_mass(c, stiffness, f_mu0) {
        Ok(x) => x,
        Err(e) => {
            let upstream = IdentifyError::NeedsUpstream {
                what: "mass by the loop approach".into(),
                needs: "the periodic friction and mass fit".into(),
            };
            return (Err(e), Err(upstream));
        }
    };
    let (_, fast) = super::select::sine_roles(c, joint.mass_kg, friction.force_n);
    let loop_mass = fit_mass_periodic(c, &fast, stiffness, Some(&friction)).or(Ok(joint));
    (Ok(friction), loop_mass)
}
