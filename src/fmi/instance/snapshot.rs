//! An instance's FMU state: the snapshot (get/set FMUstate) and its exact serialisation.

use super::*;
use crate::solver::CommandHistory;

/// Everything an FMU state snapshot holds (get/set/serialize FMUstate).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Snapshot {
    pub phase: Phase,
    pub params: Params,
    pub time_s: f64,
    pub start_time_s: f64,
    pub inputs: [f64; 4],
    pub input_slopes: [f64; 4],
    /// The simulator's state vector and command history (after initialization).
    pub state: Option<Vec<f64>>,
    pub history: Vec<(f64, f64)>,
}

impl Snapshot {
    /// Every number of a state must be finite: a NaN time or state would step on silently.
    pub fn check_finite(&self) -> std::result::Result<(), String> {
        let named: [(&str, &[f64]); 4] = [
            ("time", &[self.time_s, self.start_time_s]),
            ("input values", &self.inputs),
            ("input derivatives", &self.input_slopes),
            ("model state", self.state.as_deref().unwrap_or(&[])),
        ];
        for (what, xs) in named {
            if let Some(x) = xs.iter().find(|x| !x.is_finite()) {
                return Err(format!("the FMU state holds a non-finite {what} ({x})"));
            }
        }
        if self
            .history
            .iter()
            .any(|(t, u)| !(t.is_finite() && u.is_finite()))
        {
            return Err("the FMU state holds a non-finite valve command history".into());
        }
        Ok(())
    }
}

impl Instance {
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            phase: self.phase,
            params: self.params,
            time_s: self.time_s,
            start_time_s: self.start_time_s,
            inputs: self.inputs,
            input_slopes: self.input_slopes,
            state: self.sim.as_ref().map(|s| s.state.to_vec()),
            history: self
                .sim
                .as_ref()
                .map(|s| s.history.entries().copied().collect())
                .unwrap_or_default(),
        }
    }

    pub fn restore(&mut self, s: &Snapshot) -> Result<()> {
        const F: &str = "fmi2SetFMUstate";
        self.allowed(
            F,
            &[
                Phase::Instantiated,
                Phase::InitializationMode,
                Phase::StepComplete,
                Phase::EventMode,
                Phase::ContinuousTimeMode,
                Phase::Terminated,
                Phase::Error,
            ],
        )?;
        if let Err(e) = s.params.validate() {
            return err(
                F,
                format!("the state holds invalid parameters: {}", params_message(&e)),
            );
        }
        if let Err(why) = s.check_finite() {
            return err(F, why);
        }
        self.sim = match &s.state {
            Some(x) => {
                let mut sim =
                    Simulator::new(Model::new(&s.params), s.time_s, DEFAULT_MAX_SUBSTEP_S);
                if x.len() != sim.state.len() {
                    return err(
                        F,
                        format!(
                            "state vector of {} values, expected {}",
                            x.len(),
                            sim.state.len()
                        ),
                    );
                }
                sim.state.copy_from_slice(x);
                sim.history = CommandHistory::from_entries(s.history.clone());
                Some(sim)
            }
            None => None,
        };
        self.phase = s.phase;
        self.params = s.params;
        self.time_s = s.time_s;
        self.start_time_s = s.start_time_s;
        self.inputs = s.inputs;
        self.input_slopes = s.input_slopes;
        Ok(())
    }
}

/// Tag of a serialised FMU state.
pub const STATE_FORMAT: &str = "shaketable-fmustate";

/// Version of the serialised layout and meaning. 2: input derivatives apply to one step
/// only (version 1 states carried derivatives that kept acting, so they are refused).
pub const STATE_FORMAT_VERSION: u64 = 2;

/// Serialised FMU state: a format tag and version, then JSON with every float as its bit
/// pattern so the round trip is exact.
pub fn serialize(s: &Snapshot) -> Vec<u8> {
    let bits = |x: f64| x.to_bits();
    let v = serde_json::json!({
        "format": STATE_FORMAT,
        "version": STATE_FORMAT_VERSION,
        "writer": concat!("shaketable ", env!("CARGO_PKG_VERSION")),
        "phase": s.phase,
        "params": s.params.to_toml_string(),
        "time": bits(s.time_s),
        "start": bits(s.start_time_s),
        "inputs": s.inputs.map(bits),
        "slopes": s.input_slopes.map(bits),
        "state": s.state.as_ref().map(|x| x.iter().map(|y| y.to_bits()).collect::<Vec<u64>>()),
        "history": s.history.iter().map(|(t, u)| [t.to_bits(), u.to_bits()]).collect::<Vec<_>>(),
    });
    v.to_string().into_bytes()
}

