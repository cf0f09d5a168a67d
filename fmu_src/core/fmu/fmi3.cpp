// The FMI 3.0 co-simulation interface of the native WetCloth unit: every fmi3 function over wc::fmu::Unit
// (unit.hpp), with the cloth mesh as the array outputs `positions` [ny, nx, 3] and `wetness` [ny, nx], sized by
// the structural parameters nx and ny (UInt64), and a mesh cloth's faces (UInt64) and UVs as constant arrays.
// Nothing escapes as a crash: each call catches what the unit throws and returns fmi3Error with the reason
// logged; errors and warnings always go to the master's logger.
// Model exchange, scheduled execution, event mode, clocks and derivatives return fmi3Error.
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "fmi3Functions.h"
#include "instance.hpp"

namespace {

using wc::fmu::Causality;
using wc::fmu::Outcome;
using wc::fmu::Type;

//: FMI 3.0's side of the interface both versions share (instance.hpp).
struct Fmi3 {
    using Status = fmi3Status;
    using Logger = fmi3LogMessageCallback;
    using Environment = fmi3InstanceEnvironment;
    static constexpr Status ok = fmi3OK;
    static constexpr Status error = fmi3Error;
    static constexpr std::uint64_t MAGIC = 0x57657443'6c6f7433ull;  // "WetClot3"

    template <class Instance>
    static void emit(const Instance& instance, Status status, const char* category, const std::string& message) {
        instance.logger(instance.environment, status, category, message.c_str());
    }
};

using Fmi = wc::fmu::Interface<Fmi3>;
using Instance = Fmi::Instance;

//: A get or set of a type no variable has: fine for no variables, else an error.
fmi3Status no_such_type(fmi3Instance c, const char* function, const char* type, const fmi3ValueReference vrs[],
                        size_t nvr) {
    return Fmi::guarded(c, function, [&](Instance& instance) {
        if (nvr == 0) return fmi3OK;
        Fmi::log(&instance, fmi3Error, "logStatusError",
            std::string(function) + ": the unit has no " + type + " variable (value reference " +
                std::to_string(vrs ? vrs[0] : 0) + ")");
        return fmi3Error;
    });
}

//: Whether vr is an Integer variable of the FMI 3.0 type `structural` (UInt64) or not (Int32); logs if not.
bool integer_of_kind(Instance& instance, fmi3ValueReference vr, bool structural, const char* function) {
    if (vr >= wc::fmu::variable_count()) return true;  // the unit reports the unknown reference
    const wc::fmu::Variable& var = wc::fmu::variables()[vr];
    if (var.type != Type::INTEGER) return true;  // the unit reports the type
    if ((var.causality == Causality::STRUCTURAL_PARAMETER) == structural) return true;
    Fmi::log(&instance, fmi3Error, "logStatusError",
        std::string(function) + ": variable '" + var.name + "' is " + (structural ? "an Int32" : "a UInt64"));
    return false;
}

//: The Int32 variables' values (the UInt64 ones: Unit::get_uint64).
template <class T>
fmi3Status get_integers(fmi3Instance c, const char* function, const fmi3ValueReference vrs[], size_t nvr, T values[],
                        size_t nValues) {
    return Fmi::guarded(c, function, [&](Instance& instance) {
        if (nValues != nvr) {
            Fmi::log(&instance, fmi3Error, "logStatusError", std::string(function) + ": nValues must equal nValueReferences");
            return fmi3Error;
        }
        for (size_t k = 0; k < nvr; ++k) {
            if (!integer_of_kind(instance, vrs[k], false, function)) return fmi3Error;
            std::int64_t v = 0;
            const Outcome outcome = instance.unit->get_integer(vrs[k], v, function);
            if (outcome != Outcome::OK) return Fmi::status_of(outcome);
            values[k] = static_cast<T>(v);
        }
        return fmi3OK;
    });
}

template <class T>
fmi3Status set_integers(fmi3Instance c, const char* function, bool structural, const fmi3ValueReference vrs[],
                        size_t nvr, const T values[], size_t nValues) {
    return Fmi::guarded(c, function, [&](Instance& instance) {
        if (nValues != nvr) {
            Fmi::log(&instance, fmi3Error, "logStatusError", std::string(function) + ": nValues must equal nValueReferences");
            return fmi3Error;
        }
        Outcome outcome = Outcome::OK;
        for (size_t k = 0; k < nvr; ++k) {
            if (!integer_of_kind(instance, vrs[k], structural, function)) {
                outcome = wc::fmu::worst(outcome, Outcome::ERROR);
                continue;
            }
            const T v = values[k];
            const std::int64_t clamped = static_cast<std::uint64_t>(v) > static_cast<std::uint64_t>(
                                                                            std::numeric_limits<std::int64_t>::max()) &&
                                                 v > 0
                                             ? std::numeric_limits<std::int64_t>::max()
                                             : static_cast<std::int64_t>(v);
            outcome = wc::fmu::worst(outcome, instance.unit->set_integer(vrs[k], clamped, std::to_string(v), function));
        }
        return Fmi::status_of(outcome);
    });
}

}  // namespace

