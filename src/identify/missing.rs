//! What an identification could not estimate, and why: one [`Missing`] per estimate left
//! out, naming the estimate and carrying its [`IdentifyError`]. The JSON's `missing` list,
//! the CLI and the report show each as the error's text.

use super::error::IdentifyError;
use serde::{Serialize, Serializer};
use std::borrow::Borrow;
use std::fmt;
use std::ops::Deref;

/// An estimate of [`super::Identification`] that can be missing: one per step of the
/// section-4 chain ([`super::identify_screened_with`]), named after the field that holds
/// it when it was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Estimation {
    /// The servovalve (4.1.1): [`super::Identification::servovalve`].
    Servovalve,
    /// The apparent mass of a random test (4.1.2): [`super::Identification::mass_random`].
    MassRandom,
    /// Stiffness and sliding friction (4.2.1): [`super::Identification::triangles`].
    Triangles,
    /// Bouc-Wen friction (4.2.3): [`super::Identification::friction`].
    Friction,
    /// The loop approach's mass (4.2.2): [`super::Identification::mass_periodic`].
    MassPeriodic,
    /// The final mass: [`super::Identification::mass_kg`].
    Mass,
    /// The oil column (4.1.3): [`super::Identification::oil_column`].
    OilColumn,
    /// The table TF's validation (section 5): [`super::Identification::validation`].
    Validation,
    /// The device force: [`super::Identification::device`].
    Device,
    /// The grey-box fit of the closed loop: [`super::Identification::closed_loop`].
    ClosedLoop,
}

/// One estimate that could not be made, and why. It reads as its reason's text (what
/// the JSON, the CLI and the report show), so the text is rendered once, when made.
#[derive(Debug, Clone, PartialEq)]
pub struct Missing {
    estimation: Estimation,
    reason: IdentifyError,
    text: String,
}

impl Missing {
    /// `estimation` not made, for `reason`.
    pub fn new(estimation: Estimation, reason: IdentifyError) -> Missing {
        let text = reason.to_string();
        Missing {
            estimation,
            reason,
            text,
        }
    }

    /// The estimate that could not be made.
    pub fn estimation(&self) -> Estimation {
        self.estimation
    }

    /// Why it could not be made.
    pub fn reason(&self) -> &IdentifyError {
        &self.reason
    }
}

impl fmt::Display for Missing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// The reason's text: what callers search and join ([`Missing`] reads as it).
impl Deref for Missing {
    type Target = str;
    fn deref(&self) -> &str {
        &self.text
    }
}

impl Borrow<str> for Missing {
    fn borrow(&self) -> &str {
        &self.text
    }
}

/// The JSON holds the reason's text, as it did when `missing` was a list of strings.
impl Serialize for Missing {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_estimate_reads_serialises_and_joins_as_its_reason() {
        let reason = IdentifyError::NeedsUpstream {
            what: "oil column".into(),
            needs: "the identified mass".into(),
        };
        let m = Missing::new(Estimation::OilColumn, reason.clone());
        let text = "oil column not identified: it needs the identified mass";
        assert_eq!(m.to_string(), text);
        assert_eq!(m.reason(), &reason);
        assert_eq!(m.estimation(), Estimation::OilColumn);
        assert_eq!(serde_json::to_string(&m).unwrap(), format!("\"{text}\""));
        assert_eq!([m.clone(), m].join("; "), format!("{text}; {text}"));
    }
}
