//! Argmin's derivative-free minimisers: Nelder-Mead from a point and a step per
//! coordinate (the polishes on the predictive score, whose finite-difference gradients
//! are noise: stick-slip's chatter, free play's impacts), and Brent's search of one
//! parameter over an interval.

use argmin::core::{CostFunction, Executor};
use argmin::solver::brent::BrentOpt;
use argmin::solver::neldermead::NelderMead;

/// Argmin's Brent minimisation of `cost` over `[lower, upper]`, to the tolerance
/// `relative * |x| + absolute`, in at most `iterations`. The best point seen and its
/// cost; `None` when argmin fails.
pub(in crate::diagnose) fn brent(
    cost: impl Fn(f64) -> f64,
    [lower, upper]: [f64; 2],
    [relative, absolute]: [f64; 2],
    iterations: u64,
) -> Option<(f64, f64)> {
    struct Cost<F>(F);
    impl<F: Fn(f64) -> f64> CostFunction for Cost<F> {
        type Param = f64;
        type Output = f64;
        fn cost(&self, x: &f64) -> Result<f64, argmin::core::Error> {
            Ok((self.0)(*x))
        }
    }
    let solver = BrentOpt::new(lower, upper).set_tolerance(relative, absolute);
    let state = Executor::new(Cost(cost), solver)
        .configure(|s| s.max_iters(iterations))
        .run()
        .ok()?
        .state;
    Some((state.best_param?, state.best_cost))
}

/// Argmin's Nelder-Mead on `cost` from `x0`, the initial simplex stepping coordinate `k`
/// by `steps[k]`; it stops when the simplex's costs spread by less than `sd_tolerance`,
/// or after `iterations`. The best point seen and its cost; `None` when argmin fails.
pub(super) fn nelder_mead(
    cost: impl Fn(&[f64]) -> f64,
    x0: &[f64],
    steps: &[f64],
    sd_tolerance: f64,
    iterations: u64,
) -> Option<(Vec<f64>, f64)> {
    struct Cost<F>(F);
    impl<F: Fn(&[f64]) -> f64> CostFunction for Cost<F> {
        type Param = Vec<f64>;
        type Output = f64;
        fn cost(&self, x: &Vec<f64>) -> Result<f64, argmin::core::Error> {
            Ok((self.0)(x))
        }
    }
    let mut simplex = vec![x0.to_vec()];
    for (k, h) in steps.iter().enumerate() {
        let mut x = x0.to_vec();
        x[k] += h;
        simplex.push(x);
    }
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(sd_tolerance)
        .ok()?;
    let state = Executor::new(Cost(cost), solver)
        .configure(|s| s.max_iters(iterations))
        .run()
        .ok()?
        .state;
    Some((state.best_param?, state.best_cost))
}
