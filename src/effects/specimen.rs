//! `specimen`: a flexible specimen on the table with up to three modes (spec section 7,
//! `specimen`, and its second part, "specimen with several modes"). Each mode is a
//! mass-spring-damper ([`Oscillator`]) on the table in modal form; the table feels the sum
//! of their forces. Mode 1 is the effect's own `mass_kg`, `frequency_hz`, `damping_ratio`
//! (a one-mode specimen is the `specimen` of the first catalogue part); modes 2 and 3
//! exist while their `mass_kg > 0`.
//!
//! In the parameter file the modes are the list `modes` of `{mass_kg, frequency_hz,
//! damping_ratio}`, the first entry being mode 1 (equal to the block's own keys when both
//! are given); the list is written only when there is more than one mode, so a one-mode
//! parameter file is what it always was. Everywhere else (validation messages, the FMU
//! variables `specimen.mode2.mass`, `--effect specimen:mode2.mass_kg=...`) mode `N` is
//! named `modeN`.

use super::oscillator::Oscillator;
use super::{parameter, switch, Broken, Effect, Parameter, RandomRole, SignatureTests};
use crate::campaign::Measured;
use crate::params::Params;
use crate::params::Rule::{NonNegative, Positive};
use serde::{Deserialize, Serialize};

/// Most modes a specimen has (spec section 7, second part: "up to three modes").
pub const MAX_MODES: usize = 3;

/// One mode of the specimen in modal form: its effective mass, frequency and damping.
/// A higher mode (2 or 3) with `mass_kg == 0` is absent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpecimenMode {
    pub mass_kg: f64,
    pub frequency_hz: f64,
    pub damping_ratio: f64,
}

impl SpecimenMode {
    /// An absent higher mode that, given a mass, vibrates at `frequency_hz` with the
    /// mode-1 default damping.
    const fn absent(frequency_hz: f64) -> SpecimenMode {
        SpecimenMode {
            mass_kg: 0.0,
            frequency_hz,
            damping_ratio: DEFAULT_DAMPING_RATIO,
        }
    }

    fn oscillator(&self, enabled: bool) -> Oscillator {
        Oscillator::new(
            enabled && self.mass_kg > 0.0,
            self.mass_kg,
            self.frequency_hz,
            self.damping_ratio,
        )
    }
}

/// Default damping ratio of every mode: 2 %, a typical steel or RC specimen.
const DEFAULT_DAMPING_RATIO: f64 = 0.02;
/// Default frequencies of modes 2 and 3 (absent until given a mass): three and six times
/// mode 1's 5 Hz, the spacing of a shear building's first modes.
const DEFAULT_MODE2_HZ: f64 = 15.0;
const DEFAULT_MODE3_HZ: f64 = 30.0;

/// Flexible specimen on the table (spec section 7, `specimen`): mode 1 in the block's own
/// fields, modes 2 and 3 in `mode2`, `mode3` (absent while their mass is 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SpecimenFile", into = "SpecimenFile")]
pub struct Specimen {
    pub enabled: bool,
    pub mass_kg: f64,
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub mode2: SpecimenMode,
    pub mode3: SpecimenMode,
}

impl Default for Specimen {
    fn default() -> Self {
        Specimen {
            enabled: false,
            mass_kg: 10_000.0,
            frequency_hz: 5.0,
            damping_ratio: DEFAULT_DAMPING_RATIO,
            mode2: SpecimenMode::absent(DEFAULT_MODE2_HZ),
            mode3: SpecimenMode::absent(DEFAULT_MODE3_HZ),
        }
    }
}

impl Specimen {
    /// Physics hook: mode 1's mass on spring and damper (the one-mode specimen).
    pub fn oscillator(&self) -> Oscillator {
        Oscillator::new(
            self.enabled,
            self.mass_kg,
            self.frequency_hz,
            self.damping_ratio,
        )
    }

    /// Physics hook: modes 2 and 3, each enabled while the specimen is and its mass > 0.
    pub fn higher_oscillators(&self) -> [Oscillator; MAX_MODES - 1] {
        [
            self.mode2.oscillator(self.enabled),
            self.mode3.oscillator(self.enabled),
        ]
    }

    /// Mode 1 as a [`SpecimenMode`].
    pub fn mode1(&self) -> SpecimenMode {
        SpecimenMode {
            mass_kg: self.mass_kg,
            frequency_hz: self.frequency_hz,
            damping_ratio: self.damping_ratio,
        }
    }

    /// The modes that exist, mode 1 first (1 to [`MAX_MODES`] of them).
    pub fn modes(&self) -> Vec<SpecimenMode> {
        let mut modes = vec![self.mode1()];
        modes.extend(
            [self.mode2, self.mode3]
                .into_iter()
                .filter(|m| m.mass_kg > 0.0),
        );
        modes
    }
}

