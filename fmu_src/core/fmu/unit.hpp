// The native WetCloth unit, whatever its FMI version: a port of wetcloth/fmu/unit.py over wc::Simulation
// (fmi2.cpp and fmi3.cpp only translate FMI calls into these methods).
//
// The variables are the generated table (wetcloth_fmu_variables.cpp, written by wetcloth.fmu.native
// from wetcloth.fmu.vocabulary): the same names, value references, ranges and messages as the pythonfmu
// units.  What differs: every refusal is an FMI error status (never Fatal: the instance stays usable), a
// set call that is refused returns it at once (and, as in unit.py, the refusal stays pending: the
// initialization, or every doStep, is refused until a valid value is set), and the unit writes no mesh
// frames (mesh_output_dir must stay empty).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "wetcloth/model.hpp"

namespace wc::fmu {

//: FMI statuses, in the order of fmi2Status and fmi3Status.
enum class Outcome : int { OK = 0, WARNING = 1, DISCARD = 2, ERROR = 3, FATAL = 4 };

enum class Type : int { REAL, INTEGER, STRING, UINT64 };  // UINT64: FMI 3.0's constant array of faces
enum class Causality : int { PARAMETER, STRUCTURAL_PARAMETER, INPUT, OUTPUT, INDEPENDENT };
//: What a variable reads and writes: a Scene field, a number field of a collider built in (--scene), an
//: FMU-only parameter, an output slot of record_outputs, a mesh array output, a constant array output (a mesh
//: cloth's faces and UVs, built in: CONSTANT_FACES, CONSTANT_UV) or the time.
enum class Role : int {
    SCENE, COLLIDER, MESH_OUTPUT_DIR, MESH_FORMAT, OUTPUT, STEP_ERROR, POSITIONS, WETNESS, FACES, UV, TIME
};

//: One variable of the generated table (its index is its value reference).
struct Variable {
    const char* name;
    Type type;
    Causality causality;
    Role role;
    double Scene::*real;  // Scene field (Real), else null
    Index Scene::*integer;  // Scene field (Integer, or a string choice's code), else null
    Index slot;             // OUTPUT: slot of the outputs' row; COLLIDER: place in the colliders' rows
    double start;           // Real and Integer start value
    const char* start_text; // String start value
    bool ranged;            // min and max apply
    double lo, hi;
    bool lo_open;
    const char* range;      // describe_range's text, e.g. "0 < width <= 100 m" or "one of 'ply', 'obj'"
    const char* const* choices;  // strings with a list of allowed values
    Index choice_count;
};

//: constexpr text equality (the generated table's static checks).
constexpr bool same_text(const char* a, const char* b) {
    while (*a != '\0' && *a == *b) {
        ++a;
        ++b;
    }
    return *a == *b;
}

//: The generated table, defined in the unit's generated source (wetcloth_fmu_variables.cpp).
const Variable* variables();
std::size_t variable_count();
const char* instantiation_token();
int fmi_version();

//: difflib.get_close_matches(word, choices, n=1): the closest choice with a ratio of at least 0.6, or null.
const char* close_match(const std::string& word, const char* const* choices, Index count);

//: A serialized FMU state this unit refuses (the message says why).
//: `text` as valid UTF-8 for the log: every byte outside a well-formed UTF-8 sequence written as \xNN.
std::string valid_text(const std::string& text);

struct StateError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

//: One instance's values, simulation and life cycle.
class Unit {
public:
    //: log(status, category, message) receives every error and warning (the caller passes them on).
    using Log = std::function<void(Outcome, const char*, const std::string&)>;

    Unit(std::string instance_name, Log log);
    const std::string& instance_name() const { return name_; }

    // ---------------------------------------------------------------- variables
    //: Set one variable (type-checked against the table); a refused value is logged, stays pending and
    //: returns ERROR.  `text` is the value as a message shows it (Python's repr).
    Outcome set_real(std::uint64_t vr, double value, const char* function);
    Outcome set_integer(std::uint64_t vr, std::int64_t value, const std::string& text, const char* function);
    Outcome set_string(std::uint64_t vr, const char* value, const char* function);
    //: Read variables: Reals (with FMI 3.0's arrays, values[n_values] in order), Integers, Strings.
    Outcome get_real(const std::uint32_t* vrs, std::size_t nvr, double* values, std::size_t n_values,
                     const char* function);
    Outcome get_integer(std::uint64_t vr, std::int64_t& value, const char* function);
    //: FMI 3.0's UInt64 variables: the structural parameters and the faces (values[n_values] in order).
    Outcome get_uint64(const std::uint32_t* vrs, std::size_t nvr, std::uint64_t* values, std::size_t n_values,
                       const char* function);
    Outcome get_string(std::uint64_t vr, const char*& value, const char* function);
    //: The table's entry of vr, or null (logged) if there is none.
    const Variable* variable(std::uint64_t vr, const char* function);

