//! The catalogue of effects (spec section 7): each effect is one file here, and
//! everything that lists effects reads [`CATALOGUE`].
//!
//! # Adding an effect
//! 1. Write one file like [`valve_deadband`] (the smallest): its parameter struct (with
//!    `enabled` and serde defaults), a `pub const EFFECT: Effect` declaring its FMU switch
//!    and each parameter once with [`parameter!`] (TOML key, unit, description, FMU name
//!    and value reference, validation rule, diagnosis fitting range), the test kinds and
//!    channels where its signature lives, its no-effect values, and its physics hook: the
//!    small functions the model calls.
//! 2. Add the file to the `mod` list and its `EFFECT` to [`CATALOGUE`], and the struct as a
//!    field of [`crate::params::Params`] (its TOML block, named like the effect).
//! 3. Call the physics hook from `src/model/` (the block it acts in: `actuator.rs`,
//!    `friction.rs`, `payload.rs`, ...). An effect with states of its own (an oscillator,
//!    the free play's rod) also lists them in `src/fmi/variables/states.rs` and, where the
//!    linearisation applies, in `src/linear/` (`plant.rs`, `jacobian.rs`).
//! 4. For the diagnosis: one row in the table of `src/diagnose/effect_table.rs` (the
//!    diagnosis reads the effect's catalogue entry through it): its starts (a grid built
//!    by parameter key with `EffectValues`, helpers in `src/diagnose/starts.rs`), its start
//!    read off the data where one can be, which fit it takes (output error, or on the
//!    predictive score for an effect without a reproducible phase), and the resonance
//!    frequency whose starts lie in different valleys, if any, and what its starts take
//!    out of the identified baseline (a specimen's mass, a foundation's spring). The
//!    search fits the effects in the catalogue's order; the table's unit test checks
//!    that it covers the catalogue exactly.
//! 5. Tests: the catalogue tests below check that every parameter appears once in the
//!    parameter file, in the FMU variables and in `--effect` parsing, with unique names
//!    and value references; add a physics test of the effect in `tests/physics.rs` and a
//!    seeded draw to `tests/diagnose_hidden.rs`.
//!
//! The parameter validation, `numeric_entries`, the `--effect name:key=value` syntax and
//! its help, the FMU variable rows (`src/fmi/variables/table.rs`), campaign synthesis, the
//! diagnosis' parameters, fitting bounds (scaled to the table), evidence rule,
//! testability and JSON names read the catalogue; nothing else needs an edit.

pub mod flow_asymmetry;
pub mod flow_saturation;
pub mod foundation;
pub mod free_play;
pub mod friction_asymmetry;
pub mod oscillator;
pub mod specimen;
pub mod stick_slip;
pub mod valve_deadband;

use crate::campaign::Measured;
pub use crate::identify::select::RandomRole;
use crate::params::{Params, Rule};

/// Range a diagnosis fit may move one effect parameter in (`lower <= x <= upper`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitRange {
    pub lower: f64,
    pub upper: f64,
}

/// One numeric parameter of an effect, declared once.
#[derive(Clone, Copy)]
pub struct Parameter {
    /// Key inside the effect's TOML block (and in `--effect name:key=value`).
    pub key: &'static str,
    /// Dotted TOML key `effect.key`, as validation errors and reports name it.
    pub dotted_key: &'static str,
    /// FMU variable name.
    pub fmu_name: &'static str,
    /// FMU value reference.
    pub value_reference: u32,
    /// FMU unit, `None` when dimensionless.
    pub unit: Option<&'static str>,
    /// FMU description.
    pub description: &'static str,
    /// Validation rule, checked while the effect is enabled.
    pub rule: Rule,
    /// Fixed fitting range of the diagnosis (see [`Effect::fit_bounds`]).
    pub fit_range: FitRange,
    pub read: fn(&Params) -> f64,
    pub write: fn(&mut Params, f64),
}