/// The `[specimen]` block as the parameter file holds it: mode 1 as the block's own keys
/// and, for two or three modes, the list `modes` (spec section 7, second part).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
struct SpecimenFile {
    enabled: bool,
    mass_kg: Option<f64>,
    frequency_hz: Option<f64>,
    damping_ratio: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    modes: Option<Vec<SpecimenMode>>,
}

impl From<Specimen> for SpecimenFile {
    fn from(s: Specimen) -> SpecimenFile {
        let modes = s.modes();
        SpecimenFile {
            enabled: s.enabled,
            mass_kg: Some(s.mass_kg),
            frequency_hz: Some(s.frequency_hz),
            damping_ratio: Some(s.damping_ratio),
            modes: (modes.len() > 1).then_some(modes),
        }
    }
}

impl TryFrom<SpecimenFile> for Specimen {
    type Error = String;

    /// Mode 1 from the block's keys or the list's first entry (which must agree when both
    /// are given); a listed higher mode must have a mass (an absent one is not listed).
    fn try_from(f: SpecimenFile) -> Result<Specimen, String> {
        let d = Specimen::default();
        let mut s = Specimen {
            enabled: f.enabled,
            mass_kg: f.mass_kg.unwrap_or(d.mass_kg),
            frequency_hz: f.frequency_hz.unwrap_or(d.frequency_hz),
            damping_ratio: f.damping_ratio.unwrap_or(d.damping_ratio),
            ..d
        };
        let Some(modes) = f.modes else {
            return Ok(s);
        };
        if modes.is_empty() || modes.len() > MAX_MODES {
            return Err(format!(
                "specimen.modes lists {} modes: it must list 1 to {MAX_MODES}",
                modes.len()
            ));
        }
        let first = modes[0];
        for (key, own, listed) in [
            ("mass_kg", f.mass_kg, first.mass_kg),
            ("frequency_hz", f.frequency_hz, first.frequency_hz),
            ("damping_ratio", f.damping_ratio, first.damping_ratio),
        ] {
            if let Some(own) = own.filter(|&v| v != listed) {
                return Err(format!(
                    "specimen.{key} = {own} but the first entry of specimen.modes has \
                     {key} = {listed}: the first mode is the specimen's own values"
                ));
            }
        }
        (s.mass_kg, s.frequency_hz, s.damping_ratio) =
            (first.mass_kg, first.frequency_hz, first.damping_ratio);
        for (n, m) in modes.iter().enumerate().skip(1) {
            // NaN fails too
            if !(m.mass_kg > 0.0) {
                return Err(format!(
                    "specimen.mode{}.mass_kg = {} (entry {} of specimen.modes) must be > 0: \
                     a listed mode has a mass",
                    n + 1,
                    m.mass_kg,
                    n + 1
                ));
            }
        }
        s.mode2 = modes.get(1).copied().unwrap_or(d.mode2);
        s.mode3 = modes.get(2).copied().unwrap_or(d.mode3);
        Ok(s)
    }
}

/// Modes are numbered without gaps: mode 3 needs mode 2.
fn mode3_needs_mode2(p: &Params) -> Option<Broken> {
    let s = &p.specimen;
    (s.mode3.mass_kg > 0.0 && s.mode2.mass_kg == 0.0).then(|| Broken {
        key: "specimen.mode3.mass_kg",
        value: s.mode3.mass_kg,
        rule: "needs specimen.mode2.mass_kg > 0 (modes are numbered without gaps)".into(),
    })
}

/// Mode 1's parameters: the specimen's own.
const MODE1_PARAMETERS: [Parameter; 3] = [
    parameter!(specimen.mass_kg, fmu: "specimen.mass", vr: 141, unit: Some("kg"),
            rule: Positive, fit: (200.0, 2e5), "Specimen mass"),
    parameter!(specimen.frequency_hz, fmu: "specimen.frequency", vr: 142, unit: Some("Hz"),
            rule: Positive, fit: (0.5, 60.0), "Specimen natural frequency"),
    parameter!(specimen.damping_ratio, fmu: "specimen.damping_ratio", vr: 143, unit: None,
            rule: NonNegative, fit: (0.002, 0.5), "Specimen damping ratio"),
];

