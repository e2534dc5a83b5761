//! Nonlinear least squares (Levenberg-Marquardt) for the identification and diagnosis fits.
//!
//! Written here rather than taken from the `levenberg-marquardt` crate because the fits
//! need what it leaves to the caller: finite-difference Jacobians of residuals that are
//! whole simulations (evaluated in parallel with rayon), box bounds on physical
//! parameters, and the parameter covariance for the reported uncertainty.

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Options of [`minimise`].
#[derive(Debug, Clone, Copy)]
pub struct LsqOptions {
    pub max_iterations: usize,
    /// Stop when the relative cost decrease of an accepted step is below this.
    pub tolerance: f64,
    /// Relative finite-difference step (of `max(|theta|, scale)`).
    pub step: f64,
    /// Evaluate Jacobian columns in parallel.
    pub parallel: bool,
}

impl Default for LsqOptions {
    fn default() -> Self {
        LsqOptions {
            max_iterations: 60,
            tolerance: 1e-10,
            step: 1e-6,
            parallel: false,
        }
    }
}

/// Result of a fit.
#[derive(Debug, Clone)]
pub struct LsqFit {
    pub theta: Vec<f64>,
    /// Sum of squared residuals at `theta`.
    pub cost: f64,
    pub residuals: usize,
    /// One-sigma uncertainty of each parameter from `s^2 (J^T J)^-1`; when that is
    /// singular, infinite for a parameter the data cannot fix
    /// ([`ScaledNormal::singular_sigma`]).
    pub sigma: Vec<f64>,
    /// `s^2 (J^T J)^-1`, `None` when singular.
    pub covariance: Option<DMatrix<f64>>,
    pub iterations: usize,
}

/// Levenberg-Marquardt's damping at the start.
const LAMBDA_START: f64 = 1e-3;
/// The damping is multiplied by this after an accepted step (trust the Gauss-Newton step
/// more) and by [`LAMBDA_UP`] after a rejected one (the classic 0.3 and 10: a rejection
/// costs one evaluation, so the damping climbs fast and relaxes slowly).
const LAMBDA_DOWN: f64 = 0.3;
const LAMBDA_UP: f64 = 10.0;
/// Floor of the damping after accepted steps.
const LAMBDA_MIN: f64 = 1e-12;
/// Trial steps per iteration, each with ten times the damping of the last: 12 span
/// twelve decades; an iteration whose steps all fail ends the fit.
const TRIALS_PER_ITERATION: usize = 12;
/// Floor of `scale^2 x` this on the damped diagonal (a dead column still gets damping).
const DIAGONAL_FLOOR: f64 = 1e-30;

/// Minimise `sum r(theta)^2` from `theta0` within `[lower, upper]` (per parameter).
/// `scale` gives each parameter's typical magnitude (for steps and damping).
/// Residuals that are not finite make a trial step fail (it is rejected).
pub fn minimise<F>(
    residuals: F,
    theta0: &[f64],
    lower: &[f64],
    upper: &[f64],
    scale: &[f64],
    opts: LsqOptions,
) -> Option<LsqFit>
where
    F: Fn(&[f64]) -> Option<Vec<f64>> + Sync,
{
    if !problem_is_sound(theta0, lower, upper, scale) {
        return None;
    }
    let problem = Problem {
        residuals: &residuals,
        lower,
        upper,
        scale,
        opts,
    };
    let mut theta = theta0.to_vec();
    problem.clamp(&mut theta);
    let mut r = problem.residuals_at(&theta)?;
    let m = r.len();
    let mut c = cost(&r);
    let mut lambda = LAMBDA_START;
    let mut iterations = 0;
    let mut jm = problem.jacobian(&theta, &r)?;
    while iterations < opts.max_iterations {
        iterations += 1;
        let Some(step) = problem.damped_step(&jm, &theta, &r, c, &mut lambda) else {
            break;
        };
        let rel = (c - step.cost) / c.max(1e-300);
        (theta, r, c) = (step.theta, step.residuals, step.cost);
        if rel < opts.tolerance {
            return Some(finish(theta, c, m, &jm, iterations));
        }
        jm = problem.jacobian(&theta, &r)?;
    }
    Some(finish(theta, c, m, &jm, iterations))
}

/// Sum of squares of `r`.
fn cost(r: &[f64]) -> f64 {
    r.iter().map(|x| x * x).sum::<f64>()
}

/// What [`minimise`] minimises: the residuals and the box, scales and options.
struct Problem<'a, F> {
    residuals: &'a F,
    lower: &'a [f64],
    upper: &'a [f64],
    scale: &'a [f64],
    opts: LsqOptions,
}