extern "C" {

const char* fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    return Fmi::set_debug_logging(instance, "fmi3SetDebugLogging", loggingOn, nCategories, categories);
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String, fmi3String, fmi3String, fmi3Boolean, fmi3Boolean,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    if (logMessage) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateModelExchange: WetCloth is a co-simulation unit only");
    }
    return nullptr;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String, fmi3String, fmi3String, fmi3Boolean, fmi3Boolean,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback,
                                               fmi3LockPreemptionCallback, fmi3UnlockPreemptionCallback) {
    if (logMessage) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: WetCloth is a co-simulation unit only");
    }
    return nullptr;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)resourcePath;
    (void)visible;
    (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    const std::string refusal =
        eventModeUsed ? "the unit has no event mode (hasEventMode is false)"
        : nRequiredIntermediateVariables > 0 ? "the unit provides no intermediate updates"
                                             : "";
    return Fmi::instantiate("fmi3InstantiateCoSimulation", instanceName, instanceEnvironment, logMessage, loggingOn,
                            instantiationToken, "instantiation token", refusal);
}

void fmi3FreeInstance(fmi3Instance c) { Fmi::free_instance(c); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    return Fmi::guarded(c, "fmi3EnterInitializationMode", [&](Instance& instance) {
        const char* function = "fmi3EnterInitializationMode";
        const Outcome outcome = instance.unit->setup_experiment(function, startTime, stopTimeDefined, stopTime,
                                                                toleranceDefined, tolerance);
        if (outcome != Outcome::OK && outcome != Outcome::WARNING) return Fmi::status_of(outcome);
        return Fmi::status_of(wc::fmu::worst(outcome, instance.unit->enter_initialization(function)));
    });
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
    return Fmi::guarded(c, "fmi3ExitInitializationMode",
                   [&](Instance& instance) {
                       return Fmi::status_of(instance.unit->exit_initialization("fmi3ExitInitializationMode"));
                   });
}

fmi3Status fmi3EnterEventMode(fmi3Instance c) { return Fmi::unsupported(c, "fmi3EnterEventMode"); }

fmi3Status fmi3Terminate(fmi3Instance c) {
    return Fmi::guarded(c, "fmi3Terminate",
                   [&](Instance& instance) { return Fmi::status_of(instance.unit->terminate("fmi3Terminate")); });
}

fmi3Status fmi3Reset(fmi3Instance c) {
    return Fmi::guarded(c, "fmi3Reset", [&](Instance& instance) {
        instance.unit->reset();
        return fmi3OK;
    });
}

// ---------------------------------------------------------------------------------------------- getters
fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float64 values[], size_t nValues) {
    return Fmi::guarded(c, "fmi3GetFloat64", [&](Instance& instance) {
        if (nValueReferences == 0 && nValues == 0) return fmi3OK;
        return Fmi::status_of(instance.unit->get_real(valueReferences, nValueReferences, values, nValues, "fmi3GetFloat64"));
    });
}

fmi3Status fmi3GetUInt64(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         fmi3UInt64 values[], size_t nValues) {
    return Fmi::guarded(c, "fmi3GetUInt64", [&](Instance& instance) {
        if (nValueReferences == 0 && nValues == 0) return fmi3OK;
        return Fmi::status_of(instance.unit->get_uint64(valueReferences, nValueReferences, values, nValues, "fmi3GetUInt64"));
    });
}