/// Mode 2's parameters (mode 1's fitting ranges: a higher mode of a building model is a
/// mode like the first).
const MODE2_PARAMETERS: [Parameter; 3] = [
    parameter!(specimen.mode2.mass_kg, fmu: "specimen.mode2.mass", vr: 144,
        unit: Some("kg"), rule: NonNegative, fit: (200.0, 2e5),
        "Specimen mode 2 effective mass (0: no mode 2)"),
    parameter!(specimen.mode2.frequency_hz, fmu: "specimen.mode2.frequency", vr: 145,
        unit: Some("Hz"), rule: Positive, fit: (0.5, 60.0),
        "Specimen mode 2 natural frequency"),
    parameter!(specimen.mode2.damping_ratio, fmu: "specimen.mode2.damping_ratio", vr: 146,
        unit: None, rule: NonNegative, fit: (0.002, 0.5), "Specimen mode 2 damping ratio"),
];

/// Mode 3's parameters (as mode 2's).
const MODE3_PARAMETERS: [Parameter; 3] = [
    parameter!(specimen.mode3.mass_kg, fmu: "specimen.mode3.mass", vr: 147,
        unit: Some("kg"), rule: NonNegative, fit: (200.0, 2e5),
        "Specimen mode 3 effective mass (0: no mode 3; needs mode 2)"),
    parameter!(specimen.mode3.frequency_hz, fmu: "specimen.mode3.frequency", vr: 148,
        unit: Some("Hz"), rule: Positive, fit: (0.5, 60.0),
        "Specimen mode 3 natural frequency"),
    parameter!(specimen.mode3.damping_ratio, fmu: "specimen.mode3.damping_ratio", vr: 149,
        unit: None, rule: NonNegative, fit: (0.002, 0.5), "Specimen mode 3 damping ratio"),
];

/// Modes 2 and 3 in the order the FMU variables and the parameter file list them.
const HIGHER_MODES: [Parameter; 6] = [
    MODE2_PARAMETERS[0],
    MODE2_PARAMETERS[1],
    MODE2_PARAMETERS[2],
    MODE3_PARAMETERS[0],
    MODE3_PARAMETERS[1],
    MODE3_PARAMETERS[2],
];

pub const EFFECT: Effect = Effect {
    name: "specimen",
    switch: switch!(specimen, fmu: "specimen.enabled", vr: 140,
        "Flexible SDOF specimen on the table"),
    parameters: &MODE1_PARAMETERS,
    // declared like the others; the diagnosis fits each as a further cause ([`MODE2`])
    unfitted: &HIGHER_MODES,
    cross_check: Some(mode3_needs_mode2),
    help: "modes 2 and 3: mode2.mass_kg=..,mode2.frequency_hz=..,mode2.damping_ratio=.. \
           (mode3 likewise); a mode exists when its mass_kg > 0, mode 3 needs mode 2",
    // the random tests under acceleration control excite its modes (R2, R3)
    signature_tests: SignatureTests {
        random: &[RandomRole::Mass, RandomRole::OilColumn],
        slow_sines: 0,
        slow_triangles: 0,
        fast_sines: 0,
    },
    no_effect: &[("mass_kg", 0.0)],
    // the displacement alone shows a heavy specimen unless the loop hides it (a 20-t one
    // at 8 Hz was named at 7.99 Hz on it); the diagnosis says how heavy one could hide
    signature_channels: &[
        &[Measured::Force],
        &[Measured::Acceleration],
        &[Measured::Displacement],
    ],
};

/// A specimen of two modes as the diagnosis fits it once one mode is a cause (issue 17
/// part 1): the same switch and signature, modes 1 and 2 fitted together, evidence when
/// each mode's mass is. Not in [`super::CATALOGUE`] (its parameters are the
/// specimen's, listed there once).
pub const TWO_MODES: Effect = Effect {
    parameters: &[
        MODE1_PARAMETERS[0],
        MODE1_PARAMETERS[1],
        MODE1_PARAMETERS[2],
        MODE2_PARAMETERS[0],
        MODE2_PARAMETERS[1],
        MODE2_PARAMETERS[2],
    ],
    unfitted: &MODE3_PARAMETERS,
    // every mode must be evidence of itself
    no_effect: &[("mass_kg", 0.0), ("mode2.mass_kg", 0.0)],
    ..EFFECT
};

/// Three modes, once two are a cause (see [`TWO_MODES`]).
pub const THREE_MODES: Effect = Effect {
    parameters: &[
        MODE1_PARAMETERS[0],
        MODE1_PARAMETERS[1],
        MODE1_PARAMETERS[2],
        MODE2_PARAMETERS[0],
        MODE2_PARAMETERS[1],
        MODE2_PARAMETERS[2],
        MODE3_PARAMETERS[0],
        MODE3_PARAMETERS[1],
        MODE3_PARAMETERS[2],
    ],
    unfitted: &[],
    no_effect: &[
        ("mass_kg", 0.0),
        ("mode2.mass_kg", 0.0),
        ("mode3.mass_kg", 0.0),
    ],
    ..EFFECT
};
