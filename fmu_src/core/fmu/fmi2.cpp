// The FMI 2.0 co-simulation interface of the native WetCloth unit: every fmi2 function over wc::fmu::Unit
// (unit.hpp).  Nothing escapes as a crash: each call catches what the unit throws and returns fmi2Error
// with the reason logged; errors and warnings always go to the master's logger (debug logging adds
// nothing: the unit has no debug messages).  Model-exchange functions return fmi2Error.
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "fmi2Functions.h"
#include "instance.hpp"

namespace {

using wc::fmu::Outcome;

//: The logger's message is a format string: a '%' of the text must be doubled.
std::string escaped(const std::string& text) {
    std::string out;
    out.reserve(text.size());
    for (char c : text) {
        out += c;
        if (c == '%') out += '%';
    }
    return out;
}

//: FMI 2.0's side of the interface both versions share (instance.hpp).
struct Fmi2 {
    using Status = fmi2Status;
    using Logger = fmi2CallbackLogger;
    using Environment = fmi2ComponentEnvironment;
    static constexpr Status ok = fmi2OK;
    static constexpr Status error = fmi2Error;
    static constexpr std::uint64_t MAGIC = 0x57657443'6c6f7432ull;  // "WetClot2"

    template <class Instance>
    static void emit(const Instance& instance, Status status, const char* category, const std::string& message) {
        instance.logger(instance.environment, instance.name.c_str(), status, category, escaped(message).c_str());
    }
};

using Fmi = wc::fmu::Interface<Fmi2>;
using Instance = Fmi::Instance;

}  // namespace

extern "C" {

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    return Fmi::set_debug_logging(c, "fmi2SetDebugLogging", loggingOn != fmi2False, nCategories, categories);
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation;
    (void)visible;
    const std::string refusal = fmuType == fmi2CoSimulation
                                    ? ""
                                    : "WetCloth is a co-simulation unit; it cannot be instantiated for model exchange";
    return Fmi::instantiate("fmi2Instantiate", instanceName, functions ? functions->componentEnvironment : nullptr,
                            functions ? functions->logger : nullptr, loggingOn != fmi2False, fmuGUID, "GUID",
                            refusal);
}

void fmi2FreeInstance(fmi2Component c) { Fmi::free_instance(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    return Fmi::guarded(c, "fmi2SetupExperiment", [&](Instance& instance) {
        return Fmi::status_of(instance.unit->setup_experiment("fmi2SetupExperiment", startTime,
                                                              stopTimeDefined != fmi2False, stopTime,
                                                              toleranceDefined != fmi2False, tolerance));
    });
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    return Fmi::guarded(c, "fmi2EnterInitializationMode",
                   [&](Instance& instance) {
                       return Fmi::status_of(instance.unit->enter_initialization("fmi2EnterInitializationMode"));
                   });
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    return Fmi::guarded(c, "fmi2ExitInitializationMode",
                   [&](Instance& instance) {
                       return Fmi::status_of(instance.unit->exit_initialization("fmi2ExitInitializationMode"));
                   });
}

fmi2Status fmi2Terminate(fmi2Component c) {
    return Fmi::guarded(c, "fmi2Terminate",
                   [&](Instance& instance) { return Fmi::status_of(instance.unit->terminate("fmi2Terminate")); });
}

fmi2Status fmi2Reset(fmi2Component c) {
    return Fmi::guarded(c, "fmi2Reset", [&](Instance& instance) {
        instance.unit->reset();
        instance.discarded = false;
        return fmi2OK;
    });
}

// ---------------------------------------------------------------------------------------------- getters
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    return Fmi::guarded(c, "fmi2GetReal", [&](Instance& instance) {
        if (nvr == 0) return fmi2OK;
        return Fmi::status_of(instance.unit->get_real(vr, nvr, value, nvr, "fmi2GetReal"));
    });
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    return Fmi::guarded(c, "fmi2GetInteger", [&](Instance& instance) {
        for (size_t k = 0; k < nvr; ++k) {
            std::int64_t v = 0;
            const Outcome outcome = instance.unit->get_integer(vr[k], v, "fmi2GetInteger");
            if (outcome != Outcome::OK) return Fmi::status_of(outcome);
            value[k] = static_cast<fmi2Integer>(v);
        }
        return fmi2OK;
    });
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    (void)value;
    return Fmi::guarded(c, "fmi2GetBoolean", [&](Instance& instance) {
        if (nvr == 0) return fmi2OK;
        Fmi::log(&instance, fmi2Error, "logStatusError",
            "fmi2GetBoolean: the unit has no Boolean variable (value reference " + std::to_string(vr[0]) + ")");
        return fmi2Error;
    });
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    return Fmi::guarded(c, "fmi2GetString", [&](Instance& instance) {
        for (size_t k = 0; k < nvr; ++k) {
            const char* v = nullptr;
            const Outcome outcome = instance.unit->get_string(vr[k], v, "fmi2GetString");
            if (outcome != Outcome::OK) return Fmi::status_of(outcome);
            value[k] = v;
        }
        return fmi2OK;
    });
}

