//! Linearisation at rest, closed-loop poles and analytic transfer functions (nalgebra).
