//! A specimen with several modes (spec section 7, second part) as one candidate: its
//! modes kept in ascending frequency, mode 1 the lowest (the parameter file's order, a
//! building model's numbering), and written as the parameter file writes them.

use super::effect::Effect;
use super::effect_values::EffectValues;
use super::output::Candidate;
use crate::effects::specimen::SpecimenMode;
use std::collections::BTreeMap;

/// The key prefixes of modes 1 to 3 in a candidate's parameters (`mass_kg`,
/// `mode2.mass_kg`, `mode3.mass_kg`: the catalogue's keys).
const PREFIXES: [&str; 3] = ["", "mode2.", "mode3."];

/// Modes closer than this factor in frequency are one mode split in two (two oscillators
/// at one frequency act as one of their summed mass), and a further mode's start keeps
/// this far from the modes fitted so far: their fit's error peaks within a few half-power
/// widths of them (10 % at 3 % damping).
pub(super) const MODE_SEPARATION: f64 = 1.1;

/// Whether `f_hz` lies at least [`MODE_SEPARATION`] from each of `modes_hz`.
pub(super) fn apart(f_hz: f64, modes_hz: &[f64]) -> bool {
    modes_hz
        .iter()
        .all(|m| (f_hz / m).ln().abs() >= MODE_SEPARATION.ln())
}

/// Whether the specimen's modes in `p` lie at least [`MODE_SEPARATION`] apart.
pub(super) fn modes_apart(p: &crate::params::Params) -> bool {
    let f: Vec<f64> = p.specimen.modes().iter().map(|m| m.frequency_hz).collect();
    (0..f.len()).all(|i| apart(f[i], &f[i + 1..]))
}

/// The three fields of a mode, in [`SpecimenMode`]'s order.
const FIELDS: [&str; 3] = ["mass_kg", "frequency_hz", "damping_ratio"];

/// The values of the specimen `effect` whose modes are `modes` (mode 1 first, one per
/// mode of the effect).
pub(super) fn specimen_values(effect: Effect, modes: &[SpecimenMode]) -> EffectValues {
    let pairs: Vec<(String, f64)> = PREFIXES
        .iter()
        .zip(modes)
        .flat_map(|(prefix, m)| {
            FIELDS
                .iter()
                .zip([m.mass_kg, m.frequency_hz, m.damping_ratio])
                .map(move |(field, v)| (format!("{prefix}{field}"), v))
        })
        .collect();
    let pairs: Vec<(&str, f64)> = pairs.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    EffectValues::new(effect, &pairs)
}

/// The modes of `c` (a specimen candidate) in ascending frequency: its model's specimen
/// and its parameters' and sigmas' keys renumbered alike.
pub(super) fn sort_modes(c: &mut Candidate) {
    let field_of = |map: &BTreeMap<String, f64>, prefix: &str, field: &str| {
        map.get(&format!("{prefix}{field}")).copied()
    };
    let mut modes: Vec<([f64; 3], [Option<f64>; 3])> = PREFIXES
        .iter()
        .filter_map(|prefix| {
            let values = FIELDS.map(|f| field_of(&c.parameters, prefix, f));
            let sigma = FIELDS.map(|f| field_of(&c.sigma, prefix, f));
            match values {
                [Some(m), Some(f), Some(z)] => Some(([m, f, z], sigma)),
                _ => None,
            }
        })
        .collect();
    modes.sort_by(|a, b| a.0[1].total_cmp(&b.0[1]));
    for (prefix, (values, sigma)) in PREFIXES.iter().zip(&modes) {
        for (k, field) in FIELDS.iter().enumerate() {
            let key = format!("{prefix}{field}");
            c.parameters.insert(key.clone(), values[k]);
            match sigma[k] {
                Some(s) => c.sigma.insert(key, s),
                None => c.sigma.remove(&key),
            };
        }
    }
    let mode = |v: &[f64; 3]| SpecimenMode {
        mass_kg: v[0],
        frequency_hz: v[1],
        damping_ratio: v[2],
    };
    let s = &mut c.params.specimen;
    if let Some((first, _)) = modes.first() {
        (s.mass_kg, s.frequency_hz, s.damping_ratio) = (first[0], first[1], first[2]);
    }
    if let Some((second, _)) = modes.get(1) {
        s.mode2 = mode(second);
    }
    if let Some((third, _)) = modes.get(2) {
        s.mode3 = mode(third);
    }
}