/// The `enabled` switch of an effect as an FMU Boolean variable (value 1 or 0).
#[derive(Clone, Copy)]
pub struct Switch {
    /// Dotted TOML key `effect.enabled`.
    pub dotted_key: &'static str,
    pub fmu_name: &'static str,
    pub value_reference: u32,
    pub description: &'static str,
    pub read: fn(&Params) -> f64,
    pub write: fn(&mut Params, f64),
}

/// One catalogue effect: its switch, parameters and diagnosis metadata.
#[derive(Clone, Copy)]
pub struct Effect {
    /// Name: the TOML block, the `--effect` name and the FMU variable prefix.
    pub name: &'static str,
    pub switch: Switch,
    pub parameters: &'static [Parameter],
    /// Parameters declared like [`Effect::parameters`] (parameter file, validation, FMU,
    /// `--effect`) that the diagnosis does not fit with the effect itself: the free play's
    /// contact stiffness, and the `specimen`'s modes 2 and 3 (each fitted as a further
    /// cause once the mode before it is one: [`specimen::TWO_MODES`]).
    pub unfitted: &'static [Parameter],
    /// A rule across parameters, checked while the effect is enabled after each
    /// parameter's own rule (the `free_play` rod lighter than the table, say).
    pub cross_check: Option<fn(&Params) -> Option<Broken>>,
    /// More `--effect` syntax for the help, after the parameter list; empty when none.
    pub help: &'static str,
    /// The tests where the effect's signature lives, by what they excite: its candidate
    /// is fitted on them (every test when a campaign has none of them).
    pub signature_tests: SignatureTests,
    /// The parameters whose value makes the effect vanish, with that value (a specimen of
    /// no mass, a static ratio of 1): a fitted cause is evidence only when its uncertainty
    /// excludes them (issue 17 part 3). Empty when the effect vanishes only at a limit
    /// (a foundation infinitely stiff, a flow limit above any demand): then the rule that
    /// no parameter sits at a bound of its fitting range guards it.
    pub no_effect: &'static [(&'static str, f64)],
    /// The recorded channels its signature needs, as alternatives: the effect can be
    /// tested when every channel of at least one alternative is recorded; otherwise the
    /// diagnosis reports it as not testable, never as absent (issue 16 part 5).
    pub signature_channels: &'static [&'static [Measured]],
}

/// The tests of a campaign where an effect's signature lives, by what they excite and
/// never by name (a laboratory names its tests as it likes): random tests by their role in
/// section 4, and periodic tests by their declared peak velocity
/// ([`crate::identify::select::slowest_first`]). Each effect notes the paper's tests its
/// description picks.
#[derive(Debug, Clone, Copy)]
pub struct SignatureTests {
    /// The random tests taking these roles.
    pub random: &'static [RandomRole],
    /// This many of the friction-dominated sines
    /// ([`crate::identify::select::sine_split`]), slowest first; [`EVERY`] for all.
    pub slow_sines: usize,
    /// This many triangles, slowest first.
    pub slow_triangles: usize,
    /// This many of the inertia-dominated sines, fastest first.
    pub fast_sines: usize,
}

/// Every test of a kind ([`SignatureTests`]).
pub const EVERY: usize = usize::MAX;

/// A rule across parameters that `p` breaks: the key to name, its value, the rule in words.
#[derive(Debug, Clone, PartialEq)]
pub struct Broken {
    pub key: &'static str,
    pub value: f64,
    pub rule: String,
}