// ---------------------------------------------------------------------------------------------- setters
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    return Fmi::guarded(c, "fmi2SetReal", [&](Instance& instance) {
        Outcome outcome = Outcome::OK;
        for (size_t k = 0; k < nvr; ++k) outcome = wc::fmu::worst(outcome, instance.unit->set_real(vr[k], value[k], "fmi2SetReal"));
        return Fmi::status_of(outcome);
    });
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    return Fmi::guarded(c, "fmi2SetInteger", [&](Instance& instance) {
        Outcome outcome = Outcome::OK;
        for (size_t k = 0; k < nvr; ++k) {
            outcome = wc::fmu::worst(outcome, instance.unit->set_integer(vr[k], value[k], std::to_string(value[k]), "fmi2SetInteger"));
        }
        return Fmi::status_of(outcome);
    });
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    (void)value;
    return Fmi::guarded(c, "fmi2SetBoolean", [&](Instance& instance) {
        if (nvr == 0) return fmi2OK;
        Fmi::log(&instance, fmi2Error, "logStatusError",
            "fmi2SetBoolean: the unit has no Boolean variable (value reference " + std::to_string(vr[0]) + ")");
        return fmi2Error;
    });
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    return Fmi::guarded(c, "fmi2SetString", [&](Instance& instance) {
        Outcome outcome = Outcome::OK;
        for (size_t k = 0; k < nvr; ++k) outcome = wc::fmu::worst(outcome, instance.unit->set_string(vr[k], value[k], "fmi2SetString"));
        return Fmi::status_of(outcome);
    });
}

// ---------------------------------------------------------------------------------------------- FMU states
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    return Fmi::guarded(c, "fmi2GetFMUstate",
                   [&](Instance& instance) { return Fmi::status_of(wc::fmu::get_fmu_state(*instance.unit, FMUstate)); });
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    return Fmi::guarded(c, "fmi2SetFMUstate", [&](Instance& instance) {
        const fmi2Status status = Fmi::status_of(wc::fmu::set_fmu_state(*instance.unit, FMUstate));
        if (status == fmi2OK) instance.discarded = false;
        return status;
    });
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
    return Fmi::guarded(c, "fmi2FreeFMUstate", [&](Instance& instance) {
        return Fmi::status_of(wc::fmu::free_fmu_state(*instance.unit, FMUstate, "fmi2FreeFMUstate"));
    });
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
    return Fmi::guarded(c, "fmi2SerializedFMUstateSize", [&](Instance& instance) {
        return Fmi::status_of(wc::fmu::serialized_state_size(*instance.unit, FMUstate, size, "fmi2SerializedFMUstateSize"));
    });
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    return Fmi::guarded(c, "fmi2SerializeFMUstate", [&](Instance& instance) {
        return Fmi::status_of(wc::fmu::serialize_fmu_state(*instance.unit, FMUstate,
                                                      reinterpret_cast<unsigned char*>(serializedState), size,
                                                      "fmi2SerializeFMUstate"));
    });
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate* FMUstate) {
    return Fmi::guarded(c, "fmi2DeSerializeFMUstate", [&](Instance& instance) {
        return Fmi::status_of(wc::fmu::deserialize_fmu_state(
            *instance.unit, reinterpret_cast<const unsigned char*>(serializedState), size, FMUstate));
    });
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference[], size_t,
                                        const fmi2ValueReference[], size_t, const fmi2Real[], fmi2Real[]) {
    return Fmi::unsupported(c, "fmi2GetDirectionalDerivative");
}