fmi3Status fmi3GetInt32(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Int32 values[], size_t nValues) {
    return get_integers(c, "fmi3GetInt32", valueReferences, nValueReferences, values, nValues);
}

fmi3Status fmi3GetString(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         fmi3String values[], size_t nValues) {
    return Fmi::guarded(c, "fmi3GetString", [&](Instance& instance) {
        if (nValues != nValueReferences) {
            Fmi::log(&instance, fmi3Error, "logStatusError", "fmi3GetString: nValues must equal nValueReferences");
            return fmi3Error;
        }
        for (size_t k = 0; k < nValueReferences; ++k) {
            const char* v = nullptr;
            const Outcome outcome = instance.unit->get_string(valueReferences[k], v, "fmi3GetString");
            if (outcome != Outcome::OK) return Fmi::status_of(outcome);
            values[k] = v;
        }
        return fmi3OK;
    });
}

#define WETCLOTH_NO_GETTER(Name, T)                                                                             \
    fmi3Status fmi3Get##Name(fmi3Instance c, const fmi3ValueReference vrs[], size_t nvr, T[], size_t) {        \
        return no_such_type(c, "fmi3Get" #Name, #Name, vrs, nvr);                                               \
    }                                                                                                           \
    fmi3Status fmi3Set##Name(fmi3Instance c, const fmi3ValueReference vrs[], size_t nvr, const T[], size_t) {  \
        return no_such_type(c, "fmi3Set" #Name, #Name, vrs, nvr);                                               \
    }
WETCLOTH_NO_GETTER(Float32, fmi3Float32)
WETCLOTH_NO_GETTER(Int8, fmi3Int8)
WETCLOTH_NO_GETTER(UInt8, fmi3UInt8)
WETCLOTH_NO_GETTER(Int16, fmi3Int16)
WETCLOTH_NO_GETTER(UInt16, fmi3UInt16)
WETCLOTH_NO_GETTER(UInt32, fmi3UInt32)
WETCLOTH_NO_GETTER(Int64, fmi3Int64)
WETCLOTH_NO_GETTER(Boolean, fmi3Boolean)
#undef WETCLOTH_NO_GETTER

fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference vrs[], size_t nvr, size_t[], fmi3Binary[], size_t) {
    return no_such_type(c, "fmi3GetBinary", "Binary", vrs, nvr);
}

fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference vrs[], size_t nvr, const size_t[],
                         const fmi3Binary[], size_t) {
    return no_such_type(c, "fmi3SetBinary", "Binary", vrs, nvr);
}

fmi3Status fmi3GetClock(fmi3Instance c, const fmi3ValueReference vrs[], size_t nvr, fmi3Clock[]) {
    return no_such_type(c, "fmi3GetClock", "Clock", vrs, nvr);
}

fmi3Status fmi3SetClock(fmi3Instance c, const fmi3ValueReference vrs[], size_t nvr, const fmi3Clock[]) {
    return no_such_type(c, "fmi3SetClock", "Clock", vrs, nvr);
}

// ---------------------------------------------------------------------------------------------- setters
fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float64 values[], size_t nValues) {
    return Fmi::guarded(c, "fmi3SetFloat64", [&](Instance& instance) {
        if (nValues != nValueReferences) {
            Fmi::log(&instance, fmi3Error, "logStatusError",
                "fmi3SetFloat64: nValues must equal nValueReferences (no array variable can be set)");
            return fmi3Error;
        }
        Outcome outcome = Outcome::OK;
        for (size_t k = 0; k < nValueReferences; ++k) {
            outcome = wc::fmu::worst(outcome, instance.unit->set_real(valueReferences[k], values[k], "fmi3SetFloat64"));
        }
        return Fmi::status_of(outcome);
    });
}

fmi3Status fmi3SetUInt64(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const fmi3UInt64 values[], size_t nValues) {
    return set_integers(c, "fmi3SetUInt64", true, valueReferences, nValueReferences, values, nValues);
}

