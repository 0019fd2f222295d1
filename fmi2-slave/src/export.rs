//! The export macro.

/// Generates all 34 FMI 2.0 common + Co-Simulation functions for the model
/// type `$model` as `#[no_mangle] extern "C"` symbols, each checked at
/// compile time against the standard's function typedef.
///
/// Invoke it exactly once, in the crate that is built as the FMU's cdylib,
/// with a path that resolves at the invocation site:
///
/// ```ignore
/// pub mod fmi2_exports {
///     fmi2_slave::export_fmi2!(crate::MyModel);
/// }
/// ```
///
/// The FMU state functions work when the model's description sets
/// `can_save_state` (else `fmi2Error`). Directional derivatives,
/// input/output derivatives and asynchronous steps are not supported: those
/// functions return `fmi2Error` with a log line naming the function.
#[macro_export]
macro_rules! export_fmi2 {
    ($model:ty) => {
        use $crate::ffi as __ffi;

        /// Returns `"default"`.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub extern "C" fn fmi2GetTypesPlatform() -> *const ::std::ffi::c_char {
            $crate::abi::get_types_platform()
        }
        const _: __ffi::fmi2GetTypesPlatformTYPE = Some(fmi2GetTypesPlatform);

        /// Returns `"2.0"`.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub extern "C" fn fmi2GetVersion() -> *const ::std::ffi::c_char {
            $crate::abi::get_version()
        }
        const _: __ffi::fmi2GetVersionTYPE = Some(fmi2GetVersion);

        /// FMI 2.0 `fmi2SetDebugLogging`.
        ///
        /// # Safety
        /// Arguments as the FMI 2.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2SetDebugLogging(
            c: __ffi::fmi2Component,
            logging_on: __ffi::fmi2Boolean,
            n_categories: usize,
            categories: *const __ffi::fmi2String,
        ) -> __ffi::fmi2Status {
            unsafe {
                $crate::abi::set_debug_logging::<$model>(c, logging_on, n_categories, categories)
            }
        }
        const _: __ffi::fmi2SetDebugLoggingTYPE = Some(fmi2SetDebugLogging);

        /// FMI 2.0 `fmi2Instantiate`.
        ///
        /// # Safety
        /// Arguments as the FMI 2.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2Instantiate(
            instance_name: __ffi::fmi2String,
            fmu_type: __ffi::fmi2Type,
            guid: __ffi::fmi2String,
            resource_location: __ffi::fmi2String,
            functions: *const __ffi::fmi2CallbackFunctions,
            visible: __ffi::fmi2Boolean,
            logging_on: __ffi::fmi2Boolean,
        ) -> __ffi::fmi2Component {
            unsafe {
                $crate::abi::instantiate::<$model>(
                    instance_name,
                    fmu_type,
                    guid,
                    resource_location,
                    functions,
                    visible,
                    logging_on,
                )
            }
        }
        const _: __ffi::fmi2InstantiateTYPE = Some(fmi2Instantiate);

        /// FMI 2.0 `fmi2FreeInstance`.
        ///
        /// # Safety
        /// `c` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2FreeInstance(c: __ffi::fmi2Component) {
            unsafe { $crate::abi::free_instance::<$model>(c) }
        }
        const _: __ffi::fmi2FreeInstanceTYPE = Some(fmi2FreeInstance);

        /// FMI 2.0 `fmi2SetupExperiment`.
        ///
        /// # Safety
        /// `c` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2SetupExperiment(
            c: __ffi::fmi2Component,
            tolerance_defined: __ffi::fmi2Boolean,
            tolerance: __ffi::fmi2Real,
            start_time: __ffi::fmi2Real,
            stop_time_defined: __ffi::fmi2Boolean,
            stop_time: __ffi::fmi2Real,
        ) -> __ffi::fmi2Status {
            unsafe {
                $crate::abi::setup_experiment::<$model>(
                    c,
                    tolerance_defined,
                    tolerance,
                    start_time,
                    stop_time_defined,
                    stop_time,
                )
            }
        }
        const _: __ffi::fmi2SetupExperimentTYPE = Some(fmi2SetupExperiment);

        /// FMI 2.0 `fmi2EnterInitializationMode`.
        ///
        /// # Safety
        /// `c` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2EnterInitializationMode(
            c: __ffi::fmi2Component,
        ) -> __ffi::fmi2Status {
            unsafe { $crate::abi::enter_initialization_mode::<$model>(c) }
        }
        const _: __ffi::fmi2EnterInitializationModeTYPE = Some(fmi2EnterInitializationMode);

        /// FMI 2.0 `fmi2ExitInitializationMode`.
        ///
        /// # Safety
        /// `c` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2ExitInitializationMode(
            c: __ffi::fmi2Component,
        ) -> __ffi::fmi2Status {
            unsafe { $crate::abi::exit_initialization_mode::<$model>(c) }
        }
        const _: __ffi::fmi2ExitInitializationModeTYPE = Some(fmi2ExitInitializationMode);

        /// FMI 2.0 `fmi2Terminate`.
        ///
        /// # Safety
        /// `c` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2Terminate(c: __ffi::fmi2Component) -> __ffi::fmi2Status {
            unsafe { $crate::abi::terminate::<$model>(c) }
        }
        const _: __ffi::fmi2TerminateTYPE = Some(fmi2Terminate);

        /// FMI 2.0 `fmi2Reset`.
        ///
        /// # Safety
        /// `c` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2Reset(c: __ffi::fmi2Component) -> __ffi::fmi2Status {
            unsafe { $crate::abi::reset::<$model>(c) }
        }
        const _: __ffi::fmi2ResetTYPE = Some(fmi2Reset);

        $crate::export_fmi2!(@getset $model, fmi2GetReal, fmi2GetRealTYPE, get_real, *mut __ffi::fmi2Real);
        $crate::export_fmi2!(@getset $model, fmi2GetInteger, fmi2GetIntegerTYPE, get_integer, *mut __ffi::fmi2Integer);
        $crate::export_fmi2!(@getset $model, fmi2GetBoolean, fmi2GetBooleanTYPE, get_boolean, *mut __ffi::fmi2Boolean);
        $crate::export_fmi2!(@getset $model, fmi2GetString, fmi2GetStringTYPE, get_string, *mut __ffi::fmi2String);
        $crate::export_fmi2!(@getset $model, fmi2SetReal, fmi2SetRealTYPE, set_real, *const __ffi::fmi2Real);
        $crate::export_fmi2!(@getset $model, fmi2SetInteger, fmi2SetIntegerTYPE, set_integer, *const __ffi::fmi2Integer);
        $crate::export_fmi2!(@getset $model, fmi2SetBoolean, fmi2SetBooleanTYPE, set_boolean, *const __ffi::fmi2Boolean);
        $crate::export_fmi2!(@getset $model, fmi2SetString, fmi2SetStringTYPE, set_string, *const __ffi::fmi2String);

        $crate::export_fmi2!(@state $model, fmi2GetFMUstate, fmi2GetFMUstateTYPE, get_fmu_state,
            (s: *mut __ffi::fmi2FMUstate));
        $crate::export_fmi2!(@state $model, fmi2SetFMUstate, fmi2SetFMUstateTYPE, set_fmu_state,
            (s: __ffi::fmi2FMUstate));
        $crate::export_fmi2!(@state $model, fmi2FreeFMUstate, fmi2FreeFMUstateTYPE, free_fmu_state,
            (s: *mut __ffi::fmi2FMUstate));
        $crate::export_fmi2!(@state $model, fmi2SerializedFMUstateSize, fmi2SerializedFMUstateSizeTYPE,
            serialized_fmu_state_size, (s: __ffi::fmi2FMUstate, size: *mut usize));
        $crate::export_fmi2!(@state $model, fmi2SerializeFMUstate, fmi2SerializeFMUstateTYPE,
            serialize_fmu_state, (s: __ffi::fmi2FMUstate, bytes: *mut __ffi::fmi2Byte, size: usize));
        $crate::export_fmi2!(@state $model, fmi2DeSerializeFMUstate, fmi2DeSerializeFMUstateTYPE,
            deserialize_fmu_state, (bytes: *const __ffi::fmi2Byte, size: usize, s: *mut __ffi::fmi2FMUstate));
        $crate::export_fmi2!(@unsupported $model, fmi2GetDirectionalDerivative, fmi2GetDirectionalDerivativeTYPE,
            "providesDirectionalDerivative is false",
            (_u: *const __ffi::fmi2ValueReference, _nu: usize, _k: *const __ffi::fmi2ValueReference,
             _nk: usize, _dk: *const __ffi::fmi2Real, _du: *mut __ffi::fmi2Real));
        $crate::export_fmi2!(@unsupported $model, fmi2SetRealInputDerivatives, fmi2SetRealInputDerivativesTYPE,
            "canInterpolateInputs is false",
            (_vr: *const __ffi::fmi2ValueReference, _n: usize, _o: *const __ffi::fmi2Integer, _v: *const __ffi::fmi2Real));
        $crate::export_fmi2!(@unsupported $model, fmi2GetRealOutputDerivatives, fmi2GetRealOutputDerivativesTYPE,
            "maxOutputDerivativeOrder is 0",
            (_vr: *const __ffi::fmi2ValueReference, _n: usize, _o: *const __ffi::fmi2Integer, _v: *mut __ffi::fmi2Real));
        $crate::export_fmi2!(@unsupported $model, fmi2CancelStep, fmi2CancelStepTYPE,
            "fmi2DoStep never returns fmi2Pending", ());
        $crate::export_fmi2!(@status_unavailable $model, fmi2GetStatus, fmi2GetStatusTYPE,
            "fmi2DoStep never returns fmi2Pending", (_k: __ffi::fmi2StatusKind, _v: *mut __ffi::fmi2Status));
        $crate::export_fmi2!(@status_unavailable $model, fmi2GetIntegerStatus, fmi2GetIntegerStatusTYPE,
            "there is no Integer status", (_k: __ffi::fmi2StatusKind, _v: *mut __ffi::fmi2Integer));
        $crate::export_fmi2!(@status_unavailable $model, fmi2GetStringStatus, fmi2GetStringStatusTYPE,
            "fmi2DoStep never returns fmi2Pending", (_k: __ffi::fmi2StatusKind, _v: *mut __ffi::fmi2String));

        /// FMI 2.0 `fmi2DoStep`.
        ///
        /// # Safety
        /// `c` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2DoStep(
            c: __ffi::fmi2Component,
            current_communication_point: __ffi::fmi2Real,
            communication_step_size: __ffi::fmi2Real,
            no_set_fmu_state_prior: __ffi::fmi2Boolean,
        ) -> __ffi::fmi2Status {
            unsafe {
                $crate::abi::do_step::<$model>(
                    c,
                    current_communication_point,
                    communication_step_size,
                    no_set_fmu_state_prior,
                )
            }
        }
        const _: __ffi::fmi2DoStepTYPE = Some(fmi2DoStep);

        /// FMI 2.0 `fmi2GetRealStatus` (`fmi2LastSuccessfulTime`).
        ///
        /// # Safety
        /// Arguments as the FMI 2.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2GetRealStatus(
            c: __ffi::fmi2Component,
            kind: __ffi::fmi2StatusKind,
            value: *mut __ffi::fmi2Real,
        ) -> __ffi::fmi2Status {
            unsafe { $crate::abi::get_real_status::<$model>(c, kind, value) }
        }
        const _: __ffi::fmi2GetRealStatusTYPE = Some(fmi2GetRealStatus);

        /// FMI 2.0 `fmi2GetBooleanStatus` (`fmi2Terminated`).
        ///
        /// # Safety
        /// Arguments as the FMI 2.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi2GetBooleanStatus(
            c: __ffi::fmi2Component,
            kind: __ffi::fmi2StatusKind,
            value: *mut __ffi::fmi2Boolean,
        ) -> __ffi::fmi2Status {
            unsafe { $crate::abi::get_boolean_status::<$model>(c, kind, value) }
        }
        const _: __ffi::fmi2GetBooleanStatusTYPE = Some(fmi2GetBooleanStatus);
    };

    (@getset $model:ty, $name:ident, $ty:ident, $fn:ident, $value:ty) => {
        /// FMI 2.0 value access by value reference.
        ///
        /// # Safety
        /// `c` is null or a live instance; `vr` and `value` null or arrays of `nvr` elements.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn $name(
            c: $crate::ffi::fmi2Component,
            vr: *const $crate::ffi::fmi2ValueReference,
            nvr: usize,
            value: $value,
        ) -> $crate::ffi::fmi2Status {
            unsafe { $crate::abi::$fn::<$model>(c, vr, nvr, value) }
        }
        const _: $crate::ffi::$ty = Some($name);
    };

    (@status_unavailable $model:ty, $name:ident, $ty:ident, $why:literal, ($kind:ident : $kindty:ty, $value:ident : $valuety:ty)) => {
        /// A status this FMU cannot provide: returns `fmi2Discard` with a
        /// warning line (FMI 2.0 section 4.2.3); the instance stays usable.
        /// A NULL `value` pointer is `fmi2Error`.
        ///
        /// # Safety
        /// `c` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn $name(
            c: $crate::ffi::fmi2Component,
            $kind: $kindty,
            $value: $valuety,
        ) -> $crate::ffi::fmi2Status {
            unsafe {
                $crate::abi::status_unavailable::<$model>(c, stringify!($name), $why, $value.is_null())
            }
        }
        const _: $crate::ffi::$ty = Some($name);
    };

    (@state $model:ty, $name:ident, $ty:ident, $func:ident, ($($arg:ident : $argty:ty),* $(,)?)) => {
        /// FMU state save and restore (see `fmi2_slave::state`).
        ///
        /// # Safety
        /// Arguments as the FMI 2.0 standard defines them.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn $name(
            c: $crate::ffi::fmi2Component,
            $($arg: $argty),*
        ) -> $crate::ffi::fmi2Status {
            unsafe { $crate::abi::$func::<$model>(c, $($arg),*) }
        }
        const _: $crate::ffi::$ty = Some($name);
    };

    (@unsupported $model:ty, $name:ident, $ty:ident, $why:literal, ($($arg:ident : $argty:ty),* $(,)?)) => {
        /// Not supported by this FMU: returns `fmi2Error` with a log line.
        ///
        /// # Safety
        /// `c` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn $name(
            c: $crate::ffi::fmi2Component,
            $($arg: $argty),*
        ) -> $crate::ffi::fmi2Status {
            unsafe { $crate::abi::unsupported::<$model>(c, stringify!($name), $why) }
        }
        const _: $crate::ffi::$ty = Some($name);
    };
}