/// An accepted step: the new parameters, their residuals and cost.
struct Step {
    theta: Vec<f64>,
    residuals: Vec<f64>,
    cost: f64,
}

impl<F> Problem<'_, F>
where
    F: Fn(&[f64]) -> Option<Vec<f64>> + Sync,
{
    /// `t` within the bounds.
    fn clamp(&self, t: &mut [f64]) {
        for (i, x) in t.iter_mut().enumerate() {
            *x = x.clamp(self.lower[i], self.upper[i]);
        }
    }

    /// The residuals at `theta`, `None` when they cannot be computed or are not finite.
    fn residuals_at(&self, theta: &[f64]) -> Option<Vec<f64>> {
        (self.residuals)(theta).filter(|r| r.iter().all(|x| x.is_finite()))
    }

    /// The finite-difference Jacobian at `theta` (residuals `r`), columns in parallel
    /// when the options ask; `None` when a column cannot be computed.
    fn jacobian(&self, theta: &[f64], r: &[f64]) -> Option<DMatrix<f64>> {
        let n = theta.len();
        let m = r.len();
        let column = |j: usize| self.column(theta, r, j);
        let cols: Vec<Option<Vec<f64>>> = if self.opts.parallel {
            (0..n).into_par_iter().map(column).collect()
        } else {
            (0..n).map(column).collect()
        };
        let mut jm = DMatrix::zeros(m, n);
        for (j, col) in cols.into_iter().enumerate() {
            let col = col?;
            for i in 0..m {
                jm[(i, j)] = col[i];
            }
        }
        Some(jm)
    }

    /// Column `j` of the Jacobian: steps inside the bounds, forward first; a parameter
    /// pinned by its bounds has no column (zeros); a step whose model cannot be simulated
    /// (a limit of the model's that is not a box bound, such as the solver's reach) is
    /// taken the other way.
    fn column(&self, theta: &[f64], r: &[f64], j: usize) -> Option<Vec<f64>> {
        let h = self.opts.step * theta[j].abs().max(self.scale[j]);
        let steps = [h, -h]
            .into_iter()
            .filter(|s| (self.lower[j]..=self.upper[j]).contains(&(theta[j] + s)));
        let mut pinned = true;
        for h in steps {
            pinned = false;
            let mut t = theta.to_vec();
            t[j] += h;
            if let Some(rp) = self.residuals_at(&t) {
                return Some(rp.iter().zip(r).map(|(a, b)| (a - b) / h).collect());
            }
        }
        pinned.then(|| vec![0.0; r.len()])
    }

    /// The first damped Gauss-Newton step from `theta` (Jacobian `jm`, residuals `r`,
    /// cost `c`) that lowers the cost, raising the damping `lambda` after each one that
    /// does not and lowering it on success; `None` when [`TRIALS_PER_ITERATION`] fail.
    fn damped_step(
        &self,
        jm: &DMatrix<f64>,
        theta: &[f64],
        r: &[f64],
        c: f64,
        lambda: &mut f64,
    ) -> Option<Step> {
        let n = theta.len();
        let jt = jm.transpose();
        let jtj = &jt * jm;
        let g = &jt * DVector::from_row_slice(r);
        for _ in 0..TRIALS_PER_ITERATION {
            let mut a = jtj.clone();
            for i in 0..n {
                let floor = DIAGONAL_FLOOR / (self.scale[i] * self.scale[i]);
                a[(i, i)] += *lambda * jtj[(i, i)].max(floor);
            }
            let Some(delta) = a.lu().solve(&(-&g)) else {
                *lambda *= LAMBDA_UP;
                continue;
            };
            let mut trial: Vec<f64> = (0..n).map(|i| theta[i] + delta[i]).collect();
            self.clamp(&mut trial);
            match self.residuals_at(&trial) {
                Some(rt) if cost(&rt) < c => {
                    *lambda = (*lambda * LAMBDA_DOWN).max(LAMBDA_MIN);
                    return Some(Step {
                        cost: cost(&rt),
                        theta: trial,
                        residuals: rt,
                    });
                }
                _ => *lambda *= LAMBDA_UP,
            }
        }
        None
    }
}