fmi3Status fmi3SetInt32(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Int32 values[], size_t nValues) {
    return set_integers(c, "fmi3SetInt32", false, valueReferences, nValueReferences, values, nValues);
}

fmi3Status fmi3SetString(fmi3Instance c, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const fmi3String values[], size_t nValues) {
    return Fmi::guarded(c, "fmi3SetString", [&](Instance& instance) {
        if (nValues != nValueReferences) {
            Fmi::log(&instance, fmi3Error, "logStatusError", "fmi3SetString: nValues must equal nValueReferences");
            return fmi3Error;
        }
        Outcome outcome = Outcome::OK;
        for (size_t k = 0; k < nValueReferences; ++k) {
            outcome = wc::fmu::worst(outcome, instance.unit->set_string(valueReferences[k], values[k], "fmi3SetString"));
        }
        return Fmi::status_of(outcome);
    });
}

// ---------------------------------------------------------------------------------------------- dependencies
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference, size_t*) {
    return Fmi::unsupported(c, "fmi3GetNumberOfVariableDependencies");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference, size_t[], fmi3ValueReference[], size_t[],
                                       fmi3DependencyKind[], size_t) {
    return Fmi::unsupported(c, "fmi3GetVariableDependencies");
}

// ---------------------------------------------------------------------------------------------- FMU states
fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState* FMUState) {
    return Fmi::guarded(c, "fmi3GetFMUState",
                   [&](Instance& instance) { return Fmi::status_of(wc::fmu::get_fmu_state(*instance.unit, FMUState)); });
}

fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState FMUState) {
    return Fmi::guarded(c, "fmi3SetFMUState",
                   [&](Instance& instance) { return Fmi::status_of(wc::fmu::set_fmu_state(*instance.unit, FMUState)); });
}

fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState* FMUState) {
    return Fmi::guarded(c, "fmi3FreeFMUState", [&](Instance& instance) {
        return Fmi::status_of(wc::fmu::free_fmu_state(*instance.unit, FMUState, "fmi3FreeFMUState"));
    });
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState FMUState, size_t* size) {
    return Fmi::guarded(c, "fmi3SerializedFMUStateSize", [&](Instance& instance) {
        return Fmi::status_of(wc::fmu::serialized_state_size(*instance.unit, FMUState, size, "fmi3SerializedFMUStateSize"));
    });
}

fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    return Fmi::guarded(c, "fmi3SerializeFMUState", [&](Instance& instance) {
        return Fmi::status_of(wc::fmu::serialize_fmu_state(*instance.unit, FMUState, serializedState, size,
                                                      "fmi3SerializeFMUState"));
    });
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState* FMUState) {
    return Fmi::guarded(c, "fmi3DeserializeFMUState", [&](Instance& instance) {
        return Fmi::status_of(wc::fmu::deserialize_fmu_state(*instance.unit, serializedState, size, FMUState));
    });
}

