//! Why an estimate could not be made. The text of each variant is what the JSON's
//! `missing` list, the CLI and the report show; every variant names the test (or the
//! role no test could take) and what was not identified.

/// An estimate that could not be made, with the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IdentifyError {
    /// No test of the campaign can take a role (`role` says which and what it needs;
    /// `screening` lists the exclusions, if any).
    #[error("no {role}{}: {consequence}", screening_note(.excluded))]
    NoTest {
        role: String,
        excluded: Vec<String>,
        consequence: String,
    },
    /// The chosen test lacks a channel its estimator needs.
    #[error("{test} has no {channel} channel: {consequence}")]
    MissingChannel {
        test: String,
        channel: &'static str,
        consequence: &'static str,
    },
    /// Too short a record for the spectral estimate.
    #[error("{test}: {seconds:.2} s of data, the {what} needs at least {min_s} s (frequency resolution and averages): not identified")]
    TooShort {
        test: String,
        seconds: f64,
        what: String,
        min_s: f64,
    },
    /// A nonlinear fit stayed at its start (it would report the start as a result).
    #[error("{test}: the {what} did not move from its start values (no information in the data): not identified")]
    DidNotMove { test: String, what: String },
    /// An estimate outside its physical bounds.
    #[error(
        "{test}: {what} = {value:.4e} is outside its physical bounds {bounds:?}: not identified"
    )]
    OutOfBounds {
        test: String,
        what: String,
        value: f64,
        bounds: [f64; 2],
    },
    /// An estimate that needs an earlier one that could not be made.
    #[error("{what} not identified: it needs {needs}")]
    NeedsUpstream { what: String, needs: String },
    /// The tests of an estimator are absent or unusable, or its fit failed, with a
    /// message that names them.
    #[error("{message}")]
    NotUsable { message: String },
    /// A spectral estimate or a fit of test `test` failed.
    #[error("{test}: {message}")]
    Failed { test: String, message: String },
    /// The error of an estimator, with the file of its test.
    #[error("{error} [file {file}]")]
    InFile {
        error: Box<IdentifyError>,
        file: String,
    },
}

fn screening_note(excluded: &[String]) -> String {
    match excluded.is_empty() {
        true => String::new(),
        false => format!(" (excluded by screening: {})", excluded.join("; ")),
    }
}

impl IdentifyError {
    /// An estimate not usable, with the message that says why.
    pub fn not_usable(message: impl std::fmt::Display) -> Self {
        IdentifyError::NotUsable {
            message: message.to_string(),
        }
    }

    /// A failure of test `test` with a message.
    pub fn failed(test: &str, message: impl std::fmt::Display) -> Self {
        IdentifyError::Failed {
            test: test.to_string(),
            message: message.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_test_the_file_and_the_screening() {
        let e = IdentifyError::InFile {
            error: Box::new(IdentifyError::OutOfBounds {
                test: "R2".into(),
                what: "mass (kg)".into(),
                value: -5.0,
                bounds: [1.0, 2e6],
            }),
            file: "R2.csv".into(),
        };
        assert_eq!(
            e.to_string(),
            "R2: mass (kg) = -5.0000e0 is outside its physical bounds [1.0, 2000000.0]: not identified [file R2.csv]"
        );
        let none = IdentifyError::NoTest {
            role: "valve test".into(),
            excluded: vec!["R1 (R1.csv): flat".into()],
            consequence: "servovalve not identified".into(),
        };
        assert_eq!(
            none.to_string(),
            "no valve test (excluded by screening: R1 (R1.csv): flat): servovalve not identified"
        );
    }
}
