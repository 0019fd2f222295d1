//! The export macro.

/// Generates all 75 functions of FMI 3.0's `fmi3Functions.h` for the model
/// type `$model` as `#[no_mangle] extern "C"` symbols, each checked at
/// compile time against the standard's function typedef.
///
/// Invoke it exactly once, in the crate that is built as the FMU's cdylib,
/// with a path that resolves at the invocation site; it may sit next to
/// `fmi2_slave::export_fmi2!` (even in the same module) for one binary
/// that is both an FMI 2.0 and an FMI 3.0 FMU:
///
/// ```ignore
/// pub mod fmi_exports {
///     fmi2_slave::export_fmi2!(crate::MyModel);
///     fmi3_slave::export_fmi3!(crate::MyModel);
/// }
/// ```
///
/// Co-Simulation is implemented; `fmi3GetFloat64` / `SetFloat64`, `Int32`,
/// `Int64` (enumerations) and `Boolean` access the model's variables (arrays
/// in row-major order). The getters and setters of the other types answer
/// `fmi3OK` for no value references and `fmi3Error` otherwise. The FMU
/// state functions work when the model's description sets `can_save_state`.
/// Model Exchange and Scheduled Execution (their instantiation returns
/// NULL), Event Mode, Configuration Mode, clocks, directional and adjoint
/// derivatives, output derivatives and per-element dependencies are not
/// supported: those functions return `fmi3Error` with a log line naming the
/// function.
#[macro_export]
macro_rules! export_fmi3 {
    ($model:ty) => {
        use $crate::ffi as __fmi3_ffi;

        /// Returns `"3.0"`.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub extern "C" fn fmi3GetVersion() -> *const ::std::ffi::c_char {
            $crate::abi::get_version()
        }
        const _: __fmi3_ffi::fmi3GetVersionTYPE = Some(fmi3GetVersion);

        /// FMI 3.0 `fmi3SetDebugLogging`.
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3SetDebugLogging(
            instance: __fmi3_ffi::fmi3Instance,
            logging_on: __fmi3_ffi::fmi3Boolean,
            n_categories: usize,
            categories: *const __fmi3_ffi::fmi3String,
        ) -> __fmi3_ffi::fmi3Status {
            unsafe {
                $crate::abi::set_debug_logging::<$model>(instance, logging_on, n_categories, categories)
            }
        }
        const _: __fmi3_ffi::fmi3SetDebugLoggingTYPE = Some(fmi3SetDebugLogging);

        /// FMI 3.0 `fmi3InstantiateModelExchange`: not supported (NULL).
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3InstantiateModelExchange(
            instance_name: __fmi3_ffi::fmi3String,
            _token: __fmi3_ffi::fmi3String,
            _resource_path: __fmi3_ffi::fmi3String,
            _visible: __fmi3_ffi::fmi3Boolean,
            _logging_on: __fmi3_ffi::fmi3Boolean,
            environment: __fmi3_ffi::fmi3InstanceEnvironment,
            log_message: __fmi3_ffi::fmi3LogMessageCallback,
        ) -> __fmi3_ffi::fmi3Instance {
            unsafe {
                $crate::abi::instantiate_unsupported(
                    "fmi3InstantiateModelExchange",
                    instance_name,
                    environment,
                    log_message,
                )
            }
        }
        const _: __fmi3_ffi::fmi3InstantiateModelExchangeTYPE = Some(fmi3InstantiateModelExchange);

        /// FMI 3.0 `fmi3InstantiateCoSimulation`.
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::too_many_arguments)]
        pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
            instance_name: __fmi3_ffi::fmi3String,
            instantiation_token: __fmi3_ffi::fmi3String,
            resource_path: __fmi3_ffi::fmi3String,
            visible: __fmi3_ffi::fmi3Boolean,
            logging_on: __fmi3_ffi::fmi3Boolean,
            event_mode_used: __fmi3_ffi::fmi3Boolean,
            early_return_allowed: __fmi3_ffi::fmi3Boolean,
            required_intermediate_variables: *const __fmi3_ffi::fmi3ValueReference,
            n_required_intermediate_variables: usize,
            instance_environment: __fmi3_ffi::fmi3InstanceEnvironment,
            log_message: __fmi3_ffi::fmi3LogMessageCallback,
            intermediate_update: __fmi3_ffi::fmi3IntermediateUpdateCallback,
        ) -> __fmi3_ffi::fmi3Instance {
            unsafe {
                $crate::abi::instantiate_co_simulation::<$model>(
                    instance_name,
                    instantiation_token,
                    resource_path,
                    visible,
                    logging_on,
                    event_mode_used,
                    early_return_allowed,
                    required_intermediate_variables,
                    n_required_intermediate_variables,
                    instance_environment,
                    log_message,
                    intermediate_update,
                )
            }
        }
        const _: __fmi3_ffi::fmi3InstantiateCoSimulationTYPE = Some(fmi3InstantiateCoSimulation);

        /// FMI 3.0 `fmi3InstantiateScheduledExecution`: not supported (NULL).
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::too_many_arguments)]
        pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
            instance_name: __fmi3_ffi::fmi3String,
            _token: __fmi3_ffi::fmi3String,
            _resource_path: __fmi3_ffi::fmi3String,
            _visible: __fmi3_ffi::fmi3Boolean,
            _logging_on: __fmi3_ffi::fmi3Boolean,
            environment: __fmi3_ffi::fmi3InstanceEnvironment,
            log_message: __fmi3_ffi::fmi3LogMessageCallback,
            _clock_update: __fmi3_ffi::fmi3ClockUpdateCallback,
            _lock_preemption: __fmi3_ffi::fmi3LockPreemptionCallback,
            _unlock_preemption: __fmi3_ffi::fmi3UnlockPreemptionCallback,
        ) -> __fmi3_ffi::fmi3Instance {
            unsafe {
                $crate::abi::instantiate_unsupported(
                    "fmi3InstantiateScheduledExecution",
                    instance_name,
                    environment,
                    log_message,
                )
            }
        }
        const _: __fmi3_ffi::fmi3InstantiateScheduledExecutionTYPE =
            Some(fmi3InstantiateScheduledExecution);

        /// FMI 3.0 `fmi3FreeInstance`.
        ///
        /// # Safety
        /// `instance` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3FreeInstance(instance: __fmi3_ffi::fmi3Instance) {
            unsafe { $crate::abi::free_instance::<$model>(instance) }
        }
        const _: __fmi3_ffi::fmi3FreeInstanceTYPE = Some(fmi3FreeInstance);

        /// FMI 3.0 `fmi3EnterInitializationMode`.
        ///
        /// # Safety
        /// `instance` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3EnterInitializationMode(
            instance: __fmi3_ffi::fmi3Instance,
            tolerance_defined: __fmi3_ffi::fmi3Boolean,
            tolerance: __fmi3_ffi::fmi3Float64,
            start_time: __fmi3_ffi::fmi3Float64,
            stop_time_defined: __fmi3_ffi::fmi3Boolean,
            stop_time: __fmi3_ffi::fmi3Float64,
        ) -> __fmi3_ffi::fmi3Status {
            unsafe {
                $crate::abi::enter_initialization_mode::<$model>(
                    instance,
                    tolerance_defined,
                    tolerance,
                    start_time,
                    stop_time_defined,
                    stop_time,
                )
            }
        }
        const _: __fmi3_ffi::fmi3EnterInitializationModeTYPE = Some(fmi3EnterInitializationMode);

        /// FMI 3.0 `fmi3ExitInitializationMode`: enters Step Mode.
        ///
        /// # Safety
        /// `instance` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3ExitInitializationMode(
            instance: __fmi3_ffi::fmi3Instance,
        ) -> __fmi3_ffi::fmi3Status {
            unsafe { $crate::abi::exit_initialization_mode::<$model>(instance) }
        }
        const _: __fmi3_ffi::fmi3ExitInitializationModeTYPE = Some(fmi3ExitInitializationMode);

        /// FMI 3.0 `fmi3Terminate`.
        ///
        /// # Safety
        /// `instance` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3Terminate(
            instance: __fmi3_ffi::fmi3Instance,
        ) -> __fmi3_ffi::fmi3Status {
            unsafe { $crate::abi::terminate::<$model>(instance) }
        }
        const _: __fmi3_ffi::fmi3TerminateTYPE = Some(fmi3Terminate);

        /// FMI 3.0 `fmi3Reset`.
        ///
        /// # Safety
        /// `instance` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3Reset(instance: __fmi3_ffi::fmi3Instance) -> __fmi3_ffi::fmi3Status {
            unsafe { $crate::abi::reset::<$model>(instance) }
        }
        const _: __fmi3_ffi::fmi3ResetTYPE = Some(fmi3Reset);

        $crate::export_fmi3!(@typed $model, fmi3GetFloat64, fmi3GetFloat64TYPE, get_float64, *mut __fmi3_ffi::fmi3Float64);
        $crate::export_fmi3!(@typed $model, fmi3SetFloat64, fmi3SetFloat64TYPE, set_float64, *const __fmi3_ffi::fmi3Float64);
        $crate::export_fmi3!(@typed $model, fmi3GetInt32, fmi3GetInt32TYPE, get_int32, *mut __fmi3_ffi::fmi3Int32);
        $crate::export_fmi3!(@typed $model, fmi3SetInt32, fmi3SetInt32TYPE, set_int32, *const __fmi3_ffi::fmi3Int32);
        $crate::export_fmi3!(@typed $model, fmi3GetInt64, fmi3GetInt64TYPE, get_int64, *mut __fmi3_ffi::fmi3Int64);
        $crate::export_fmi3!(@typed $model, fmi3SetInt64, fmi3SetInt64TYPE, set_int64, *const __fmi3_ffi::fmi3Int64);
        $crate::export_fmi3!(@typed $model, fmi3GetBoolean, fmi3GetBooleanTYPE, get_boolean, *mut __fmi3_ffi::fmi3Boolean);
        $crate::export_fmi3!(@typed $model, fmi3SetBoolean, fmi3SetBooleanTYPE, set_boolean, *const __fmi3_ffi::fmi3Boolean);

        $crate::export_fmi3!(@other $model, fmi3GetFloat32, fmi3GetFloat32TYPE, "Float32", false, *mut __fmi3_ffi::fmi3Float32);
        $crate::export_fmi3!(@other $model, fmi3SetFloat32, fmi3SetFloat32TYPE, "Float32", true, *const __fmi3_ffi::fmi3Float32);
        $crate::export_fmi3!(@other $model, fmi3GetInt8, fmi3GetInt8TYPE, "Int8", false, *mut __fmi3_ffi::fmi3Int8);
        $crate::export_fmi3!(@other $model, fmi3SetInt8, fmi3SetInt8TYPE, "Int8", true, *const __fmi3_ffi::fmi3Int8);
        $crate::export_fmi3!(@other $model, fmi3GetUInt8, fmi3GetUInt8TYPE, "UInt8", false, *mut __fmi3_ffi::fmi3UInt8);
        $crate::export_fmi3!(@other $model, fmi3SetUInt8, fmi3SetUInt8TYPE, "UInt8", true, *const __fmi3_ffi::fmi3UInt8);
        $crate::export_fmi3!(@other $model, fmi3GetInt16, fmi3GetInt16TYPE, "Int16", false, *mut __fmi3_ffi::fmi3Int16);
        $crate::export_fmi3!(@other $model, fmi3SetInt16, fmi3SetInt16TYPE, "Int16", true, *const __fmi3_ffi::fmi3Int16);
        $crate::export_fmi3!(@other $model, fmi3GetUInt16, fmi3GetUInt16TYPE, "UInt16", false, *mut __fmi3_ffi::fmi3UInt16);
        $crate::export_fmi3!(@other $model, fmi3SetUInt16, fmi3SetUInt16TYPE, "UInt16", true, *const __fmi3_ffi::fmi3UInt16);
        $crate::export_fmi3!(@other $model, fmi3GetUInt32, fmi3GetUInt32TYPE, "UInt32", false, *mut __fmi3_ffi::fmi3UInt32);
        $crate::export_fmi3!(@other $model, fmi3SetUInt32, fmi3SetUInt32TYPE, "UInt32", true, *const __fmi3_ffi::fmi3UInt32);
        $crate::export_fmi3!(@other $model, fmi3GetUInt64, fmi3GetUInt64TYPE, "UInt64", false, *mut __fmi3_ffi::fmi3UInt64);
        $crate::export_fmi3!(@other $model, fmi3SetUInt64, fmi3SetUInt64TYPE, "UInt64", true, *const __fmi3_ffi::fmi3UInt64);
        $crate::export_fmi3!(@other $model, fmi3GetString, fmi3GetStringTYPE, "String", false, *mut __fmi3_ffi::fmi3String);
        $crate::export_fmi3!(@other $model, fmi3SetString, fmi3SetStringTYPE, "String", true, *const __fmi3_ffi::fmi3String);

        /// FMI 3.0 `fmi3GetBinary`: this FMU has no Binary variables.
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3GetBinary(
            instance: __fmi3_ffi::fmi3Instance,
            vr: *const __fmi3_ffi::fmi3ValueReference,
            nvr: usize,
            value_sizes: *mut usize,
            values: *mut __fmi3_ffi::fmi3Binary,
            n_values: usize,
        ) -> __fmi3_ffi::fmi3Status {
            unsafe {
                $crate::abi::other_type::<$model>(
                    instance, "fmi3GetBinary", "Binary", vr, nvr,
                    n_values > 0 && (values.is_null() || value_sizes.is_null()), false,
                )
            }
        }
        const _: __fmi3_ffi::fmi3GetBinaryTYPE = Some(fmi3GetBinary);

        /// FMI 3.0 `fmi3SetBinary`: this FMU has no Binary variables.
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3SetBinary(
            instance: __fmi3_ffi::fmi3Instance,
            vr: *const __fmi3_ffi::fmi3ValueReference,
            nvr: usize,
            value_sizes: *const usize,
            values: *const __fmi3_ffi::fmi3Binary,
            n_values: usize,
        ) -> __fmi3_ffi::fmi3Status {
            unsafe {
                $crate::abi::other_type::<$model>(
                    instance, "fmi3SetBinary", "Binary", vr, nvr,
                    n_values > 0 && (values.is_null() || value_sizes.is_null()), true,
                )
            }
        }
        const _: __fmi3_ffi::fmi3SetBinaryTYPE = Some(fmi3SetBinary);

        /// FMI 3.0 `fmi3GetClock`: this FMU has no clocks.
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3GetClock(
            instance: __fmi3_ffi::fmi3Instance,
            vr: *const __fmi3_ffi::fmi3ValueReference,
            nvr: usize,
            values: *mut __fmi3_ffi::fmi3Clock,
        ) -> __fmi3_ffi::fmi3Status {
            unsafe {
                $crate::abi::other_type::<$model>(
                    instance, "fmi3GetClock", "Clock", vr, nvr, nvr > 0 && values.is_null(), false,
                )
            }
        }
        const _: __fmi3_ffi::fmi3GetClockTYPE = Some(fmi3GetClock);

        /// FMI 3.0 `fmi3SetClock`: this FMU has no clocks.
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn fmi3SetClock(
            instance: __fmi3_ffi::fmi3Instance,
            vr: *const __fmi3_ffi::fmi3ValueReference,
            nvr: usize,
            values: *const __fmi3_ffi::fmi3Clock,
        ) -> __fmi3_ffi::fmi3Status {
            unsafe {
                $crate::abi::other_type::<$model>(
                    instance, "fmi3SetClock", "Clock", vr, nvr, nvr > 0 && values.is_null(), true,
                )
            }
        }
        const _: __fmi3_ffi::fmi3SetClockTYPE = Some(fmi3SetClock);

        $crate::export_fmi3!(@state $model, fmi3GetFMUState, fmi3GetFMUStateTYPE, get_fmu_state,
            (s: *mut __fmi3_ffi::fmi3FMUState));
        $crate::export_fmi3!(@state $model, fmi3SetFMUState, fmi3SetFMUStateTYPE, set_fmu_state,
            (s: __fmi3_ffi::fmi3FMUState));
        $crate::export_fmi3!(@state $model, fmi3FreeFMUState, fmi3FreeFMUStateTYPE, free_fmu_state,
            (s: *mut __fmi3_ffi::fmi3FMUState));
        $crate::export_fmi3!(@state $model, fmi3SerializedFMUStateSize, fmi3SerializedFMUStateSizeTYPE,
            serialized_fmu_state_size, (s: __fmi3_ffi::fmi3FMUState, size: *mut usize));
        $crate::export_fmi3!(@state $model, fmi3SerializeFMUState, fmi3SerializeFMUStateTYPE,
            serialize_fmu_state, (s: __fmi3_ffi::fmi3FMUState, bytes: *mut __fmi3_ffi::fmi3Byte, size: usize));
        $crate::export_fmi3!(@state $model, fmi3DeserializeFMUState, fmi3DeserializeFMUStateTYPE,
            deserialize_fmu_state, (bytes: *const __fmi3_ffi::fmi3Byte, size: usize, s: *mut __fmi3_ffi::fmi3FMUState));

        $crate::export_fmi3!(@unsupported $model, fmi3EnterEventMode, fmi3EnterEventModeTYPE,
            "hasEventMode is false (the instance is in Step Mode after fmi3ExitInitializationMode)", ());
        $crate::export_fmi3!(@unsupported $model, fmi3GetNumberOfVariableDependencies,
            fmi3GetNumberOfVariableDependenciesTYPE,
            "providesPerElementDependencies is false (the dependencies are in modelDescription.xml)",
            (_vr: __fmi3_ffi::fmi3ValueReference, _n: *mut usize));
        $crate::export_fmi3!(@unsupported $model, fmi3GetVariableDependencies, fmi3GetVariableDependenciesTYPE,
            "providesPerElementDependencies is false (the dependencies are in modelDescription.xml)",
            (_dependent: __fmi3_ffi::fmi3ValueReference, _ei: *mut usize,
             _independents: *mut __fmi3_ffi::fmi3ValueReference, _eii: *mut usize,
             _kinds: *mut __fmi3_ffi::fmi3DependencyKind, _n: usize));
        $crate::export_fmi3!(@unsupported $model, fmi3GetDirectionalDerivative, fmi3GetDirectionalDerivativeTYPE,
            "providesDirectionalDerivatives is false",
            (_u: *const __fmi3_ffi::fmi3ValueReference, _nu: usize,
             _k: *const __fmi3_ffi::fmi3ValueReference, _nk: usize,
             _seed: *const __fmi3_ffi::fmi3Float64, _ns: usize,
             _sens: *mut __fmi3_ffi::fmi3Float64, _nsens: usize));
        $crate::export_fmi3!(@unsupported $model, fmi3GetAdjointDerivative, fmi3GetAdjointDerivativeTYPE,
            "providesAdjointDerivatives is false",
            (_u: *const __fmi3_ffi::fmi3ValueReference, _nu: usize,
             _k: *const __fmi3_ffi::fmi3ValueReference, _nk: usize,
             _seed: *const __fmi3_ffi::fmi3Float64, _ns: usize,
             _sens: *mut __fmi3_ffi::fmi3Float64, _nsens: usize));
        $crate::export_fmi3!(@unsupported $model, fmi3EnterConfigurationMode, fmi3EnterConfigurationModeTYPE,
            "this FMU has no structural parameters (no Configuration Mode)", ());
        $crate::export_fmi3!(@unsupported $model, fmi3ExitConfigurationMode, fmi3ExitConfigurationModeTYPE,
            "this FMU has no structural parameters (no Configuration Mode)", ());
        $crate::export_fmi3!(@unsupported $model, fmi3GetIntervalDecimal, fmi3GetIntervalDecimalTYPE,
            "this FMU has no clocks",
            (_vr: *const __fmi3_ffi::fmi3ValueReference, _n: usize,
             _intervals: *mut __fmi3_ffi::fmi3Float64, _q: *mut __fmi3_ffi::fmi3IntervalQualifier));
        $crate::export_fmi3!(@unsupported $model, fmi3GetIntervalFraction, fmi3GetIntervalFractionTYPE,
            "this FMU has no clocks",
            (_vr: *const __fmi3_ffi::fmi3ValueReference, _n: usize,
             _counters: *mut __fmi3_ffi::fmi3UInt64, _res: *mut __fmi3_ffi::fmi3UInt64,
             _q: *mut __fmi3_ffi::fmi3IntervalQualifier));
        $crate::export_fmi3!(@unsupported $model, fmi3GetShiftDecimal, fmi3GetShiftDecimalTYPE,
            "this FMU has no clocks",
            (_vr: *const __fmi3_ffi::fmi3ValueReference, _n: usize, _shifts: *mut __fmi3_ffi::fmi3Float64));
        $crate::export_fmi3!(@unsupported $model, fmi3GetShiftFraction, fmi3GetShiftFractionTYPE,
            "this FMU has no clocks",
            (_vr: *const __fmi3_ffi::fmi3ValueReference, _n: usize,
             _counters: *mut __fmi3_ffi::fmi3UInt64, _res: *mut __fmi3_ffi::fmi3UInt64));
        $crate::export_fmi3!(@unsupported $model, fmi3SetIntervalDecimal, fmi3SetIntervalDecimalTYPE,
            "this FMU has no clocks",
            (_vr: *const __fmi3_ffi::fmi3ValueReference, _n: usize, _intervals: *const __fmi3_ffi::fmi3Float64));
        $crate::export_fmi3!(@unsupported $model, fmi3SetIntervalFraction, fmi3SetIntervalFractionTYPE,
            "this FMU has no clocks",
            (_vr: *const __fmi3_ffi::fmi3ValueReference, _n: usize,
             _counters: *const __fmi3_ffi::fmi3UInt64, _res: *const __fmi3_ffi::fmi3UInt64));
        $crate::export_fmi3!(@unsupported $model, fmi3SetShiftDecimal, fmi3SetShiftDecimalTYPE,
            "this FMU has no clocks",
            (_vr: *const __fmi3_ffi::fmi3ValueReference, _n: usize, _shifts: *const __fmi3_ffi::fmi3Float64));
        $crate::export_fmi3!(@unsupported $model, fmi3SetShiftFraction, fmi3SetShiftFractionTYPE,
            "this FMU has no clocks",
            (_vr: *const __fmi3_ffi::fmi3ValueReference, _n: usize,
             _counters: *const __fmi3_ffi::fmi3UInt64, _res: *const __fmi3_ffi::fmi3UInt64));
        $crate::export_fmi3!(@unsupported $model, fmi3EvaluateDiscreteStates, fmi3EvaluateDiscreteStatesTYPE,
            "providesEvaluateDiscreteStates is false", ());
        $crate::export_fmi3!(@unsupported $model, fmi3UpdateDiscreteStates, fmi3UpdateDiscreteStatesTYPE,
            "hasEventMode is false (no Event Mode)",
            (_a: *mut __fmi3_ffi::fmi3Boolean, _b: *mut __fmi3_ffi::fmi3Boolean,
             _c: *mut __fmi3_ffi::fmi3Boolean, _d: *mut __fmi3_ffi::fmi3Boolean,
             _e: *mut __fmi3_ffi::fmi3Boolean, _t: *mut __fmi3_ffi::fmi3Float64));
        $crate::export_fmi3!(@unsupported $model, fmi3EnterContinuousTimeMode, fmi3EnterContinuousTimeModeTYPE,
            "Model Exchange is not supported", ());
        $crate::export_fmi3!(@unsupported $model, fmi3CompletedIntegratorStep, fmi3CompletedIntegratorStepTYPE,
            "Model Exchange is not supported",
            (_no_prior: __fmi3_ffi::fmi3Boolean, _event: *mut __fmi3_ffi::fmi3Boolean,
             _terminate: *mut __fmi3_ffi::fmi3Boolean));
        $crate::export_fmi3!(@unsupported $model, fmi3SetTime, fmi3SetTimeTYPE,
            "Model Exchange is not supported", (_time: __fmi3_ffi::fmi3Float64));
        $crate::export_fmi3!(@unsupported $model, fmi3SetContinuousStates, fmi3SetContinuousStatesTYPE,
            "Model Exchange is not supported",
            (_x: *const __fmi3_ffi::fmi3Float64, _n: usize));
        $crate::export_fmi3!(@unsupported $model, fmi3GetContinuousStateDerivatives,
            fmi3GetContinuousStateDerivativesTYPE, "Model Exchange is not supported",
            (_dx: *mut __fmi3_ffi::fmi3Float64, _n: usize));
        $crate::export_fmi3!(@unsupported $model, fmi3GetEventIndicators, fmi3GetEventIndicatorsTYPE,
            "Model Exchange is not supported",
            (_z: *mut __fmi3_ffi::fmi3Float64, _n: usize));
        $crate::export_fmi3!(@unsupported $model, fmi3GetContinuousStates, fmi3GetContinuousStatesTYPE,
            "Model Exchange is not supported",
            (_x: *mut __fmi3_ffi::fmi3Float64, _n: usize));
        $crate::export_fmi3!(@unsupported $model, fmi3GetNominalsOfContinuousStates,
            fmi3GetNominalsOfContinuousStatesTYPE, "Model Exchange is not supported",
            (_nominals: *mut __fmi3_ffi::fmi3Float64, _n: usize));
        $crate::export_fmi3!(@unsupported $model, fmi3GetNumberOfEventIndicators,
            fmi3GetNumberOfEventIndicatorsTYPE, "Model Exchange is not supported", (_n: *mut usize));
        $crate::export_fmi3!(@unsupported $model, fmi3GetNumberOfContinuousStates,
            fmi3GetNumberOfContinuousStatesTYPE, "Model Exchange is not supported", (_n: *mut usize));
        $crate::export_fmi3!(@unsupported $model, fmi3EnterStepMode, fmi3EnterStepModeTYPE,
            "hasEventMode is false (the instance is in Step Mode after fmi3ExitInitializationMode)", ());
        $crate::export_fmi3!(@unsupported $model, fmi3GetOutputDerivatives, fmi3GetOutputDerivativesTYPE,
            "maxOutputDerivativeOrder is 0",
            (_vr: *const __fmi3_ffi::fmi3ValueReference, _nvr: usize, _orders: *const __fmi3_ffi::fmi3Int32,
             _values: *mut __fmi3_ffi::fmi3Float64, _n: usize));
        $crate::export_fmi3!(@unsupported $model, fmi3ActivateModelPartition, fmi3ActivateModelPartitionTYPE,
            "Scheduled Execution is not supported",
            (_clock: __fmi3_ffi::fmi3ValueReference, _t: __fmi3_ffi::fmi3Float64));

        /// FMI 3.0 `fmi3DoStep`: never returns early and needs no event
        /// handling; `terminateSimulation` after a discarded step.
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard requires.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::too_many_arguments)]
        pub unsafe extern "C" fn fmi3DoStep(
            instance: __fmi3_ffi::fmi3Instance,
            current_communication_point: __fmi3_ffi::fmi3Float64,
            communication_step_size: __fmi3_ffi::fmi3Float64,
            no_set_fmu_state_prior: __fmi3_ffi::fmi3Boolean,
            event_handling_needed: *mut __fmi3_ffi::fmi3Boolean,
            terminate_simulation: *mut __fmi3_ffi::fmi3Boolean,
            early_return: *mut __fmi3_ffi::fmi3Boolean,
            last_successful_time: *mut __fmi3_ffi::fmi3Float64,
        ) -> __fmi3_ffi::fmi3Status {
            unsafe {
                $crate::abi::do_step::<$model>(
                    instance,
                    current_communication_point,
                    communication_step_size,
                    no_set_fmu_state_prior,
                    event_handling_needed,
                    terminate_simulation,
                    early_return,
                    last_successful_time,
                )
            }
        }
        const _: __fmi3_ffi::fmi3DoStepTYPE = Some(fmi3DoStep);
    };

    (@typed $model:ty, $name:ident, $ty:ident, $fn:ident, $value:ty) => {
        /// FMI 3.0 value access by value reference (arrays in row-major
        /// order; `nValues` counts the elements).
        ///
        /// # Safety
        /// `instance` is null or a live instance; `vr` null or `nvr`
        /// elements; `values` null or `n_values` elements.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn $name(
            instance: $crate::ffi::fmi3Instance,
            vr: *const $crate::ffi::fmi3ValueReference,
            nvr: usize,
            values: $value,
            n_values: usize,
        ) -> $crate::ffi::fmi3Status {
            unsafe { $crate::abi::$fn::<$model>(instance, vr, nvr, values, n_values) }
        }
        const _: $crate::ffi::$ty = Some($name);
    };

    (@other $model:ty, $name:ident, $ty:ident, $type_name:literal, $setter:literal, $value:ty) => {
        /// A type this FMU has no variables of: `fmi3OK` for no value
        /// references, else `fmi3Error` with a log line.
        ///
        /// # Safety
        /// `instance` is null or a live instance; `vr` null or `nvr` elements.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn $name(
            instance: $crate::ffi::fmi3Instance,
            vr: *const $crate::ffi::fmi3ValueReference,
            nvr: usize,
            values: $value,
            n_values: usize,
        ) -> $crate::ffi::fmi3Status {
            unsafe {
                $crate::abi::other_type::<$model>(
                    instance,
                    stringify!($name),
                    $type_name,
                    vr,
                    nvr,
                    n_values > 0 && values.is_null(),
                    $setter,
                )
            }
        }
        const _: $crate::ffi::$ty = Some($name);
    };

    (@state $model:ty, $name:ident, $ty:ident, $func:ident, ($($arg:ident : $argty:ty),* $(,)?)) => {
        /// FMU state save and restore (fmu-core's state codec).
        ///
        /// # Safety
        /// Arguments as the FMI 3.0 standard defines them.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn $name(
            instance: $crate::ffi::fmi3Instance,
            $($arg: $argty),*
        ) -> $crate::ffi::fmi3Status {
            unsafe { $crate::abi::$func::<$model>(instance, $($arg),*) }
        }
        const _: $crate::ffi::$ty = Some($name);
    };

    (@unsupported $model:ty, $name:ident, $ty:ident, $why:literal, ($($arg:ident : $argty:ty),* $(,)?)) => {
        /// Not supported by this FMU: returns `fmi3Error` with a log line.
        ///
        /// # Safety
        /// `instance` is null or a live instance of this FMU.
        #[unsafe(no_mangle)]
        #[allow(non_snake_case)]
        pub unsafe extern "C" fn $name(
            instance: $crate::ffi::fmi3Instance,
            $($arg: $argty),*
        ) -> $crate::ffi::fmi3Status {
            unsafe { $crate::abi::unsupported::<$model>(instance, stringify!($name), $why) }
        }
        const _: $crate::ffi::$ty = Some($name);
    };
}