/// Whether the start, bounds and scales make a problem [`minimise`] can run: every value
/// finite, matching lengths, `lower <= upper` and positive scales (data-derived starts or
/// bounds may be NaN; `f64::clamp` panics on such bounds).
fn problem_is_sound(theta0: &[f64], lower: &[f64], upper: &[f64], scale: &[f64]) -> bool {
    let n = theta0.len();
    n > 0
        && [lower.len(), upper.len(), scale.len()]
            .iter()
            .all(|&l| l == n)
        && (0..n).all(|i| {
            theta0[i].is_finite()
                && lower[i].is_finite()
                && upper[i].is_finite()
                && lower[i] <= upper[i]
                && scale[i].is_finite()
                && scale[i] > 0.0
        })
}

impl LsqFit {
    /// Whether the fit moved from `theta0` (relative change above `1e-9` of the scale in
    /// some parameter): a fit that did not move reports its start, not an estimate.
    pub fn moved_from(&self, theta0: &[f64], scale: &[f64]) -> bool {
        self.iterations > 0
            && self
                .theta
                .iter()
                .zip(theta0)
                .zip(scale)
                .any(|((t, t0), s)| (t - t0).abs() > 1e-9 * t0.abs().max(*s))
    }
}

/// Eigenvalues of the scaled `J^T J` (unit diagonal: columns normalised, so that units do
/// not count) below this are a null direction: the matrix is singular only when columns
/// are exactly dependent (a limit that does not bind, a parameter the channels do not
/// reach), which leaves eigenvalues at rounding level, 1e-16; 1e-12 keeps a margin above.
const NULL_EIGENVALUE: f64 = 1e-12;

/// Most QR sweeps of the eigen-decomposition: a few per eigenvalue suffice for the at
/// most dozen parameters of a fit, so a thousand is a wide margin that still returns.
const EIGEN_ITERATION_LIMIT: usize = 1000;

/// A parameter whose squared share of a null direction exceeds this is not identified.
const NULL_SHARE: f64 = 1e-6;

/// `J^T J` scaled to a unit diagonal over its live columns (those with a positive
/// diagonal; units do not count), and its eigen-decomposition: what both the covariance
/// and the singular sigmas read. `None` when the scaled matrix is not finite (nalgebra's
/// `SymmetricEigen::new` would never return on it) or the decomposition does not converge.
struct ScaledNormal {
    live: Vec<usize>,
    d: Vec<f64>,
    eig: nalgebra::SymmetricEigen<f64, nalgebra::Dyn>,
}

impl ScaledNormal {
    fn of(jtj: &DMatrix<f64>) -> Option<Self> {
        let n = jtj.nrows();
        let live: Vec<usize> = (0..n).filter(|&i| jtj[(i, i)] > 0.0).collect();
        let d: Vec<f64> = live.iter().map(|&i| jtj[(i, i)].sqrt()).collect();
        let m = live.len();
        let scaled = DMatrix::from_fn(m, m, |a, b| jtj[(live[a], live[b])] / (d[a] * d[b]));
        if !scaled.iter().all(|x| x.is_finite()) {
            return None;
        }
        let eig = nalgebra::SymmetricEigen::try_new(scaled, f64::EPSILON, EIGEN_ITERATION_LIMIT)?;
        Some(ScaledNormal { live, d, eig })
    }

    fn null(&self, j: usize) -> bool {
        !(self.eig.eigenvalues[j] > NULL_EIGENVALUE)
    }

    /// The covariance `s2 (J^T J)^-1` of `n` parameters through the eigen-decomposition;
    /// `None` when a column is dead or a direction is null (the data do not fix it). A
    /// plain inverse of a nearly singular matrix returns rounding noise without failing.
    fn covariance(&self, n: usize, s2: f64) -> Option<DMatrix<f64>> {
        let m = self.live.len();
        if m < n || (0..m).any(|j| self.null(j)) {
            return None;
        }
        let inverse_eigenvalues = DMatrix::from_diagonal(&self.eig.eigenvalues.map(|l| 1.0 / l));
        let inv = &self.eig.eigenvectors * inverse_eigenvalues * self.eig.eigenvectors.transpose();
        let d = &self.d;
        Some(DMatrix::from_fn(n, n, |a, b| {
            s2 * inv[(a, b)] / (d[a] * d[b])
        }))
    }

    /// One-sigma uncertainties of `n` parameters from a singular `J^T J` (scaled by
    /// `s2`): infinite for a parameter whose column is zero or that takes part in a null
    /// direction (the data cannot fix it), and from the pseudo-inverse for the others,
    /// whose estimates the null directions do not touch (a flow limit that never binds
    /// leaves the other parameters' uncertainties defined).
    fn singular_sigma(&self, n: usize, s2: f64) -> Vec<f64> {
        let m = self.live.len();
        let mut sigma = vec![f64::INFINITY; n];
        for (a, &i) in self.live.iter().enumerate() {
            let v = |j: usize| self.eig.eigenvectors[(a, j)].powi(2);
            if (0..m).filter(|&j| self.null(j)).map(v).sum::<f64>() > NULL_SHARE {
                continue;
            }
            let var: f64 = (0..m)
                .filter(|&j| !self.null(j))
                .map(|j| v(j) / self.eig.eigenvalues[j])
                .sum();
            sigma[i] = (s2 * var).sqrt() / self.d[a];
        }
        sigma
    }
}