/// The format version of a serialised state: the tag of this format (or the version-1
/// tag `shaketable-fmustate-1`), and a version equal to ours; a mismatch names both.
fn check_format(v: &serde_json::Value) -> std::result::Result<(), String> {
    let found = match v["format"].as_str() {
        Some(STATE_FORMAT) => v["version"].as_u64(),
        Some(tag) => match tag.strip_prefix("shaketable-fmustate-") {
            Some(n) => n.parse::<u64>().ok(),
            None => {
                return Err(format!(
                "not a serialized ShakeTable state (format tag {tag:?}, expected {STATE_FORMAT:?})"
            ))
            }
        },
        None => return Err("not a serialized ShakeTable state (no format tag)".into()),
    };
    let writer = v["writer"].as_str().unwrap_or("an earlier shaketable");
    match found {
        Some(STATE_FORMAT_VERSION) => Ok(()),
        Some(n) => Err(format!(
            "serialized state format version {n} (written by {writer}), this FMU reads version \
             {STATE_FORMAT_VERSION} (shaketable {}): save the state again with this FMU",
            env!("CARGO_PKG_VERSION")
        )),
        None => Err(format!(
            "serialized state has no valid format version (expected {STATE_FORMAT_VERSION})"
        )),
    }
}

pub fn deserialize(bytes: &[u8]) -> std::result::Result<Snapshot, String> {
    let v: serde_json::Value = serde_json::from_slice(bytes)
        .map_err(|e| format!("not a serialized ShakeTable state: {e}"))?;
    check_format(&v)?;
    let f = |x: &serde_json::Value| -> std::result::Result<f64, String> {
        x.as_u64()
            .map(f64::from_bits)
            .ok_or_else(|| format!("bad number {x}"))
    };
    let arr4 = |x: &serde_json::Value| -> std::result::Result<[f64; 4], String> {
        let a = x.as_array().filter(|a| a.len() == 4).ok_or("bad array")?;
        Ok([f(&a[0])?, f(&a[1])?, f(&a[2])?, f(&a[3])?])
    };
    let params = Params::from_toml_str(
        v["params"].as_str().ok_or("missing params")?,
        "<serialized state>",
    )
    .map_err(|e| params_message(&e))?;
    let state = match &v["state"] {
        serde_json::Value::Null => None,
        x => Some(
            x.as_array()
                .ok_or("bad state")?
                .iter()
                .map(f)
                .collect::<std::result::Result<Vec<f64>, String>>()?,
        ),
    };
    let history = v["history"]
        .as_array()
        .ok_or("bad history")?
        .iter()
        .map(|p| -> std::result::Result<(f64, f64), String> {
            let a = p
                .as_array()
                .filter(|a| a.len() == 2)
                .ok_or("bad history entry")?;
            Ok((f(&a[0])?, f(&a[1])?))
        })
        .collect::<std::result::Result<Vec<_>, String>>()?;
    let snap = Snapshot {
        phase: serde_json::from_value(v["phase"].clone()).map_err(|e| e.to_string())?,
        params,
        time_s: f(&v["time"])?,
        start_time_s: f(&v["start"])?,
        inputs: arr4(&v["inputs"])?,
        input_slopes: arr4(&v["slopes"])?,
        state,
        history,
    };
    snap.check_finite()?;
    Ok(snap)
}

#[cfg(test)]
mod tests {
    use super::super::tests::running;
    use super::*;

    #[test]
    fn snapshot_serialization_round_trips_bit_for_bit() {
        let mut i = running();
        i.set("fmi2SetReal", Kind::Real, &[0, 1], &[0.001, 0.01])
            .unwrap();
        for k in 0..50 {
            i.do_step(k as f64 / 512.0, 1.0 / 512.0).unwrap();
        }
        let s = i.snapshot();
        let back = deserialize(&serialize(&s)).unwrap();
        assert_eq!(back, s);
    }
}