/// The parameters of a specimen cause as the parameter file writes its block: mode 1's
/// keys, and for two or three modes the list `modes` of `{mass_kg, frequency_hz,
/// damping_ratio}` in ascending frequency (mode 1 first); any other effect's as they are.
pub fn parameters_json(effect: Effect, parameters: &BTreeMap<String, f64>) -> serde_json::Value {
    let modes: Vec<serde_json::Value> = PREFIXES
        .iter()
        .map_while(|prefix| {
            let fields: Option<Vec<(&str, f64)>> = FIELDS
                .iter()
                .map(|f| Some((*f, *parameters.get(&format!("{prefix}{f}"))?)))
                .collect();
            fields.map(|f| serde_json::json!(f.into_iter().collect::<BTreeMap<_, _>>()))
        })
        .collect();
    if effect.specimen_modes().is_none() || modes.len() < 2 {
        return serde_json::json!(parameters);
    }
    let mut object: serde_json::Map<String, serde_json::Value> = FIELDS
        .iter()
        .filter_map(|f| Some((f.to_string(), serde_json::json!(parameters.get(*f)?))))
        .collect();
    object.insert("modes".into(), serde_json::Value::Array(modes));
    serde_json::Value::Object(object)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn candidate(effect: Effect, keyed: &[(&str, f64)]) -> Candidate {
        let mut c = Candidate::empty(effect);
        for (k, v) in keyed {
            c.parameters.insert(k.to_string(), *v);
            c.sigma.insert(k.to_string(), v * 0.01);
        }
        c
    }

    /// A mode found below the first becomes mode 1: the model, the keys and the sigmas
    /// move together, and the JSON lists both modes, lowest first.
    #[test]
    fn a_lower_mode_found_second_becomes_mode_one() {
        let mut c = candidate(
            Effect::specimen(2).unwrap(),
            &[
                ("mass_kg", 6e3),
                ("frequency_hz", 13.5),
                ("damping_ratio", 0.02),
                ("mode2.mass_kg", 15e3),
                ("mode2.frequency_hz", 4.2),
                ("mode2.damping_ratio", 0.03),
            ],
        );
        sort_modes(&mut c);
        assert_eq!(c.parameters["frequency_hz"], 4.2);
        assert_eq!(c.parameters["mode2.frequency_hz"], 13.5);
        assert_eq!(c.sigma["mass_kg"], 150.0);
        assert_eq!(c.params.specimen.frequency_hz, 4.2);
        assert_eq!(c.params.specimen.mode2.mass_kg, 6e3);
        let v = parameters_json(c.effect, &c.parameters);
        assert_eq!(v["frequency_hz"], 4.2);
        assert_eq!(v["modes"][1]["frequency_hz"], 13.5);
        assert_eq!(v["modes"].as_array().unwrap().len(), 2);
    }

    /// Two modes 5 % apart are one mode split in two; 3 times apart, two modes.
    #[test]
    fn modes_closer_than_the_separation_are_one() {
        let mut p = crate::params::Params::trees_lab();
        p.apply_effect_spec(
            "specimen:mass_kg=1e4,frequency_hz=9.8,mode2.mass_kg=1e4,mode2.frequency_hz=10.29",
        )
        .unwrap();
        assert!(!modes_apart(&p));
        p.specimen.mode2.frequency_hz = 29.4;
        assert!(modes_apart(&p));
    }

    /// A one-mode specimen's parameters are written as they always were.
    #[test]
    fn one_mode_keeps_its_flat_parameters() {
        let one = candidate(
            Effect::of(&crate::effects::specimen::EFFECT),
            &[
                ("mass_kg", 6e3),
                ("frequency_hz", 13.5),
                ("damping_ratio", 0.02),
            ],
        );
        let v = parameters_json(one.effect, &one.parameters);
        assert_eq!(v, serde_json::json!(one.parameters));
    }
}
