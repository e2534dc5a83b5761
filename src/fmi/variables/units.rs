//! The units the variables use: SI base-unit exponents and the display unit labs read
//! each in (UnitDefinitions and `displayUnit` in modelDescription.xml).

/// One unit of the table: its SI base-unit exponents and the display unit labs read it
/// in (`display = factor * value`), for UnitDefinitions and each variable's `displayUnit`.
#[derive(Debug, Clone, Copy)]
pub struct Unit {
    pub name: &'static str,
    /// Exponents of kg, m and s.
    pub base: (i32, i32, i32),
    /// `(name, factor)` of the display unit.
    pub display: Option<(&'static str, f64)>,
}

/// Standard gravity, m/s^2: the `g` display unit of accelerations.
const STANDARD_GRAVITY_M_S2: f64 = 9.80665;

/// Every unit the variables use.
pub const UNITS: &[Unit] = &[
    Unit {
        name: "m",
        base: (0, 1, 0),
        display: Some(("mm", 1e3)),
    },
    Unit {
        name: "m/s",
        base: (0, 1, -1),
        display: Some(("mm/s", 1e3)),
    },
    Unit {
        name: "m/s2",
        base: (0, 1, -2),
        display: Some(("g", 1.0 / STANDARD_GRAVITY_M_S2)),
    },
    Unit {
        name: "N",
        base: (1, 1, -2),
        display: Some(("kN", 1e-3)),
    },
    Unit {
        name: "Pa",
        base: (1, -1, -2),
        display: Some(("bar", 1e-5)),
    },
    Unit {
        name: "kg",
        base: (1, 0, 0),
        display: Some(("t", 1e-3)),
    },
    Unit {
        name: "N/m",
        base: (1, 0, -2),
        display: Some(("kN/mm", 1e-6)),
    },
    Unit {
        name: "m2",
        base: (0, 2, 0),
        display: Some(("cm2", 1e4)),
    },
    Unit {
        name: "m3",
        base: (0, 3, 0),
        display: Some(("l", 1e3)),
    },
    Unit {
        name: "m3/s",
        base: (0, 3, -1),
        display: Some(("l/min", 6e4)),
    },
    Unit {
        name: "m3/(s.Pa)",
        base: (-1, 4, 1),
        display: None,
    },
    Unit {
        name: "s",
        base: (0, 0, 1),
        display: Some(("ms", 1e3)),
    },
    Unit {
        name: "Hz",
        base: (0, 0, -1),
        display: None,
    },
    Unit {
        name: "1/s",
        base: (0, 0, -1),
        display: None,
    },
    Unit {
        name: "1/s2",
        base: (0, 0, -2),
        display: None,
    },
    Unit {
        name: "Pa/s",
        base: (1, -1, -3),
        display: Some(("bar/s", 1e-5)),
    },
    Unit {
        name: "1/m",
        base: (0, -1, 0),
        display: None,
    },
    Unit {
        name: "s/m",
        base: (0, -1, 1),
        display: None,
    },
    Unit {
        name: "s2/m",
        base: (0, -1, 2),
        display: None,
    },
    Unit {
        name: "1/N",
        base: (-1, -1, 2),
        display: None,
    },
];

/// The unit named `name`.
pub fn unit(name: &str) -> Option<&'static Unit> {
    UNITS.iter().find(|u| u.name == name)
}