// ---------------------------------------------------------------------------------------------- unsupported
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference[], size_t,
                                        const fmi3ValueReference[], size_t, const fmi3Float64[], size_t,
                                        fmi3Float64[], size_t) {
    return Fmi::unsupported(c, "fmi3GetDirectionalDerivative");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3ValueReference[],
                                    size_t, const fmi3Float64[], size_t, fmi3Float64[], size_t) {
    return Fmi::unsupported(c, "fmi3GetAdjointDerivative");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance c) {
    return Fmi::guarded(c, "fmi3EnterConfigurationMode", [&](Instance& instance) {
        if (instance.unit->initialized()) {
            instance.unit->error("fmi3EnterConfigurationMode: the unit is initialized; its structural parameters "
                                 "are fixed (fmi3Reset first)");
            return fmi3Error;
        }
        return fmi3OK;
    });
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance c) {
    return Fmi::guarded(c, "fmi3ExitConfigurationMode", [&](Instance&) { return fmi3OK; });
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance c, const fmi3ValueReference[], size_t, fmi3Float64[],
                                  fmi3IntervalQualifier[]) {
    return Fmi::unsupported(c, "fmi3GetIntervalDecimal");
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance c, const fmi3ValueReference[], size_t, fmi3UInt64[], fmi3UInt64[],
                                   fmi3IntervalQualifier[]) {
    return Fmi::unsupported(c, "fmi3GetIntervalFraction");
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance c, const fmi3ValueReference[], size_t, fmi3Float64[]) {
    return Fmi::unsupported(c, "fmi3GetShiftDecimal");
}
fmi3Status fmi3GetShiftFraction(fmi3Instance c, const fmi3ValueReference[], size_t, fmi3UInt64[], fmi3UInt64[]) {
    return Fmi::unsupported(c, "fmi3GetShiftFraction");
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3Float64[]) {
    return Fmi::unsupported(c, "fmi3SetIntervalDecimal");
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3UInt64[],
                                   const fmi3UInt64[]) {
    return Fmi::unsupported(c, "fmi3SetIntervalFraction");
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3Float64[]) {
    return Fmi::unsupported(c, "fmi3SetShiftDecimal");
}
fmi3Status fmi3SetShiftFraction(fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3UInt64[],
                                const fmi3UInt64[]) {
    return Fmi::unsupported(c, "fmi3SetShiftFraction");
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) { return Fmi::unsupported(c, "fmi3EvaluateDiscreteStates"); }
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean*, fmi3Boolean*, fmi3Boolean*, fmi3Boolean*,
                                    fmi3Boolean*, fmi3Float64*) {
    return Fmi::unsupported(c, "fmi3UpdateDiscreteStates");
}
fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) { return Fmi::unsupported(c, "fmi3EnterContinuousTimeMode"); }
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean, fmi3Boolean*, fmi3Boolean*) {
    return Fmi::unsupported(c, "fmi3CompletedIntegratorStep");
}
fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64) { return Fmi::unsupported(c, "fmi3SetTime"); }
fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64[], size_t) {
    return Fmi::unsupported(c, "fmi3SetContinuousStates");
}
fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64[], size_t) {
    return Fmi::unsupported(c, "fmi3GetContinuousStateDerivatives");
}
fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64[], size_t) {
    return Fmi::unsupported(c, "fmi3GetEventIndicators");
}
fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64[], size_t) {
    return Fmi::unsupported(c, "fmi3GetContinuousStates");
}
fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64[], size_t) {
    return Fmi::unsupported(c, "fmi3GetNominalsOfContinuousStates");
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t*) {
    return Fmi::unsupported(c, "fmi3GetNumberOfEventIndicators");
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t*) {
    return Fmi::unsupported(c, "fmi3GetNumberOfContinuousStates");
}
fmi3Status fmi3GetOutputDerivatives(fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3Int32[],
                                    fmi3Float64[], size_t) {
    return Fmi::unsupported(c, "fmi3GetOutputDerivatives");
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance c, fmi3ValueReference, fmi3Float64) {
    return Fmi::unsupported(c, "fmi3ActivateModelPartition");
}

fmi3Status fmi3EnterStepMode(fmi3Instance c) {
    return Fmi::guarded(c, "fmi3EnterStepMode", [&](Instance& instance) {
        if (!instance.unit->initialized()) {
            instance.unit->error("fmi3EnterStepMode before the unit was initialized");
            return fmi3Error;
        }
        return fmi3OK;
    });
}

// ---------------------------------------------------------------------------------------------- co-simulation
fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* eventHandlingNeeded,
                      fmi3Boolean* terminateSimulation, fmi3Boolean* earlyReturn, fmi3Float64* lastSuccessfulTime) {
    (void)noSetFMUStatePriorToCurrentPoint;
    return Fmi::guarded(c, "fmi3DoStep", [&](Instance& instance) {
        const Outcome outcome = instance.unit->do_step(currentCommunicationPoint, communicationStepSize);
        if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
        if (earlyReturn) *earlyReturn = fmi3False;
        // After a step that failed (a blow-up) the unit stays where it was and asks the master to stop there;
        // a step refused for a pending refused value or the wrong time can go on.
        if (terminateSimulation) *terminateSimulation = instance.unit->step_failed() ? fmi3True : fmi3False;
        if (lastSuccessfulTime) *lastSuccessfulTime = instance.unit->time();
        return Fmi::status_of(outcome);
    });
}

}  // extern "C"