    // ---------------------------------------------------------------- life cycle
    //: The experiment (fmi2SetupExperiment, fmi3EnterInitializationMode, named by `function`): only in the
    //: instantiated state; a defined stop time must not lie before the start time; a defined tolerance must
    //: be a number > 0 (else ERROR).  The unit's accuracy is its own parameter `tolerance`'s: the first
    //: tolerance the master defines is answered with a logged warning saying so (WARNING), later ones
    //: pass silently (OK).
    Outcome setup_experiment(const char* function, double start_time, bool stop_defined, double stop_time,
                             bool tolerance_defined = false, double tolerance = 0.0);
    Outcome enter_initialization(const char* function);
    Outcome exit_initialization(const char* function);
    //: doStep: OK, DISCARD (the unit stays at current_time, message logged) or ERROR (a call the master
    //: must not make: nothing changes).  A doStep from another time than the unit's is refused for that
    //: first, then one while a refused value is pending.
    Outcome do_step(double current_time, double step_size);
    //: Whether the last doStep failed (a blow-up; or a failure the unit could not go back from): the run
    //: cannot go on from there, and the unit asks the master to stop (fmi2Terminated, fmi3DoStep's
    //: terminateSimulation).  A step refused for a pending value or the wrong time can go on: false.
    bool step_failed() const { return step_failed_; }
    Outcome terminate(const char* function);
    void reset();
    bool initialized() const { return initialized_; }
    //: The master's time (s) of the current state.
    double time() const;

    // ---------------------------------------------------------------- FMU states
    //: The whole unit (values, pending refusals, clock, simulation) as bytes.
    std::vector<unsigned char> state() const;
    //: StateError unless `bytes` is a state of a unit like this one (format, checksum, valid values).
    static void check_state(const std::vector<unsigned char>& bytes);
    //: Return to a state: OK, or ERROR (logged) with the unit unchanged.
    Outcome set_state(const std::vector<unsigned char>& bytes);

    //: Log an error (also used by the FMI layers for their own refusals).
    void error(const std::string& message) const { log_(Outcome::ERROR, "logStatusError", message); }
    //: OK where the variables asked for filled exactly the n_values values (at of them); else ERROR, logged.
    Outcome all_values_filled(std::size_t at, std::size_t n_values, const char* function) const;
    void warning(const std::string& message) const { log_(Outcome::WARNING, "logStatusWarning", message); }

private:
    void apply_starts();
    Simulation& simulation();  // the running one, or the preview of the current values
    void changed();             // the outputs read so far are stale
    //: The FMI state the unit is in, as messages name it ("instantiated", "initialization mode", ...).
    const char* phase() const;
    //: ERROR, logged: `function` may not be called in the current state, only in `allowed`.
    Outcome refuse_call(const char* function, const char* allowed) const;
    //: The variable vr if the master may set it with this type (else logged, null).
    const Variable* settable(std::uint64_t vr, Type type, const char* function);
    //: A refused value (unit.py's set_value): logged, pending, ERROR; an accepted one clears its refusal.
    Outcome refuse(const Variable& var, std::uint64_t vr, const std::string& message);
    Outcome accept(std::uint64_t vr);
    std::string current_text(const Variable& var) const;
    void pending(std::uint64_t vr, const std::string& message);
    void clear_pending(std::uint64_t vr);

    std::string name_;
    Log log_;
    Scene values_;
    std::vector<double> colliders_;  // the colliders' fields as the variables hold them, in the rows' layout
    std::string mesh_output_dir_, mesh_format_;
    std::vector<std::pair<std::uint64_t, std::string>> refused_;  // value reference -> message, in order
    bool initialized_ = false, terminated_ = false, clock_set_ = false;
    bool entered_ = false;  // in initialization mode (entered, not yet left)
    bool step_failed_ = false;      // the last doStep failed (step_failed)
    bool tolerance_noted_ = false;  // the warning that the master's tolerance is not used was logged
    double start_time_ = 0.0;
    bool stop_defined_ = false;
    double stop_time_ = 0.0;  // s, the experiment's stop time where stop_defined_: no step ends beyond it
    std::unique_ptr<Simulation> sim_, preview_;
    Checkpoint before_;  // each doStep's start, to go back to after a failed step
    double outputs_[8] = {};
    bool outputs_valid_ = false;
    std::vector<double> mesh_;
};

//: The FMU state calls of both FMI versions over one unit (`function` names the call in messages).  A
//: state object holds the bytes of Unit::state; objects are shared by all instances of the process, and
//: any other pointer is refused with an error.  GetFMUstate: a new object in *state, or *state updated;
//: SetFMUstate: the unit returns to it (nothing changes when refused); FreeFMUstate: *state deleted and
//: nulled; SerializedFMUstateSize, SerializeFMUstate: its bytes; DeSerializeFMUstate: checked bytes into
//: a new object in *state, or *state updated.
Outcome get_fmu_state(Unit& unit, void** state);
Outcome set_fmu_state(Unit& unit, void* state);
Outcome free_fmu_state(Unit& unit, void** state, const char* function);
Outcome serialized_state_size(Unit& unit, void* state, std::size_t* size, const char* function);
Outcome serialize_fmu_state(Unit& unit, void* state, unsigned char* out, std::size_t size, const char* function);
Outcome deserialize_fmu_state(Unit& unit, const unsigned char* data, std::size_t size, void** state);

}  // namespace wc::fmu