/// Declares one [`Parameter`] of the block `$block.$field` (see the effect files), or of
/// a sub-block `$block.$sub.$field` (key `$sub.$field`: the `specimen`'s `mode2.mass_kg`).
macro_rules! parameter {
    ($block:ident . $sub:ident . $field:ident, fmu: $fmu:literal, vr: $vr:literal,
     unit: $unit:expr, rule: $rule:expr, fit: ($lower:expr, $upper:expr), $description:literal) => {
        $crate::effects::Parameter {
            key: concat!(stringify!($sub), ".", stringify!($field)),
            dotted_key: concat!(
                stringify!($block),
                ".",
                stringify!($sub),
                ".",
                stringify!($field)
            ),
            fmu_name: $fmu,
            value_reference: $vr,
            unit: $unit,
            description: $description,
            rule: $rule,
            fit_range: $crate::effects::FitRange {
                lower: $lower,
                upper: $upper,
            },
            read: |p| p.$block.$sub.$field,
            write: |p, v| p.$block.$sub.$field = v,
        }
    };
    ($block:ident . $field:ident, fmu: $fmu:literal, vr: $vr:literal, unit: $unit:expr,
     rule: $rule:expr, fit: ($lower:expr, $upper:expr), $description:literal) => {
        $crate::effects::Parameter {
            key: stringify!($field),
            dotted_key: concat!(stringify!($block), ".", stringify!($field)),
            fmu_name: $fmu,
            value_reference: $vr,
            unit: $unit,
            description: $description,
            rule: $rule,
            fit_range: $crate::effects::FitRange {
                lower: $lower,
                upper: $upper,
            },
            read: |p| p.$block.$field,
            write: |p, v| p.$block.$field = v,
        }
    };
}
pub(crate) use parameter;

/// Declares the [`Switch`] of the block `$block` (its `enabled` field).
macro_rules! switch {
    ($block:ident, fmu: $fmu:literal, vr: $vr:literal, $description:literal) => {
        $crate::effects::Switch {
            dotted_key: concat!(stringify!($block), ".enabled"),
            fmu_name: $fmu,
            value_reference: $vr,
            description: $description,
            read: |p| if p.$block.enabled { 1.0 } else { 0.0 },
            write: |p, v| p.$block.enabled = v != 0.0,
        }
    };
}
pub(crate) use switch;

/// Every effect, in catalogue order (spec section 7): the order of the parameter file,
/// the FMU variables, validation and diagnosis.
pub const CATALOGUE: [Effect; 8] = [
    specimen::EFFECT,
    foundation::EFFECT,
    stick_slip::EFFECT,
    flow_saturation::EFFECT,
    valve_deadband::EFFECT,
    friction_asymmetry::EFFECT,
    flow_asymmetry::EFFECT,
    free_play::EFFECT,
];

/// The effect named `name`.
pub fn by_name(name: &str) -> Option<&'static Effect> {
    CATALOGUE.iter().find(|e| e.name == name)
}

/// The effects and their parameters for the `--effect` help: one line per effect,
/// `name: key (unit, default value), ...`.
pub fn effect_syntax_help() -> String {
    let defaults = Params::trees_lab();
    let lines: Vec<String> = CATALOGUE
        .iter()
        .map(|e| {
            let keys: Vec<String> = e
                .all_parameters()
                .map(|q| {
                    let unit = q.unit.map(|u| format!("{u}, ")).unwrap_or_default();
                    format!("{} ({unit}default {})", q.key, (q.read)(&defaults))
                })
                .collect();
            let line = format!("  {}: {}", e.name, keys.join(", "));
            if e.help.is_empty() {
                line
            } else {
                format!("{line}\n    {}", e.help)
            }
        })
        .collect();
    lines.join("\n")
}

impl Effect {
    /// Whether the effect is switched on in `p`.
    pub fn is_enabled(&self, p: &Params) -> bool {
        (self.switch.read)(p) != 0.0
    }

    /// Switch the effect on or off in `p`.
    pub fn set_enabled(&self, p: &mut Params, on: bool) {
        (self.switch.write)(p, if on { 1.0 } else { 0.0 })
    }

