//! Three-variable controller with delta-P stabilisation (spec section 2).

use crate::params::Controller;

/// What the controller measures (noise included, spec section 2).
#[derive(Debug, Clone, Copy, Default)]
pub struct Feedback {
    /// LVDT displacement (relative to the reaction mass), m.
    pub displacement_m: f64,
    /// Table velocity (true, relative to the reaction mass), m/s.
    pub velocity_m_s: f64,
    /// Absolute table acceleration, m/s^2.
    pub acceleration_m_s2: f64,
    /// Actuator force A (P_a - P_b), N.
    pub force_n: f64,
}

/// The reference generator's three signals at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Reference {
    pub displacement_m: f64,
    pub velocity_m_s: f64,
    pub acceleration_m_s2: f64,
}

/// `u = clip(Kp(r-x) + Kv(r'-v) + Ka(r''-a) + Fv r' + Fa r'' - Kdp F_A, -1, 1)` (spec section 2).
#[inline]
pub fn valve_command(k: &Controller, r: &Reference, y: &Feedback) -> f64 {
    command_before_clip(k, r, y).clamp(-1.0, 1.0)
}

/// The command before its clip to [-1, 1] (the clip's edges are switching surfaces).
#[inline]
pub fn command_before_clip(k: &Controller, r: &Reference, y: &Feedback) -> f64 {
    k.kp * (r.displacement_m - y.displacement_m)
        + k.kv * (r.velocity_m_s - y.velocity_m_s)
        + k.ka * (r.acceleration_m_s2 - y.acceleration_m_s2)
        + k.fv * r.velocity_m_s
        + k.fa * r.acceleration_m_s2
        - k.kdp * y.force_n
}