fn finish(theta: Vec<f64>, cost: f64, m: usize, jm: &DMatrix<f64>, iterations: usize) -> LsqFit {
    let n = theta.len();
    let dof = (m as f64 - n as f64).max(1.0);
    let s2 = cost / dof;
    let jtj = jm.transpose() * jm;
    // one decomposition serves the covariance and, when it has none, the sigmas
    let scaled = ScaledNormal::of(&jtj);
    let covariance = scaled.as_ref().and_then(|s| s.covariance(n, s2));
    let sigma = match (&covariance, &scaled) {
        (Some(cov), _) => (0..n).map(|i| cov[(i, i)].max(0.0).sqrt()).collect(),
        (None, Some(s)) => s.singular_sigma(n, s2),
        (None, None) => vec![f64::INFINITY; n],
    };
    LsqFit {
        theta,
        cost,
        residuals: m,
        sigma,
        covariance,
        iterations,
    }
}

/// Linear least squares `min |A x - b|` (SVD), with the one-sigma parameter uncertainty.
pub fn linear(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<(DVector<f64>, Vec<f64>)> {
    if a.nrows() < a.ncols() || a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
        return None;
    }
    let svd = a.clone().svd(true, true);
    let x = svd.solve(b, 1e-12).ok()?;
    if x.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let r = a * &x - b;
    let dof = (a.nrows() as f64 - a.ncols() as f64).max(1.0);
    let s2 = r.norm_squared() / dof;
    let cov = (a.transpose() * a).try_inverse();
    let sigma = match cov {
        Some(c) => (0..a.ncols())
            .map(|i| (s2 * c[(i, i)]).max(0.0).sqrt())
            .collect(),
        None => vec![f64::NAN; a.ncols()],
    };
    Some((x, sigma))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`ScaledNormal::singular_sigma`] of `jtj`, infinite everywhere when it cannot be
    /// decomposed (such a fit's uncertainty is unknown).
    fn singular_sigma(jtj: DMatrix<f64>, s2: f64) -> Vec<f64> {
        let n = jtj.nrows();
        ScaledNormal::of(&jtj).map_or(vec![f64::INFINITY; n], |s| s.singular_sigma(n, s2))
    }

    /// A singular `J^T J` with a non-finite entry (an infinite diagonal divides to NaN)
    /// gives infinite sigmas at once rather than an endless eigen-iteration.
    #[test]
    fn a_non_finite_normal_matrix_has_unknown_sigma() {
        let mut jtj = DMatrix::from_element(3, 3, 1.0);
        jtj[(1, 1)] = f64::INFINITY;
        let sigma = singular_sigma(jtj, 1.0);
        assert!(sigma.iter().all(|s| s.is_infinite()), "{sigma:?}");
    }

    /// A singular `J^T J` (one parameter that never reaches the residual): that one's
    /// sigma is infinite, the others' are those of the fit without it.
    #[test]
    fn a_parameter_the_data_cannot_fix_has_infinite_sigma() {
        let t: Vec<f64> = (0..40).map(|i| i as f64).collect();
        // residuals of a line `a + b t` against noisy data, and a third column of zeros
        let noise = |i: usize| 0.1 * ((i * 7919) % 13) as f64 / 13.0 - 0.05;
        let r = |p: &[f64; 3]| -> Vec<f64> {
            t.iter()
                .enumerate()
                .map(|(i, t)| p[0] + p[1] * t - (1.0 + 0.5 * t + noise(i)) + 0.0 * p[2])
                .collect()
        };
        let jac = |p: [f64; 3]| {
            let r0 = r(&p);
            DMatrix::from_fn(t.len(), 3, |i, j| {
                let mut q = p;
                q[j] += 1e-6;
                (r(&q)[i] - r0[i]) / 1e-6
            })
        };
        let p = [1.0, 0.5, 0.0];
        let s2 = r(&p).iter().map(|x| x * x).sum::<f64>() / 37.0;
        let jm = jac(p);
        let sigma = singular_sigma(jm.transpose() * &jm, s2);
        assert!(sigma[2].is_infinite(), "{sigma:?}");
        let reduced = jm.columns(0, 2).into_owned();
        let cov = (reduced.transpose() * &reduced).try_inverse().unwrap() * s2;
        for i in 0..2 {
            let want = cov[(i, i)].sqrt();
            assert!(
                (sigma[i] / want - 1.0).abs() < 1e-6,
                "{i}: {} vs {want}",
                sigma[i]
            );
        }
    }

    /// Fit `y = a exp(-b t)` to exact data from a poor start.
    #[test]
    fn recovers_an_exponential() {
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 3.0 * (-0.7 * t).exp()).collect();
        let f = minimise(
            |p| {
                Some(
                    t.iter()
                        .zip(&y)
                        .map(|(t, y)| p[0] * (-p[1] * t).exp() - y)
                        .collect(),
                )
            },
            &[1.0, 2.0],
            &[0.0, 0.0],
            &[10.0, 10.0],
            &[1.0, 1.0],
            LsqOptions::default(),
        )
        .unwrap();
        assert!(
            (f.theta[0] - 3.0).abs() < 1e-6 && (f.theta[1] - 0.7).abs() < 1e-6,
            "{:?}",
            f.theta
        );
    }

    /// The diagnosis fits with parallel Jacobian columns and relies on the result being
    /// the same whatever the threads (its outputs are compared byte for byte): the fit
    /// with columns in parallel, on one thread and on four, is bit for bit the
    /// sequential one.
    #[test]
    fn parallel_columns_give_the_sequential_fit_bit_for_bit() {
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.05).collect();
        let y: Vec<f64> = t
            .iter()
            .map(|t| 2.0 * (-0.3 * t).exp() * (4.0 * t).cos() + 0.01 * (17.0 * t).sin())
            .collect();
        let fit = |parallel: bool| {
            minimise(
                |p| {
                    Some(
                        t.iter()
                            .zip(&y)
                            .map(|(t, y)| p[0] * (-p[1] * t).exp() * (p[2] * t).cos() - y)
                            .collect(),
                    )
                },
                &[1.0, 0.5, 3.8],
                &[0.0, 0.0, 0.0],
                &[10.0, 10.0, 10.0],
                &[1.0, 1.0, 1.0],
                LsqOptions {
                    parallel,
                    ..LsqOptions::default()
                },
            )
            .unwrap()
        };
        let bits = |f: &LsqFit| {
            let mut v: Vec<u64> = f.theta.iter().map(|x| x.to_bits()).collect();
            v.extend(f.sigma.iter().map(|x| x.to_bits()));
            v.push(f.cost.to_bits());
            v
        };
        let sequential = fit(false);
        assert!(
            (sequential.theta[2] - 4.0).abs() < 1e-3,
            "{:?}",
            sequential.theta
        );
        for threads in [1, 4] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let parallel = pool.install(|| fit(true));
            assert_eq!(bits(&parallel), bits(&sequential), "{threads} threads");
            assert_eq!(parallel.iterations, sequential.iterations);
        }
    }

    #[test]
    fn bounds_hold() {
        let f = minimise(
            |p| Some(vec![p[0] - 5.0]),
            &[0.5],
            &[0.0],
            &[1.0],
            &[1.0],
            LsqOptions::default(),
        )
        .unwrap();
        assert_eq!(f.theta[0], 1.0);
    }

    /// A model limit that is not a box bound (the solver's reach): at a start on it the
    /// forward difference cannot be simulated, so the Jacobian steps back, and the fit
    /// runs to the best model inside the limit instead of failing.
    #[test]
    fn a_jacobian_steps_back_from_a_limit_that_is_no_bound() {
        let data = [1.0, 2.0, 3.0];
        // the model y = a x cannot be simulated beyond a = 0.5; the data want a = 1
        let residuals = |t: &[f64]| -> Option<Vec<f64>> {
            (t[0] <= 0.5).then(|| data.iter().map(|x| t[0] * x - x).collect())
        };
        let fit = minimise(
            residuals,
            &[0.5],
            &[0.0],
            &[10.0],
            &[1.0],
            Default::default(),
        )
        .expect("a fit from the limit");
        assert!((fit.theta[0] - 0.5).abs() < 1e-9, "{:?}", fit.theta);
        let fit = minimise(
            residuals,
            &[0.2],
            &[0.0],
            &[10.0],
            &[1.0],
            Default::default(),
        )
        .expect("a fit up to the limit");
        assert!(
            fit.theta[0] <= 0.5 && fit.theta[0] > 0.45,
            "{:?}",
            fit.theta
        );
    }
}
