//! The FMI 3.0 functions of what this FMU does not have, exported because the standard
//! requires every function of the interface types: variables of other types (any value
//! reference is unknown), clocks, structural parameters (Configuration Mode), per-element
//! dependencies at run time (they are in modelDescription.xml) and Scheduled Execution.
//! Each returns fmi3Error and says why; none changes the instance.
//!
//! Safety of every export: as in `exports3_common` (only value-reference arrays are read).
#![allow(clippy::missing_safety_doc)]
#![allow(non_snake_case)]

use super::guard::{guarded_as, slice};
use super::state_machine::Func;
use super::types::{Component, Status, ValueReference};
use libc::size_t;

/// Err for the first of `vr` (the model has no variable of that type); Ok for none.
fn no_such(vr: &[ValueReference]) -> Result<Status, String> {
    match vr.first() {
        None => Ok(Status::Ok),
        Some(v) => Err(format!(
            "unknown value reference {v} (the FMU has only Float64 variables and the Int32 solver.maxSteps)"
        )),
    }
}

/// Getters and setters of the types the FMU has no variables of: `(instance,
/// valueReferences, nValueReferences, values, nValues)`.
macro_rules! no_variables {
    ($($(#[$doc:meta])* $name:ident, $func:expr, $ptr:ty;)*) => {$(
        $(#[$doc])*
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(
            c: Component,
            vr: *const ValueReference,
            nvr: size_t,
            _values: $ptr,
            _nValues: size_t,
        ) -> Status {
            guarded_as(c, $func, Some(stringify!($name)), |_| {
                // SAFETY: nvr elements, per FMI.
                no_such(unsafe { slice(vr, nvr, "valueReferences")? })
            })
        }
    )*};
}

no_variables! {
    /// fmi3GetFloat32: no Float32 variables.
    fmi3GetFloat32, Func::GetBoolean, *mut f32;
    /// fmi3GetInt8: no Int8 variables.
    fmi3GetInt8, Func::GetBoolean, *mut i8;
    /// fmi3GetUInt8: no UInt8 variables.
    fmi3GetUInt8, Func::GetBoolean, *mut u8;
    /// fmi3GetInt16: no Int16 variables.
    fmi3GetInt16, Func::GetBoolean, *mut i16;
    /// fmi3GetUInt16: no UInt16 variables.
    fmi3GetUInt16, Func::GetBoolean, *mut u16;
    /// fmi3GetUInt32: no UInt32 variables.
    fmi3GetUInt32, Func::GetBoolean, *mut u32;
    /// fmi3GetInt64: no Int64 variables.
    fmi3GetInt64, Func::GetBoolean, *mut i64;
    /// fmi3GetUInt64: no UInt64 variables.
    fmi3GetUInt64, Func::GetBoolean, *mut u64;
    /// fmi3GetBoolean: no Boolean variables.
    fmi3GetBoolean, Func::GetBoolean, *mut u8;
    /// fmi3GetString: no String variables.
    fmi3GetString, Func::GetString, *mut *const libc::c_char;
    /// fmi3SetFloat32: no Float32 variables.
    fmi3SetFloat32, Func::SetBoolean, *const f32;
    /// fmi3SetInt8: no Int8 variables.
    fmi3SetInt8, Func::SetBoolean, *const i8;
    /// fmi3SetUInt8: no UInt8 variables.
    fmi3SetUInt8, Func::SetBoolean, *const u8;
    /// fmi3SetInt16: no Int16 variables.
    fmi3SetInt16, Func::SetBoolean, *const i16;
    /// fmi3SetUInt16: no UInt16 variables.
    fmi3SetUInt16, Func::SetBoolean, *const u16;
    /// fmi3SetUInt32: no UInt32 variables.
    fmi3SetUInt32, Func::SetBoolean, *const u32;
    /// fmi3SetInt64: no Int64 variables.
    fmi3SetInt64, Func::SetBoolean, *const i64;
    /// fmi3SetUInt64: no UInt64 variables.
    fmi3SetUInt64, Func::SetBoolean, *const u64;
    /// fmi3SetBoolean: no Boolean variables.
    fmi3SetBoolean, Func::SetBoolean, *const u8;
    /// fmi3SetString: no String variables.
    fmi3SetString, Func::SetString, *const *const libc::c_char;
}

/// fmi3GetBinary: no Binary variables.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBinary(
    c: Component,
    vr: *const ValueReference,
    nvr: size_t,
    _valueSizes: *mut size_t,
    _values: *mut *const u8,
    _nValues: size_t,
) -> Status {
    // SAFETY: nvr elements, per FMI.
    guarded_as(c, Func::GetBoolean, Some("fmi3GetBinary"), |_| no_such(unsafe { slice(vr, nvr, "valueReferences")? }))
}

/// fmi3SetBinary: no Binary variables.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBinary(
    c: Component,
    vr: *const ValueReference,
    nvr: size_t,
    _valueSizes: *const size_t,
    _values: *const *const u8,
    _nValues: size_t,
) -> Status {
    // SAFETY: nvr elements, per FMI.
    guarded_as(c, Func::SetBoolean, Some("fmi3SetBinary"), |_| no_such(unsafe { slice(vr, nvr, "valueReferences")? }))
}