// ---------------------------------------------------------------------------------------------- model exchange
fmi2Status fmi2EnterEventMode(fmi2Component c) { return Fmi::unsupported(c, "fmi2EnterEventMode"); }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo*) { return Fmi::unsupported(c, "fmi2NewDiscreteStates"); }
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { return Fmi::unsupported(c, "fmi2EnterContinuousTimeMode"); }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean, fmi2Boolean*, fmi2Boolean*) {
    return Fmi::unsupported(c, "fmi2CompletedIntegratorStep");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real) { return Fmi::unsupported(c, "fmi2SetTime"); }
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real[], size_t) {
    return Fmi::unsupported(c, "fmi2SetContinuousStates");
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real[], size_t) { return Fmi::unsupported(c, "fmi2GetDerivatives"); }
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real[], size_t) {
    return Fmi::unsupported(c, "fmi2GetEventIndicators");
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real[], size_t) {
    return Fmi::unsupported(c, "fmi2GetContinuousStates");
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real[], size_t) {
    return Fmi::unsupported(c, "fmi2GetNominalsOfContinuousStates");
}

// ---------------------------------------------------------------------------------------------- co-simulation
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                       const fmi2Real[]) {
    return Fmi::unsupported(c, "fmi2SetRealInputDerivatives");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t, const fmi2Integer[],
                                        fmi2Real[]) {
    return Fmi::unsupported(c, "fmi2GetRealOutputDerivatives");
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    return Fmi::guarded(c, "fmi2DoStep", [&](Instance& instance) {
        const Outcome outcome = instance.unit->do_step(currentCommunicationPoint, communicationStepSize);
        instance.discarded = instance.unit->step_failed();
        return Fmi::status_of(outcome);
    });
}

fmi2Status fmi2CancelStep(fmi2Component c) { return Fmi::unsupported(c, "fmi2CancelStep (doStep is never asynchronous)"); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
    (void)s;
    (void)value;
    return Fmi::guarded(c, "fmi2GetStatus", [&](Instance& instance) {
        Fmi::log(&instance, fmi2Discard, "logStatusDiscard",
            "fmi2GetStatus: no status to report (doStep is never asynchronous)");
        return fmi2Discard;
    });
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
    return Fmi::guarded(c, "fmi2GetRealStatus", [&](Instance& instance) {
        if (s != fmi2LastSuccessfulTime || value == nullptr) {
            Fmi::log(&instance, fmi2Discard, "logStatusDiscard", "fmi2GetRealStatus: only fmi2LastSuccessfulTime is known");
            return fmi2Discard;
        }
        *value = instance.unit->time();
        return fmi2OK;
    });
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
    (void)s;
    (void)value;
    return Fmi::guarded(c, "fmi2GetIntegerStatus", [&](Instance& instance) {
        Fmi::log(&instance, fmi2Discard, "logStatusDiscard", "fmi2GetIntegerStatus: no integer status to report");
        return fmi2Discard;
    });
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
    return Fmi::guarded(c, "fmi2GetBooleanStatus", [&](Instance& instance) {
        if (s != fmi2Terminated || value == nullptr) {
            Fmi::log(&instance, fmi2Discard, "logStatusDiscard", "fmi2GetBooleanStatus: only fmi2Terminated is known");
            return fmi2Discard;
        }
        // After a step that failed (a blow-up) the unit stays where it was and asks the master to stop there
        // (a repeated step would fail the same way), until the master restores a state.  A step refused for
        // a pending refused value, or asked at the wrong time, can go on (a valid value set, the right time):
        // not terminated.
        *value = instance.discarded ? fmi2True : fmi2False;
        return fmi2OK;
    });
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
    (void)s;
    (void)value;
    return Fmi::guarded(c, "fmi2GetStringStatus", [&](Instance& instance) {
        Fmi::log(&instance, fmi2Discard, "logStatusDiscard", "fmi2GetStringStatus: no string status to report");
        return fmi2Discard;
    });
}

}  // extern "C"
