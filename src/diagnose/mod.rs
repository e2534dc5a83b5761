//! Diagnosis: residuals of the identified baseline, candidate effects, selection.
