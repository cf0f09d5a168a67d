// What the FMI 2.0 and FMI 3.0 interfaces of the native unit (fmi2.cpp, fmi3.cpp) share: an instance
// of the unit with the master's logger, and the guard every call runs through, so that nothing the unit
// throws reaches the master: the call returns the version's error status with the reason logged.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>

#include "unit.hpp"

namespace wc::fmu {

//: The worse of two outcomes.
inline Outcome worst(Outcome a, Outcome b) { return static_cast<int>(b) > static_cast<int>(a) ? b : a; }

//: The calls both FMI versions make alike.  `Version` gives the version's `Status` with its `ok` and
//: `error` values, the `Logger` and `Environment` types, the instances' `MAGIC`, and `emit(instance,
//: status, category, message)`, which calls the master's logger.
template <class Version>
struct Interface {
    using Status = typename Version::Status;

    //: One instance: the master's name for it, its logger and the unit; `magic` tells a live instance
    //: from a stray or freed pointer.
    struct Instance {
        std::uint64_t magic = Version::MAGIC;
        std::string name;
        typename Version::Environment environment = nullptr;
        typename Version::Logger logger = nullptr;
        bool logging_on = false;
        bool discarded = false;  // the last doStep failed (a blow-up): the unit asks the master to stop there
        std::unique_ptr<Unit> unit;
    };

    static Status status_of(Outcome outcome) { return static_cast<Status>(outcome); }

    static void log(const Instance* instance, Status status, const char* category, const std::string& message) {
        if (instance == nullptr || instance->logger == nullptr) return;
        Version::emit(*instance, status, category, valid_text(message));
    }

    static Instance* instance_of(void* c) {
        auto* instance = static_cast<Instance*>(c);
        return instance != nullptr && instance->magic == Version::MAGIC ? instance : nullptr;
    }

    //: Run `body` (returning Status) for a valid instance; whatever it throws is logged as an error.
    template <class Body>
    static Status guarded(void* c, const char* function, Body&& body) {
        Instance* instance = instance_of(c);
        if (instance == nullptr) return Version::error;  // not an instance of this unit: nothing to log through
        try {
            return body(*instance);
        } catch (const std::bad_alloc&) {
            log(instance, Version::error, "logStatusError", std::string(function) + ": out of memory");
        } catch (const std::exception& exc) {
            log(instance, Version::error, "logStatusError", std::string(function) + " failed: " + exc.what());
        } catch (...) {
            log(instance, Version::error, "logStatusError", std::string(function) + " failed");
        }
        return Version::error;
    }

    static Status unsupported(void* c, const char* function) {
        return guarded(c, function, [&](Instance& instance) {
            log(&instance, Version::error, "logStatusError",
                std::string(function) + " is not supported: WetCloth is a co-simulation unit without it");
            return Version::error;
        });
    }

    //: SetDebugLogging: every category named must be one of the unit's.
    static Status set_debug_logging(void* c, const char* function, bool on, std::size_t n_categories,
                                    const char* const categories[]) {
        return guarded(c, function, [&](Instance& instance) {
            static const char* const known[] = {"logStatusWarning", "logStatusDiscard", "logStatusError",
                                                "logStatusFatal", "logAll"};
            for (std::size_t k = 0; k < n_categories; ++k) {
                bool found = false;
                for (const char* name : known) found = found || (categories[k] && std::strcmp(categories[k], name) == 0);
                if (!found) {
                    log(&instance, Version::error, "logStatusError",
                        std::string(function) + ": unknown log category '" + (categories[k] ? categories[k] : "") +
                            "'; the unit has logStatusWarning, logStatusDiscard, logStatusError, logStatusFatal, logAll");
                    return Version::error;
                }
            }
            instance.logging_on = on;
            return Version::ok;
        });
    }

    //: A new instance, or null with the reason logged: `refusal` (the version's own checks; empty if
    //: none), a `token` that is not this build's (`token_name`: what the version calls it), or a unit that
    //: could not be made.
    static Instance* instantiate(const char* function, const char* name, typename Version::Environment environment,
                                 typename Version::Logger logger, bool logging_on, const char* token,
                                 const char* token_name, const std::string& refusal) {
        Instance probe;
        probe.name = name ? name : "";
        probe.environment = environment;
        probe.logger = logger;
        try {
            if (!refusal.empty()) {
                log(&probe, Version::error, "logStatusError", std::string(function) + ": " + refusal);
                return nullptr;
            }
            if (token == nullptr || std::strcmp(token, instantiation_token()) != 0) {
                log(&probe, Version::error, "logStatusError",
                    std::string(function) + ": the " + token_name + " " + (token ? token : "(none)") +
                        " is not this binary's (" + instantiation_token() +
                        "): the model description belongs to another build of the unit");
                return nullptr;
            }
            auto owned = std::make_unique<Instance>();
            Instance* instance = owned.get();
            instance->name = probe.name;
            instance->environment = environment;
            instance->logger = logger;
            instance->logging_on = logging_on;
            instance->unit = std::make_unique<Unit>(
                instance->name, [instance](Outcome outcome, const char* category, const std::string& message) {
                    log(instance, status_of(outcome), category, message);
                });
            return owned.release();
        } catch (const std::exception& exc) {
            log(&probe, Version::error, "logStatusError", std::string(function) + " failed: " + exc.what());
        } catch (...) {
            log(&probe, Version::error, "logStatusError", std::string(function) + " failed");
        }
        return nullptr;
    }

    static void free_instance(void* c) {
        Instance* instance = instance_of(c);
        if (instance == nullptr) return;
        instance->magic = 0;
        delete instance;
    }
};

}  // namespace wc::fmu