    /// Every parameter: the fitted ones ([`Effect::parameters`]), then [`Effect::unfitted`].
    pub fn all_parameters(&self) -> impl Iterator<Item = &'static Parameter> {
        self.parameters.iter().chain(self.unfitted.iter())
    }

    /// The parameter with TOML key `key`.
    pub fn parameter(&self, key: &str) -> Option<&'static Parameter> {
        self.all_parameters().find(|q| q.key == key)
    }

    /// The parameter `key` in `p`; `None` when the effect has no such parameter.
    pub fn read(&self, p: &Params, key: &str) -> Option<f64> {
        self.parameter(key).map(|q| (q.read)(p))
    }

    /// Set the parameter `key` in `p`; `false` when the effect has no such parameter.
    pub fn apply(&self, p: &mut Params, key: &str, value: f64) -> bool {
        match self.parameter(key) {
            Some(q) => {
                (q.write)(p, value);
                true
            }
            None => false,
        }
    }

    /// Fitting bounds of the diagnosis, one per parameter in declaration order: the
    /// declared ranges (set for the 41-t TREES Lab table) scaled to `table` by what
    /// the parameter's unit measures: masses by the table's mass, flows by its flow gain,
    /// stiffnesses by its oil column's. A 6-t table's specimen range then ends at 30 t,
    /// not at 200 t, and a wrong effect cannot wander to masses no such table carries
    /// (issue 17 part 6). Frequencies, ratios and lengths are the table's own physics
    /// and keep their ranges.
    pub fn fit_bounds(&self, table: &Params) -> Vec<FitRange> {
        let reference = Params::trees_lab();
        let ratio = |now: f64, then: f64| {
            let r = now / then;
            if r.is_finite() && r > 0.0 {
                r
            } else {
                1.0
            }
        };
        let scale = |unit: Option<&str>| match unit {
            Some("kg") => ratio(table.table.mass_kg, reference.table.mass_kg),
            Some("m3/s") => ratio(
                table.actuator.flow_gain_m3_s,
                reference.actuator.flow_gain_m3_s,
            ),
            Some("N/m") => ratio(
                table.actuator.oil_column_stiffness_n_m(),
                reference.actuator.oil_column_stiffness_n_m(),
            ),
            _ => 1.0,
        };
        self.parameters
            .iter()
            .map(|q| {
                let k = scale(q.unit);
                FitRange {
                    lower: q.fit_range.lower * k,
                    upper: q.fit_range.upper * k,
                }
            })
            .collect()
    }

    /// Switch the effect on in `p` and set its parameters from `key=value` pairs: the
    /// `--effect specimen:mass_kg=20000,frequency_hz=6` syntax after the colon.
    /// The result is not validated here ([`Params::apply_effect_spec`] does).
    /// A key `modeN.key` names mode N of a multi-mode effect (`specimen`): that mode exists
    /// only with `modeN.mass_kg > 0`, so naming it without a mass is an error.
    pub fn apply_pairs(&self, p: &mut Params, pairs: &str, spec: &str) -> Result<(), String> {
        self.set_enabled(p, true);
        let mut modes_named: Vec<&str> = Vec::new();
        for pair in pairs.split(',').filter(|s| !s.trim().is_empty()) {
            let (k, v) = pair
                .split_once('=')
                .ok_or_else(|| format!("`{pair}` in `{spec}` is not key=value"))?;
            let k = k.trim();
            let name = self.name;
            let Some(q) = self.parameter(k) else {
                // sorted, as the message has always listed them
                let mut known: Vec<&str> = self.all_parameters().map(|q| q.key).collect();
                known.sort_unstable();
                return Err(format!(
                    "effect `{name}` has no parameter `{k}`; it has {known:?}"
                ));
            };
            let v: f64 = v
                .trim()
                .parse()
                .map_err(|_| format!("`{name}.{k}` = `{v}` is not a number"))?;
            (q.write)(p, v);
            if let Some((mode, _)) = q.key.split_once('.') {
                modes_named.push(mode);
            }
        }
        for mode in modes_named {
            let mass_key = format!("{mode}.mass_kg");
            if self.read(p, &mass_key) == Some(0.0) {
                return Err(format!(
                    "`{spec}` sets `{}.{mode}` keys but `{}.{mass_key}` is 0: a mode exists \
                     only with a mass > 0 (add `{mass_key}=...`)",
                    self.name, self.name
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
