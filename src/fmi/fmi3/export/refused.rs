//! The functions this Co-Simulation FMU does not offer (other types, clocks, event mode,
//! Model Exchange, derivatives), each exported with its exact signature and refused.

#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use super::*;
use fmi_sys::fmi3::*;

/// Functions this FMU does not offer, each with its exact signature (checked against
/// the `fmi-sys` type): logged and refused with fmi3Error.
macro_rules! not_offered {
    ($($name:ident, $ty:ident ( $($arg:ident : $t:ty),* );)*) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $name(instance: fmi3Instance, $($arg: $t),*) -> fmi3Status {
            $(let _ = $arg;)*
            unsafe { refuse(instance, stringify!($name), CO_SIMULATION_ONLY) }
        }
        const _: $ty = Some($name);
    )*};
}

not_offered! {
    fmi3GetFloat32, fmi3GetFloat32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Float32, nValues: usize);
    fmi3GetInt8, fmi3GetInt8TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Int8, nValues: usize);
    fmi3GetUInt8, fmi3GetUInt8TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3UInt8, nValues: usize);
    fmi3GetInt16, fmi3GetInt16TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Int16, nValues: usize);
    fmi3GetUInt16, fmi3GetUInt16TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3UInt16, nValues: usize);
    fmi3GetInt32, fmi3GetInt32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Int32, nValues: usize);
    fmi3GetUInt32, fmi3GetUInt32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3UInt32, nValues: usize);
    fmi3GetUInt64, fmi3GetUInt64TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3UInt64, nValues: usize);
    fmi3GetString, fmi3GetStringTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3String, nValues: usize);
    fmi3GetBinary, fmi3GetBinaryTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, valueSizes: *mut usize, values: *mut fmi3Binary, nValues: usize);
    fmi3GetClock, fmi3GetClockTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *mut fmi3Clock);
    fmi3SetFloat32, fmi3SetFloat32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Float32, nValues: usize);
    fmi3SetInt8, fmi3SetInt8TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Int8, nValues: usize);
    fmi3SetUInt8, fmi3SetUInt8TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3UInt8, nValues: usize);
    fmi3SetInt16, fmi3SetInt16TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Int16, nValues: usize);
    fmi3SetUInt16, fmi3SetUInt16TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3UInt16, nValues: usize);
    fmi3SetInt32, fmi3SetInt32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Int32, nValues: usize);
    fmi3SetUInt32, fmi3SetUInt32TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3UInt32, nValues: usize);
    fmi3SetUInt64, fmi3SetUInt64TYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3UInt64, nValues: usize);
    fmi3SetString, fmi3SetStringTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3String, nValues: usize);
    fmi3SetBinary, fmi3SetBinaryTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, valueSizes: *const usize, values: *const fmi3Binary, nValues: usize);
    fmi3SetClock, fmi3SetClockTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, values: *const fmi3Clock);
    fmi3GetNumberOfVariableDependencies, fmi3GetNumberOfVariableDependenciesTYPE (valueReference: fmi3ValueReference, nDependencies: *mut usize);
    fmi3GetVariableDependencies, fmi3GetVariableDependenciesTYPE (dependent: fmi3ValueReference, elementIndicesOfDependent: *mut usize, independents: *mut fmi3ValueReference, elementIndicesOfIndependents: *mut usize, dependencyKinds: *mut fmi3DependencyKind, nDependencies: usize);
    fmi3GetDirectionalDerivative, fmi3GetDirectionalDerivativeTYPE (unknowns: *const fmi3ValueReference, nUnknowns: usize, knowns: *const fmi3ValueReference, nKnowns: usize, seed: *const fmi3Float64, nSeed: usize, sensitivity: *mut fmi3Float64, nSensitivity: usize);
    fmi3GetAdjointDerivative, fmi3GetAdjointDerivativeTYPE (unknowns: *const fmi3ValueReference, nUnknowns: usize, knowns: *const fmi3ValueReference, nKnowns: usize, seed: *const fmi3Float64, nSeed: usize, sensitivity: *mut fmi3Float64, nSensitivity: usize);
    fmi3EnterConfigurationMode, fmi3EnterConfigurationModeTYPE ();
    fmi3ExitConfigurationMode, fmi3ExitConfigurationModeTYPE ();
    fmi3GetIntervalDecimal, fmi3GetIntervalDecimalTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, intervals: *mut fmi3Float64, qualifiers: *mut fmi3IntervalQualifier);
    fmi3GetIntervalFraction, fmi3GetIntervalFractionTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64, qualifiers: *mut fmi3IntervalQualifier);
    fmi3GetShiftDecimal, fmi3GetShiftDecimalTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, shifts: *mut fmi3Float64);
    fmi3GetShiftFraction, fmi3GetShiftFractionTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64);
    fmi3SetIntervalDecimal, fmi3SetIntervalDecimalTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, intervals: *const fmi3Float64);
    fmi3SetIntervalFraction, fmi3SetIntervalFractionTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64);
    fmi3SetShiftDecimal, fmi3SetShiftDecimalTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, shifts: *const fmi3Float64);
    fmi3SetShiftFraction, fmi3SetShiftFractionTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64);
    fmi3EvaluateDiscreteStates, fmi3EvaluateDiscreteStatesTYPE ();
    fmi3UpdateDiscreteStates, fmi3UpdateDiscreteStatesTYPE (discreteStatesNeedUpdate: *mut fmi3Boolean, terminateSimulation: *mut fmi3Boolean, nominalsOfContinuousStatesChanged: *mut fmi3Boolean, valuesOfContinuousStatesChanged: *mut fmi3Boolean, nextEventTimeDefined: *mut fmi3Boolean, nextEventTime: *mut fmi3Float64);
    fmi3EnterEventMode, fmi3EnterEventModeTYPE ();
    fmi3EnterContinuousTimeMode, fmi3EnterContinuousTimeModeTYPE ();
    fmi3CompletedIntegratorStep, fmi3CompletedIntegratorStepTYPE (noSetFMUStatePriorToCurrentPoint: fmi3Boolean, enterEventMode: *mut fmi3Boolean, terminateSimulation: *mut fmi3Boolean);
    fmi3SetTime, fmi3SetTimeTYPE (time: fmi3Float64);
    fmi3SetContinuousStates, fmi3SetContinuousStatesTYPE (continuousStates: *const fmi3Float64, nContinuousStates: usize);
    fmi3GetContinuousStateDerivatives, fmi3GetContinuousStateDerivativesTYPE (derivatives: *mut fmi3Float64, nContinuousStates: usize);
    fmi3GetEventIndicators, fmi3GetEventIndicatorsTYPE (eventIndicators: *mut fmi3Float64, nEventIndicators: usize);
    fmi3GetContinuousStates, fmi3GetContinuousStatesTYPE (continuousStates: *mut fmi3Float64, nContinuousStates: usize);
    fmi3GetNominalsOfContinuousStates, fmi3GetNominalsOfContinuousStatesTYPE (nominals: *mut fmi3Float64, nContinuousStates: usize);
    fmi3GetNumberOfEventIndicators, fmi3GetNumberOfEventIndicatorsTYPE (nEventIndicators: *mut usize);
    fmi3GetNumberOfContinuousStates, fmi3GetNumberOfContinuousStatesTYPE (nContinuousStates: *mut usize);
    fmi3EnterStepMode, fmi3EnterStepModeTYPE ();
    fmi3GetOutputDerivatives, fmi3GetOutputDerivativesTYPE (valueReferences: *const fmi3ValueReference, nValueReferences: usize, orders: *const fmi3Int32, values: *mut fmi3Float64, nValues: usize);
    fmi3ActivateModelPartition, fmi3ActivateModelPartitionTYPE (clockReference: fmi3ValueReference, activationTime: fmi3Float64);
}