/// Functions refused whatever their arguments (none is read): `name(instance, ...) =>
/// why`.
macro_rules! refused {
    ($($(#[$doc:meta])* $name:ident($($arg:ident: $ty:ty),*) => $why:expr;)*) => {$(
        $(#[$doc])*
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(c: Component $(, $arg: $ty)*) -> Status {
            $(let _ = $arg;)*
            guarded_as(c, Func::Unsupported, Some(stringify!($name)), |_| Err($why.into()))
        }
    )*};
}

const NO_CLOCKS: &str = "the FMU has no clocks";

refused! {
    /// fmi3GetClock: no clocks.
    fmi3GetClock(_vr: *const ValueReference, _nvr: size_t, _values: *mut u8) => NO_CLOCKS;
    /// fmi3SetClock: no clocks.
    fmi3SetClock(_vr: *const ValueReference, _nvr: size_t, _values: *const u8) => NO_CLOCKS;
    /// fmi3GetIntervalDecimal: no clocks.
    fmi3GetIntervalDecimal(_vr: *const ValueReference, _nvr: size_t, _i: *mut f64, _q: *mut i32) => NO_CLOCKS;
    /// fmi3GetIntervalFraction: no clocks.
    fmi3GetIntervalFraction(_vr: *const ValueReference, _nvr: size_t, _counters: *mut u64, _r: *mut u64, _q: *mut i32) => NO_CLOCKS;
    /// fmi3GetShiftDecimal: no clocks.
    fmi3GetShiftDecimal(_vr: *const ValueReference, _nvr: size_t, _s: *mut f64) => NO_CLOCKS;
    /// fmi3GetShiftFraction: no clocks.
    fmi3GetShiftFraction(_vr: *const ValueReference, _nvr: size_t, _counters: *mut u64, _r: *mut u64) => NO_CLOCKS;
    /// fmi3SetIntervalDecimal: no clocks.
    fmi3SetIntervalDecimal(_vr: *const ValueReference, _nvr: size_t, _i: *const f64) => NO_CLOCKS;
    /// fmi3SetIntervalFraction: no clocks.
    fmi3SetIntervalFraction(_vr: *const ValueReference, _nvr: size_t, _counters: *const u64, _r: *const u64) => NO_CLOCKS;
    /// fmi3SetShiftDecimal: no clocks.
    fmi3SetShiftDecimal(_vr: *const ValueReference, _nvr: size_t, _s: *const f64) => NO_CLOCKS;
    /// fmi3SetShiftFraction: no clocks.
    fmi3SetShiftFraction(_vr: *const ValueReference, _nvr: size_t, _counters: *const u64, _r: *const u64) => NO_CLOCKS;
    /// fmi3ActivateModelPartition: Scheduled Execution only.
    fmi3ActivateModelPartition(_clock: ValueReference, _t: f64) => "Scheduled Execution is not supported";
    /// fmi3EvaluateDiscreteStates: no discrete states.
    fmi3EvaluateDiscreteStates() => "the FMU has no discrete states (providesEvaluateDiscreteStates is false)";
    /// fmi3EnterConfigurationMode: no structural parameters.
    fmi3EnterConfigurationMode() => "the FMU has no structural parameters";
    /// fmi3ExitConfigurationMode: no structural parameters.
    fmi3ExitConfigurationMode() => "the FMU has no structural parameters";
    /// fmi3GetNumberOfVariableDependencies: the dependencies are in modelDescription.xml.
    fmi3GetNumberOfVariableDependencies(_vr: ValueReference, _n: *mut size_t) =>
        "not provided: the dependencies are in modelDescription.xml's <ModelStructure>";
    /// fmi3GetVariableDependencies: the dependencies are in modelDescription.xml.
    fmi3GetVariableDependencies(_d: ValueReference, _ed: *mut size_t, _i: *mut ValueReference, _ei: *mut size_t,
        _k: *mut i32, _n: size_t) => "not provided: the dependencies are in modelDescription.xml's <ModelStructure>";
}
