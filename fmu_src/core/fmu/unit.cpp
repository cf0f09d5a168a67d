// The native WetCloth unit (unit.hpp): a port of wetcloth/fmu/unit.py and the checks of
// wetcloth/fmu/checkpoint.py over wc::Simulation.
#include "unit.hpp"

#include <algorithm>
#include <array>
#include <type_traits>
#include <unordered_set>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <new>
#include <stdexcept>

#include "wetcloth/byte_record.hpp"
#include "wetcloth/stepping.hpp"
#include "unit_data.hpp"  // defined in the unit's generated source, with the variable table

namespace wc::fmu {

namespace {

//: Relative tolerance when matching the master's communication time with the unit's (unit.py).
constexpr double TIME_TOLERANCE = 1e-9;

//: A ParameterError's text: "parameter 'name': message", or "parameter 'name' is ..." (errors.line).
std::string parameter_error(const char* name, const std::string& message) {
    return std::string("parameter '") + name + (message.rfind("is ", 0) == 0 ? "' " : "': ") + message;
}

//: scene.check_value for a number: finite and within the range.
void check_number(const Variable& var, double value, const std::string& text) {
    if (!std::isfinite(value)) {
        throw std::invalid_argument(parameter_error(var.name, text + " is not a finite number; allowed: " + var.range));
    }
    const bool below = var.lo_open ? value <= var.lo : value < var.lo;
    if (below || value > var.hi) {
        throw std::invalid_argument(parameter_error(var.name, text + " is out of range; allowed: " + var.range));
    }
}

//: The code of a string choice, or -1.
Index choice_code(const Variable& var, const char* value) {
    for (Index k = 0; k < var.choice_count; ++k) {
        if (std::strcmp(var.choices[k], value) == 0) return k;
    }
    return -1;
}

//: vocabulary.check_variable for a string; the choice's code (scene fields) or 0.
Index check_string(const Variable& var, const char* value) {
    if (value == nullptr) {
        throw std::invalid_argument(parameter_error(var.name, std::string("expected a string, got None; allowed: ") +
                                                                  (var.range ? var.range : "a text")));
    }
    if (var.role == Role::MESH_OUTPUT_DIR) {
        if (value[0] != '\0') {
            throw std::invalid_argument(parameter_error(
                var.name, py_repr(std::string_view(value)) +
                              " is not allowed: this unit (the native WetCloth) writes no mesh frames; allowed: '' "
                              "(empty). The Python unit, built by `wetcloth build-fmu`, writes them."));
        }
        return 0;
    }
    const Index code = choice_code(var, value);
    if (code < 0) {
        std::string hint;
        if (var.role == Role::SCENE) {
            if (const char* close = close_match(value, var.choices, var.choice_count)) {
                hint = " (did you mean " + py_repr(std::string_view(close)) + "?)";
            }
        }
        throw std::invalid_argument(parameter_error(
            var.name, py_repr(std::string_view(value)) + " is not allowed" + hint + "; allowed: " + var.range));
    }
    return code;
}

//: The length of the well-formed UTF-8 sequence at text[at] (1 to 4), or 0 if there is none.
std::size_t utf8_length(const std::string& text, std::size_t at) {
    const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(k < text.size() ? text[k] : 0); };
    const unsigned char lead = byte(at);
    if (lead < 0x80) return 1;
    // The second byte's range after each lead (Unicode's Table 3-7: no overlong forms, surrogates or > U+10FFFF).
    unsigned char lo = 0x80, hi = 0xBF;
    std::size_t length = 0;
    if (lead >= 0xC2 && lead <= 0xDF) {
        length = 2;
    } else if (lead >= 0xE0 && lead <= 0xEF) {
        length = 3;
        lo = lead == 0xE0 ? 0xA0 : 0x80;
        hi = lead == 0xED ? 0x9F : 0xBF;
    } else if (lead >= 0xF0 && lead <= 0xF4) {
        length = 4;
        lo = lead == 0xF0 ? 0x90 : 0x80;
        hi = lead == 0xF4 ? 0x8F : 0xBF;
    }
    if (length == 0 || byte(at + 1) < lo || byte(at + 1) > hi) return 0;
    for (std::size_t k = 2; k < length; ++k) {
        if (byte(at + k) < 0x80 || byte(at + k) > 0xBF) return 0;
    }
    return length;
}

const char* type_name(Type type) {
    switch (type) {
        case Type::REAL: return fmi_version() == 2 ? "Real" : "Float64";
        case Type::INTEGER: return fmi_version() == 2 ? "Integer" : "UInt64";
        case Type::UINT64: return "UInt64";
        default: return "String";
    }
}

Scene start_scene() {
    Scene scene;
    for (std::size_t vr = 0; vr < variable_count(); ++vr) {
        const Variable& var = variables()[vr];
        if (var.role != Role::SCENE) continue;
        if (var.real) scene.*var.real = var.start;
        if (var.integer) {
            scene.*var.integer = var.type == Type::STRING ? choice_code(var, var.start_text)
                                                          : static_cast<Index>(var.start);
        }
    }
    return scene;
}

//: The colliders' fields as the unit starts with them (the collider variables' start values), in the rows'
//: layout: the rows built in (shape codes) with every number field at its start value.
std::vector<double> start_colliders() {
    std::vector<double> fields(SCENE_COLLIDERS, SCENE_COLLIDERS + SCENE_COLLIDERS_SIZE);
    for (std::size_t vr = 0; vr < variable_count(); ++vr) {
        const Variable& var = variables()[vr];
        if (var.role == Role::COLLIDER) fields[static_cast<std::size_t>(var.slot)] = var.start;
    }
    return fields;
}

//: The core's collider rows of the colliders' fields (Collider.row(): the normal made unit; a mesh collider's
//: radius column keeps its mesh's index, built in).
std::vector<double> collider_rows(const std::vector<double>& fields) {
    std::vector<double> rows(fields);
    for (std::size_t at = 0; at < rows.size(); at += COLLIDER_COLUMNS) {
        double* row = rows.data() + at;
        if (row[C_SHAPE] == MESH) row[C_RADIUS] = SCENE_COLLIDERS[at + C_RADIUS];
        const double norm = std::sqrt(row[C_NORMAL_X] * row[C_NORMAL_X] + row[C_NORMAL_Y] * row[C_NORMAL_Y] +
                                      row[C_NORMAL_Z] * row[C_NORMAL_Z]);
        for (Index c = C_NORMAL_X; c <= C_NORMAL_Z; ++c) row[c] = row[c] / norm;
    }
    return rows;
}

//: What is wrong with the colliders' fields as a whole (scene._checked_colliders: a plane's normal that is
//: zero), or "".
std::string collider_problem(const std::vector<double>& fields) {
    for (std::size_t at = 0; at < fields.size(); at += COLLIDER_COLUMNS) {
        const double* row = fields.data() + at;
        if (row[C_SHAPE] == PLANE && row[C_NORMAL_X] == 0.0 && row[C_NORMAL_Y] == 0.0 && row[C_NORMAL_Z] == 0.0) {
            return "parameter 'collider" + std::to_string(at / COLLIDER_COLUMNS + 1) +
                   "_normal_z': a plane's normal is zero; allowed: a nonzero (normal_x, normal_y, normal_z)";
        }
    }
    return "";
}

template <class T>
std::vector<T> vector_of(const T* values, std::size_t size) {
    return std::vector<T>(values, values + size);
}

//: The cloth from a mesh file built into the unit (native_mesh.py's arrays), or null: the nx x ny grid.
const std::shared_ptr<const ClothMesh>& built_in_cloth() {
    static const std::shared_ptr<const ClothMesh> cloth = []() -> std::shared_ptr<const ClothMesh> {
        if (!CLOTH_MESH) return nullptr;
        auto m = std::make_shared<ClothMesh>();
        m->source = CLOTH_SOURCE;
        m->n = CLOTH_COUNTS[0];
        m->pair_tension_count = CLOTH_COUNTS[1];
        m->kd = CLOTH_COUNTS[2];
        m->marker_size = CLOTH_COUNTS[3];
        m->bends = CLOTH_COUNTS[4] != 0;
        std::copy(CLOTH_SCALARS, CLOTH_SCALARS + 3, m->centre);
        m->size = CLOTH_SCALARS[3];
        m->rest_gap = CLOTH_SCALARS[4];
        m->typical_gap = CLOTH_SCALARS[5];
        m->least_margin = CLOTH_SCALARS[6];
        m->hierarchy_stretch_stiffness = CLOTH_SCALARS[7];
        m->grid_width = CLOTH_SCALARS[8];
        m->grid_length = CLOTH_SCALARS[9];
        m->grid_nx = CLOTH_COUNTS[5];
        m->grid_ny = CLOTH_COUNTS[6];
        m->pair_buckling_count = CLOTH_COUNTS[7];
        m->hinged_grid = CLOTH_COUNTS[8] != 0;
        m->rest_pos = vector_of(CLOTH_REST_POS, CLOTH_REST_POS_SIZE);
        m->rest_xy = vector_of(CLOTH_REST_XY, CLOTH_REST_XY_SIZE);
        m->area = vector_of(CLOTH_AREA, CLOTH_AREA_SIZE);
        m->pairs = vector_of(CLOTH_PAIRS, CLOTH_PAIRS_SIZE);
        m->pair_rest = vector_of(CLOTH_PAIR_REST, CLOTH_PAIR_REST_SIZE);
        m->pair_shape = vector_of(CLOTH_PAIR_SHAPE, CLOTH_PAIR_SHAPE_SIZE);
        m->pair_kind = vector_of(CLOTH_PAIR_KIND, CLOTH_PAIR_KIND_SIZE);
        m->triangles = vector_of(CLOTH_TRIANGLES, CLOTH_TRIANGLES_SIZE);
        m->corner_shares = vector_of(CLOTH_CORNER_SHARES, CLOTH_CORNER_SHARES_SIZE);
        m->order = vector_of(CLOTH_ORDER, CLOTH_ORDER_SIZE);
        m->rank = vector_of(CLOTH_RANK, CLOTH_RANK_SIZE);
        m->levels = vector_of(CLOTH_LEVELS, CLOTH_LEVELS_SIZE);
        m->a_start = vector_of(CLOTH_A_START, CLOTH_A_START_SIZE);
        m->a_column = vector_of(CLOTH_A_COLUMN, CLOTH_A_COLUMN_SIZE);
        m->diagonal = vector_of(CLOTH_DIAGONAL, CLOTH_DIAGONAL_SIZE);
        m->p_start = vector_of(CLOTH_P_START, CLOTH_P_START_SIZE);
        m->p_column = vector_of(CLOTH_P_COLUMN, CLOTH_P_COLUMN_SIZE);
        m->p_value = vector_of(CLOTH_P_VALUE, CLOTH_P_VALUE_SIZE);
        m->r_start = vector_of(CLOTH_R_START, CLOTH_R_START_SIZE);
        m->r_column = vector_of(CLOTH_R_COLUMN, CLOTH_R_COLUMN_SIZE);
        m->r_value = vector_of(CLOTH_R_VALUE, CLOTH_R_VALUE_SIZE);
        m->spring_entries = vector_of(CLOTH_SPRING_ENTRIES, CLOTH_SPRING_ENTRIES_SIZE);
        return m;
    }();
    return cloth;
}

//: The pins by pinned_vertices built into the unit (native_mesh.py's), or null: none.
const std::shared_ptr<const Pins>& built_in_pins() {
    static const std::shared_ptr<const Pins> pins = []() -> std::shared_ptr<const Pins> {
        if (!PINS) return nullptr;
        auto p = std::make_shared<Pins>();
        p->box = PIN_BOX;
        std::copy(PIN_CORNERS, PIN_CORNERS + 6, p->corners);
        p->attribute = vector_of(PIN_ATTRIBUTE, PIN_ATTRIBUTE_SIZE);
        p->text = PIN_TEXTS[0];
        p->allowed = PIN_TEXTS[1];
        return p;
    }();
    return pins;
}

//: scene_problem with the unit's cloth and pins.
std::string unit_scene_problem(const Scene& scene) {
    return scene_problem(scene, built_in_cloth().get(), built_in_pins().get());
}

//: The scene's colliders (with their fields `colliders`), grip keys and cloth built into the unit
//: (build-fmu --native --scene; none without).
Fixtures scene_fixtures(const std::vector<double>& colliders) {
    Fixtures f;
    f.colliders = collider_rows(colliders);
    f.mesh_headers.assign(SCENE_MESH_HEADERS, SCENE_MESH_HEADERS + SCENE_MESH_HEADERS_SIZE);
    f.mesh_vertices.assign(SCENE_MESH_VERTICES, SCENE_MESH_VERTICES + SCENE_MESH_VERTICES_SIZE);
    f.face_normals.assign(SCENE_FACE_NORMALS, SCENE_FACE_NORMALS + SCENE_FACE_NORMALS_SIZE);
    f.edge_normals.assign(SCENE_EDGE_NORMALS, SCENE_EDGE_NORMALS + SCENE_EDGE_NORMALS_SIZE);
    f.vertex_normals.assign(SCENE_VERTEX_NORMALS, SCENE_VERTEX_NORMALS + SCENE_VERTEX_NORMALS_SIZE);
    f.mesh_triangles.assign(SCENE_MESH_TRIANGLES, SCENE_MESH_TRIANGLES + SCENE_MESH_TRIANGLES_SIZE);
    f.cell_start.assign(SCENE_CELL_START, SCENE_CELL_START + SCENE_CELL_START_SIZE);
    f.cell_items.assign(SCENE_CELL_ITEMS, SCENE_CELL_ITEMS + SCENE_CELL_ITEMS_SIZE);
    f.grip_keys.assign(SCENE_GRIP_KEYS, SCENE_GRIP_KEYS + SCENE_GRIP_KEYS_SIZE);
    f.collider_keys.assign(SCENE_COLLIDER_KEYS, SCENE_COLLIDER_KEYS + SCENE_COLLIDER_KEYS_SIZE);
    f.collider_key_numbers.assign(SCENE_COLLIDER_KEY_NUMBERS,
                                  SCENE_COLLIDER_KEY_NUMBERS + SCENE_COLLIDER_KEY_NUMBERS_SIZE);
    f.cloth_mesh = built_in_cloth();
    f.pins = built_in_pins();
    return f;
}

//: The simulation of `scene` with the unit's fixtures, its colliders' fields `colliders` (std::invalid_argument
//: as Simulation's).
std::unique_ptr<Simulation> new_simulation(const Scene& scene, const std::vector<double>& colliders) {
    return std::make_unique<Simulation>(scene, scene_fixtures(colliders));
}

// ------------------------------------------------------------------------------ state bytes
constexpr char STATE_MAGIC[] = "wetcloth-native-fmu-state\n";
constexpr std::size_t MAGIC_SIZE = sizeof(STATE_MAGIC) - 1;
constexpr std::uint32_t STATE_VERSION = 1;

//: Whether two scenes hold the same values (Python's Scene equality).
bool same_scene(const Scene& a, const Scene& b) {
    std::vector<double> x, y;
    for_each_field(a, [&](const char*, const auto& v) { x.push_back(static_cast<double>(v)); });
    for_each_field(b, [&](const char*, const auto& v) { y.push_back(static_cast<double>(v)); });
    return x == y;
}

//: A parsed unit state (checkpoint.Checkpoint).
struct Parsed {
    Scene values;
    std::vector<double> colliders;
    std::string mesh_output_dir, mesh_format;
    std::vector<std::pair<std::uint64_t, std::string>> refused;
    bool initialized = false, clock_set = false;
    double start_time = 0.0;
    Checkpoint simulation;
};

Parsed parse(const std::vector<unsigned char>& bytes) {
    if (bytes.size() < MAGIC_SIZE + 12 || std::memcmp(bytes.data(), STATE_MAGIC, MAGIC_SIZE) != 0) {
        throw StateError("not a serialized state of a native WetCloth unit (" + std::to_string(bytes.size()) +
                         " bytes without its header)");
    }
    ByteReader<StateError> in{bytes.data(), bytes.size(), MAGIC_SIZE, "serialized WetCloth FMU state is truncated"};
    const auto version = in.get<std::uint32_t>();
    if (version != STATE_VERSION) {
        throw StateError("serialized WetCloth FMU state of format version " + std::to_string(version) +
                         "; this unit reads version " + std::to_string(STATE_VERSION));
    }
    const auto checksum = in.get<std::uint64_t>();
    if (!in.body_matches(checksum)) {
        throw StateError("serialized WetCloth FMU state is corrupt or truncated (its checksum does not match)");
    }
    Parsed p;
    const auto count = in.get<std::uint64_t>();
    if (count != variable_count()) {
        throw StateError("the state is of a unit with other variables (" + std::to_string(count) + ", this unit has " +
                         std::to_string(variable_count()) + ")");
    }
    for_each_field(p.values, [&](const char*, auto& v) { v = in.get<std::remove_reference_t<decltype(v)>>(); });
    p.colliders = start_colliders();
    for (double& v : p.colliders) v = in.get<double>();
    p.mesh_output_dir = in.text();
    p.mesh_format = in.text();
    const auto refusals = in.get<std::uint64_t>();
    if (refusals > variable_count()) throw StateError("serialized WetCloth FMU state is malformed (refusals)");
    for (std::uint64_t k = 0; k < refusals; ++k) {
        const auto vr = in.get<std::uint64_t>();
        if (vr >= variable_count()) throw StateError("the state refuses variables this unit does not have");
        p.refused.emplace_back(vr, in.text());
    }
    p.initialized = in.get<std::uint8_t>() != 0;
    p.clock_set = in.get<std::uint8_t>() != 0;
    p.start_time = in.get<double>();
    if (!(std::fabs(p.start_time) <= MAX_TIME)) {
        throw StateError("serialized WetCloth FMU state: its start time " + py_repr(p.start_time) +
                         " s is not a finite number within +-" + py_g(MAX_TIME) + " s");
    }
    const auto size = in.get<std::uint64_t>();
    if (bytes.size() - in.at != size) throw StateError("serialized WetCloth FMU state is malformed (its size)");
    if (p.initialized != (size > 0)) throw StateError("serialized WetCloth FMU state is malformed (its simulation)");
    if (p.initialized) {
        try {
            p.simulation = Simulation::from_bytes(bytes.data() + in.at, static_cast<std::size_t>(size));
        } catch (const SnapshotError& exc) {
            throw StateError(exc.what());
        }
    }
    // The values, each within its range (checkpoint.fitting_simulation), and the scene as a whole.
    for (std::size_t vr = 0; vr < variable_count(); ++vr) {
        const Variable& var = variables()[vr];
        try {
            if (var.role == Role::SCENE && var.real) check_number(var, p.values.*var.real, py_repr(p.values.*var.real));
            if (var.role == Role::COLLIDER) {
                const double v = p.colliders[static_cast<std::size_t>(var.slot)];
                check_number(var, v, py_repr(v));
            }
            if (var.role == Role::SCENE && var.integer && var.type == Type::INTEGER) {
                const Index v = p.values.*var.integer;
                check_number(var, static_cast<double>(v), std::to_string(v));
            }
            if (var.role == Role::SCENE && var.integer && var.type == Type::STRING) {
                const Index code = p.values.*var.integer;
                if (code < 0 || code >= var.choice_count) {
                    throw std::invalid_argument(parameter_error(var.name, "a choice code out of range"));
                }
            }
            if (var.role == Role::MESH_OUTPUT_DIR) check_string(var, p.mesh_output_dir.c_str());
            if (var.role == Role::MESH_FORMAT) check_string(var, p.mesh_format.c_str());
        } catch (const std::invalid_argument& exc) {
            throw StateError(std::string("the state holds an invalid value: ") + exc.what());
        }
    }
    const std::vector<double> built = start_colliders();
    for (std::size_t at = 0; at < built.size(); at += COLLIDER_COLUMNS) {
        if (p.colliders[at + C_SHAPE] != built[at + C_SHAPE]) throw StateError("the state's colliders are not this unit's");
    }
    const std::string colliders = collider_problem(p.colliders);
    if (!colliders.empty()) throw StateError("the state holds an invalid value: " + colliders);
    if (p.initialized && !same_scene(p.values, p.simulation.scene)) {
        throw StateError("the state's variable values differ from its simulation's scene");
    }
    return p;
}

}  // namespace

// ------------------------------------------------------------------------------ difflib
namespace {

//: difflib.SequenceMatcher(None, a, b).ratio() (no junk: the texts are short).
double ratio(const std::string& a, const std::string& b) {
    if (a.empty() && b.empty()) return 1.0;
    std::size_t matches = 0;
    std::vector<std::array<std::size_t, 4>> queue{{0, a.size(), 0, b.size()}};
    while (!queue.empty()) {
        const auto [alo, ahi, blo, bhi] = queue.back();
        queue.pop_back();
        // find_longest_match: the longest block, earliest in a, then earliest in b
        std::size_t best_i = alo, best_j = blo, best = 0;
        std::vector<std::size_t> lengths(b.size() + 1, 0), next(b.size() + 1, 0);
        for (std::size_t i = alo; i < ahi; ++i) {
            std::fill(next.begin(), next.end(), 0);
            for (std::size_t j = blo; j < bhi; ++j) {
                if (a[i] != b[j]) continue;
                const std::size_t k = next[j + 1] = (j > 0 ? lengths[j] : 0) + 1;
                if (k > best) {
                    best_i = i + 1 - k;
                    best_j = j + 1 - k;
                    best = k;
                }
            }
            lengths.swap(next);
        }
        if (best == 0) continue;
        matches += best;
        if (alo < best_i && blo < best_j) queue.push_back({alo, best_i, blo, best_j});
        if (best_i + best < ahi && best_j + best < bhi) queue.push_back({best_i + best, ahi, best_j + best, bhi});
    }
    return 2.0 * static_cast<double>(matches) / static_cast<double>(a.size() + b.size());
}

}  // namespace

const char* close_match(const std::string& word, const char* const* choices, Index count) {
    const char* best = nullptr;
    double best_ratio = 0.0;
    for (Index k = 0; k < count; ++k) {
        const double r = ratio(choices[k], word);  // get_close_matches: seq1 the possibility, seq2 the word
        if (r < 0.6) continue;
        if (best == nullptr || r > best_ratio || (r == best_ratio && std::strcmp(choices[k], best) > 0)) {
            best = choices[k];
            best_ratio = r;
        }
    }
    return best;
}

// ------------------------------------------------------------------------------ the unit
std::string valid_text(const std::string& text) {
    std::string out;
    for (std::size_t at = 0; at < text.size();) {
        const std::size_t length = utf8_length(text, at);
        if (length > 0) {
            out.append(text, at, length);
            at += length;
            continue;
        }
        static const char digits[] = "0123456789abcdef";
        const auto value = static_cast<unsigned char>(text[at++]);
        out += std::string("\\x") + digits[value >> 4] + digits[value & 15];
    }
    return out;
}

Unit::Unit(std::string instance_name, Log log) : name_(std::move(instance_name)), log_(std::move(log)) {
    apply_starts();
}

void Unit::apply_starts() {
    values_ = start_scene();
    colliders_ = start_colliders();
    for (std::size_t vr = 0; vr < variable_count(); ++vr) {
        const Variable& var = variables()[vr];
        if (var.role == Role::MESH_OUTPUT_DIR) mesh_output_dir_ = var.start_text;
        if (var.role == Role::MESH_FORMAT) mesh_format_ = var.start_text;
    }
}

void Unit::reset() {
    apply_starts();
    refused_.clear();
    initialized_ = terminated_ = clock_set_ = entered_ = stop_defined_ = step_failed_ = false;
    start_time_ = stop_time_ = 0.0;
    sim_.reset();
    preview_.reset();
    changed();
}

void Unit::changed() { outputs_valid_ = false; }

Simulation& Unit::simulation() {
    if (sim_) return *sim_;
    if (!preview_) {
        // The initial state of the current values, or of the defaults while they do not form a scene.
        if (unit_scene_problem(values_).empty() && collider_problem(colliders_).empty()) {
            try {
                preview_ = new_simulation(values_, colliders_);
            } catch (const std::invalid_argument&) {  // a collider in the cloth at t = 0
            }
        }
        if (!preview_) preview_ = new_simulation(start_scene(), start_colliders());
    }
    return *preview_;
}

double Unit::time() const { return start_time_ + (sim_ ? sim_->time() : 0.0); }

const Variable* Unit::variable(std::uint64_t vr, const char* function) {
    if (vr >= variable_count()) {
        error(std::string(function) + ": no variable has the value reference " + std::to_string(vr) + " (0 to " +
              std::to_string(variable_count() - 1) + ")");
        return nullptr;
    }
    return &variables()[vr];
}

void Unit::pending(std::uint64_t vr, const std::string& message) {
    for (auto& entry : refused_) {
        if (entry.first == vr) {
            entry.second = message;
            return;
        }
    }
    refused_.emplace_back(vr, message);
}

void Unit::clear_pending(std::uint64_t vr) {
    refused_.erase(std::remove_if(refused_.begin(), refused_.end(), [vr](const auto& e) { return e.first == vr; }),
                   refused_.end());
}

std::string Unit::current_text(const Variable& var) const {
    switch (var.role) {
        case Role::MESH_OUTPUT_DIR: return py_repr(std::string_view(mesh_output_dir_));
        case Role::MESH_FORMAT: return py_repr(std::string_view(mesh_format_));
        case Role::COLLIDER: return py_repr(colliders_[static_cast<std::size_t>(var.slot)]);
        default: break;
    }
    if (var.real) return py_repr(values_.*var.real);
    if (var.type == Type::STRING) return py_repr(std::string_view(var.choices[values_.*var.integer]));
    return std::to_string(values_.*var.integer);
}

Outcome Unit::refuse(const Variable& var, std::uint64_t vr, const std::string& message) {
    pending(vr, message);
    error(message + " (value refused: " + var.name + " stays " + current_text(var) + ")");
    return Outcome::ERROR;
}

Outcome Unit::accept(std::uint64_t vr) {
    clear_pending(vr);
    changed();
    return Outcome::OK;
}

//: The message of a value set after initialization that must not change (unit.py's set_value and
//: Simulation.set_inputs).
static std::string fixed_after_start(const Variable& var) {
    return parameter_error(var.name, var.role == Role::SCENE || var.role == Role::COLLIDER
                                         ? "is fixed once the simulation starts; only inputs may change"
                                         : "is fixed once the unit is initialized");
}

const Variable* Unit::settable(std::uint64_t vr, Type type, const char* function) {
    const Variable* var = variable(vr, function);
    if (!var) return nullptr;
    if (var->causality == Causality::OUTPUT || var->causality == Causality::INDEPENDENT) {
        error(std::string(function) + ": variable '" + var->name + "' is an output: the master cannot set it");
        return nullptr;
    }
    if (var->type != type) {
        error(std::string(function) + ": variable '" + var->name + "' is a " + type_name(var->type) + ", not a " +
              type_name(type));
        return nullptr;
    }
    return var;
}

Outcome Unit::set_real(std::uint64_t vr, double value, const char* function) {
    const Variable* var = settable(vr, Type::REAL, function);
    if (!var) return Outcome::ERROR;
    try {
        const std::string text = py_repr(value);
        if (var->role == Role::COLLIDER) {
            double& field = colliders_[static_cast<std::size_t>(var->slot)];
            if (!initialized_) {
                check_number(*var, value, text);
                field = value;
                preview_.reset();
            } else if (value != field) {
                throw std::invalid_argument(fixed_after_start(*var));
            }
            return accept(vr);
        }
        if (!initialized_) {
            check_number(*var, value, text);
            values_.*var->real = value;
            preview_.reset();
        } else if (value != values_.*var->real) {  // an unchanged value changes nothing (and clears a refusal)
            if (!scene_input(var->name)) throw std::invalid_argument(fixed_after_start(*var));
            check_number(*var, value, text);
            Scene next = values_;
            next.*var->real = value;
            sim_->set_inputs(next);  // a changed input wakes a sleeping cloth
            values_ = next;
        }
    } catch (const std::invalid_argument& exc) {
        return refuse(*var, vr, exc.what());
    }
    return accept(vr);
}

Outcome Unit::set_integer(std::uint64_t vr, std::int64_t value, const std::string& text, const char* function) {
    const Variable* var = settable(vr, Type::INTEGER, function);
    if (!var) return Outcome::ERROR;
    try {
        if (!initialized_) {
            check_number(*var, static_cast<double>(value), text);
            values_.*var->integer = value;
            preview_.reset();
        } else if (value != values_.*var->integer) {
            throw std::invalid_argument(fixed_after_start(*var));  // no Integer is an input
        }
    } catch (const std::invalid_argument& exc) {
        return refuse(*var, vr, exc.what());
    }
    return accept(vr);
}

Outcome Unit::set_string(std::uint64_t vr, const char* value, const char* function) {
    const Variable* var = settable(vr, Type::STRING, function);
    if (!var) return Outcome::ERROR;
    try {
        if (!initialized_) {
            const Index code = check_string(*var, value);
            switch (var->role) {
                case Role::MESH_OUTPUT_DIR: mesh_output_dir_ = value; break;
                case Role::MESH_FORMAT: mesh_format_ = value; break;
                default: values_.*var->integer = code; break;
            }
            preview_.reset();
        } else {
            if (value == nullptr) check_string(*var, value);
            const char* current = var->role == Role::MESH_OUTPUT_DIR ? mesh_output_dir_.c_str()
                                  : var->role == Role::MESH_FORMAT   ? mesh_format_.c_str()
                                                                     : var->choices[values_.*var->integer];
            if (std::strcmp(value, current) != 0) throw std::invalid_argument(fixed_after_start(*var));  // no String is an input
        }
    } catch (const std::invalid_argument& exc) {
        return refuse(*var, vr, exc.what());
    }
    return accept(vr);
}

Outcome Unit::get_real(const std::uint32_t* vrs, std::size_t nvr, double* values, std::size_t n_values,
                       const char* function) {
    std::size_t at = 0;
    for (std::size_t k = 0; k < nvr; ++k) {
        const Variable* var = variable(vrs[k], function);
        if (!var) return Outcome::ERROR;
        if (var->type != Type::REAL) {
            error(std::string(function) + ": variable '" + var->name + "' is a " + type_name(var->type));
            return Outcome::ERROR;
        }
        std::size_t size = var->role == Role::UV ? CONSTANT_UV_SIZE : 1;
        if (var->role == Role::POSITIONS || var->role == Role::WETNESS) {
            const Index n = sim_ ? sim_->n() : built_in_cloth() ? built_in_cloth()->n : values_.nx * values_.ny;
            size = static_cast<std::size_t>(var->role == Role::POSITIONS ? 3 * n : n);
        }
        if (at + size > n_values) {
            error(std::string(function) + ": " + std::to_string(n_values) + " values asked for, but the variables hold more"
                  " (" + var->name + " alone " + std::to_string(size) + ")");
            return Outcome::ERROR;
        }
        switch (var->role) {
            case Role::SCENE: values[at] = values_.*var->real; break;
            case Role::COLLIDER: values[at] = colliders_[static_cast<std::size_t>(var->slot)]; break;
            case Role::TIME: values[at] = time(); break;
            case Role::OUTPUT:
                if (!outputs_valid_) {
                    simulation().outputs(outputs_);
                    outputs_valid_ = true;
                }
                values[at] = outputs_[var->slot];
                break;
            case Role::STEP_ERROR: values[at] = simulation().error_estimate(); break;
            case Role::UV: std::copy(CONSTANT_UV, CONSTANT_UV + CONSTANT_UV_SIZE, values + at); break;
            case Role::POSITIONS:
                if (static_cast<std::size_t>(3 * simulation().n()) != size) {
                    error(std::string(function) + ": 'positions' holds 3 nx ny = " +
                          std::to_string(3 * simulation().n()) + " values");
                    return Outcome::ERROR;
                }
                simulation().positions(values + at);
                break;
            case Role::WETNESS:
                if (static_cast<std::size_t>(simulation().n()) != size) {
                    error(std::string(function) + ": 'wetness' holds nx ny = " + std::to_string(simulation().n()) +
                          " values");
                    return Outcome::ERROR;
                }
                simulation().wetness(values + at);
                break;
            default: break;
        }
        at += size;
    }
    return all_values_filled(at, n_values, function);
}

Outcome Unit::all_values_filled(std::size_t at, std::size_t n_values, const char* function) const {
    if (at == n_values) return Outcome::OK;
    error(std::string(function) + ": " + std::to_string(n_values) + " values asked for, the variables hold " +
          std::to_string(at));
    return Outcome::ERROR;
}

Outcome Unit::get_integer(std::uint64_t vr, std::int64_t& value, const char* function) {
    const Variable* var = variable(vr, function);
    if (!var) return Outcome::ERROR;
    if (var->type != Type::INTEGER) {
        error(std::string(function) + ": variable '" + var->name + "' is a " + type_name(var->type));
        return Outcome::ERROR;
    }
    value = values_.*var->integer;
    return Outcome::OK;
}

Outcome Unit::get_uint64(const std::uint32_t* vrs, std::size_t nvr, std::uint64_t* values, std::size_t n_values,
                         const char* function) {
    std::size_t at = 0;
    for (std::size_t k = 0; k < nvr; ++k) {
        const Variable* var = variable(vrs[k], function);
        if (!var) return Outcome::ERROR;
        const bool structural = var->type == Type::INTEGER && var->causality == Causality::STRUCTURAL_PARAMETER;
        if (var->type != Type::UINT64 && !structural) {
            error(std::string(function) + ": variable '" + var->name + "' is " +
                  (var->type == Type::INTEGER ? "an Int32" : std::string("a ") + type_name(var->type)));
            return Outcome::ERROR;
        }
        const std::size_t size = var->role == Role::FACES ? CONSTANT_FACES_SIZE : 1;
        if (at + size > n_values) {
            error(std::string(function) + ": " + std::to_string(n_values) + " values asked for, but the variables hold more"
                  " (" + var->name + " alone " + std::to_string(size) + ")");
            return Outcome::ERROR;
        }
        if (var->role == Role::FACES) {
            std::copy(CONSTANT_FACES, CONSTANT_FACES + CONSTANT_FACES_SIZE, values + at);
        } else {
            values[at] = static_cast<std::uint64_t>(values_.*var->integer);
        }
        at += size;
    }
    return all_values_filled(at, n_values, function);
}

Outcome Unit::get_string(std::uint64_t vr, const char*& value, const char* function) {
    const Variable* var = variable(vr, function);
    if (!var) return Outcome::ERROR;
    if (var->type != Type::STRING) {
        error(std::string(function) + ": variable '" + var->name + "' is a " + type_name(var->type));
        return Outcome::ERROR;
    }
    switch (var->role) {
        case Role::MESH_OUTPUT_DIR: value = mesh_output_dir_.c_str(); break;
        case Role::MESH_FORMAT: value = mesh_format_.c_str(); break;
        default: value = var->choices[values_.*var->integer]; break;
    }
    return Outcome::OK;
}

// ------------------------------------------------------------------------------ life cycle
const char* Unit::phase() const {
    if (terminated_) return "terminated";
    if (initialized_) return "initialized (stepping)";
    return entered_ ? "initialization mode" : "instantiated";
}

Outcome Unit::refuse_call(const char* function, const char* allowed) const {
    error(std::string(function) + " is not allowed in the " + phase() + " state; allowed only in the " + allowed +
          " state");
    return Outcome::ERROR;
}

Outcome Unit::setup_experiment(const char* function, double start_time, bool stop_defined, double stop_time,
                               bool tolerance_defined, double tolerance) {
    if (initialized_ || terminated_ || entered_) return refuse_call(function, "instantiated");
    if (tolerance_defined && !(tolerance > 0.0)) {
        error(std::string(function) + ": tolerance " + py_repr(tolerance) + " is not allowed; allowed: a "
              "tolerance > 0 where toleranceDefined is true (or none). The unit's accuracy is set by its own "
              "parameter 'tolerance', not by the experiment's");
        return Outcome::ERROR;
    }
    if (!(std::fabs(start_time) <= MAX_TIME)) {
        error(std::string(function) + ": the start time must be a finite number of seconds within +-" +
              py_g(MAX_TIME) + " s, got " + py_repr(start_time));
        return Outcome::ERROR;
    }
    if (stop_defined && !(stop_time >= start_time)) {
        error(std::string(function) + ": stopTime " + py_repr(stop_time) + " s lies before startTime " +
              py_repr(start_time) + " s; allowed: stopTime >= startTime");
        return Outcome::ERROR;
    }
    start_time_ = start_time;
    clock_set_ = true;
    stop_defined_ = stop_defined;
    stop_time_ = stop_time;
    changed();
    if (tolerance_defined && !tolerance_noted_) {
        tolerance_noted_ = true;
        warning(std::string(function) + ": the experiment's tolerance " + py_repr(tolerance) + " is not used: the "
                "unit's accuracy is set by its own parameter 'tolerance' (a local error bound per internal step, "
                "relative to the cloth's size; 0: fixed steps of max_step), not by the master's");
        return Outcome::WARNING;
    }
    return Outcome::OK;
}

Outcome Unit::enter_initialization(const char* function) {
    if (initialized_ || terminated_ || entered_) return refuse_call(function, "instantiated");
    entered_ = true;
    return Outcome::OK;
}

Outcome Unit::exit_initialization(const char* function) {
    if (initialized_ || terminated_ || !entered_) return refuse_call(function, "initialization mode");
    std::vector<std::string> problems;
    for (const auto& entry : refused_) problems.push_back(entry.second);
    const std::string whole = unit_scene_problem(values_);
    if (!whole.empty()) problems.push_back(whole);
    const std::string colliders = collider_problem(colliders_);
    if (!colliders.empty()) problems.push_back(colliders);
    if (problems.empty()) {
        try {
            sim_ = new_simulation(values_, colliders_);
        } catch (const std::bad_alloc&) {
            problems.push_back("not enough memory for a cloth of nx x ny = " + std::to_string(values_.nx) + " x " +
                               std::to_string(values_.ny) + " particles");
        } catch (const std::exception& exc) {
            problems.emplace_back(exc.what());
        }
    }
    if (!problems.empty()) {
        std::string message = "initialization refused: ";
        std::vector<std::string> seen;
        for (const auto& p : problems) {
            if (std::find(seen.begin(), seen.end(), p) != seen.end()) continue;
            message += (seen.empty() ? "" : "; ") + p;
            seen.push_back(p);
        }
        error(message);
        return Outcome::ERROR;
    }
    preview_.reset();
    initialized_ = true;
    entered_ = false;
    changed();
    return Outcome::OK;
}

Outcome Unit::do_step(double current_time, double step_size) {
    if (!(std::fabs(current_time) <= MAX_TIME && step_size >= 0.0 && current_time + step_size <= MAX_TIME)) {
        error("doStep needs a finite communication point within +-" + py_g(MAX_TIME) +
              " s and a finite step size >= 0 s that ends there too (t + step <= " + py_g(MAX_TIME) +
              " s), got t = " + py_repr(current_time) + " s, step " + py_repr(step_size) + " s");
        return Outcome::ERROR;
    }
    const double slack = TIME_TOLERANCE * std::max(1.0, std::fabs(stop_time_));  // a sum of steps' rounding
    if (stop_defined_ && current_time + step_size > stop_time_ + slack) {
        error("doStep from t = " + py_repr(current_time) + " s by " + py_repr(step_size) +
              " s ends past the experiment's stopTime " + py_repr(stop_time_) + " s; allowed: t + step <= stopTime");
        return Outcome::ERROR;
    }
    if (terminated_) {
        error("doStep at t = " + py_g(current_time) + " s after fmiTerminate: the run is over");
        return Outcome::ERROR;
    }
    if (!initialized_) {
        error("doStep before the unit was initialized");
        return Outcome::ERROR;
    }
    step_failed_ = false;
    Simulation& sim = *sim_;
    if (clock_set_) {  // the time first: a step at the wrong time is refused for that, whatever else is pending
        const double now = start_time_ + sim.time();
        if (std::fabs(current_time - now) > TIME_TOLERANCE * std::max(1.0, std::fabs(now))) {
            error("doStep from t = " + py_repr(current_time) + " s, but the unit is at t = " + py_repr(now) +
                  " s; restore an FMU state to go back in time");
            return Outcome::DISCARD;
        }
    }
    if (!refused_.empty()) {
        for (const auto& entry : refused_) error("step refused at t = " + py_g(current_time) + " s: " + entry.second);
        return Outcome::DISCARD;
    }
    if (!clock_set_) {
        start_time_ = current_time - sim.time();
        clock_set_ = true;
    }
    sim.save(before_);
    changed();
    std::string failure;
    try {
        const double duration = current_time + step_size - start_time_ - sim.time();
        if (sim.advance(duration > 0.0 ? duration : 0.0) == BLOWN_UP) failure = "BlowUpError: " + sim.blow_up_message();
    } catch (const std::bad_alloc&) {
        failure = "MemoryError: out of memory";
    } catch (const std::exception& exc) {
        failure = std::string("RuntimeError: ") + exc.what();
    }
    if (failure.empty()) return Outcome::OK;
    step_failed_ = true;
    try {
        sim.restore(before_);
    } catch (const std::exception& exc) {
        error(std::string("step from t = ") + py_g(current_time) + " s failed and the unit could not go back: " +
              exc.what());
        return Outcome::ERROR;
    }
    error("step from t = " + py_g(current_time) + " s by " + py_g(step_size) + " s failed: " + failure +
          " The unit stays at t = " + py_g(current_time) + " s with its last good outputs.");
    return Outcome::DISCARD;
}

Outcome Unit::terminate(const char* function) {
    if (terminated_) {
        warning("fmiTerminate called again: the run had already ended; nothing done");
        return Outcome::OK;
    }
    if (!initialized_) return refuse_call(function, "initialized (stepping)");
    terminated_ = true;
    return Outcome::OK;
}

// ------------------------------------------------------------------------------ FMU states
namespace {

struct StateObject {
    std::vector<unsigned char> bytes;
};

std::mutex& registry_mutex() {
    static std::mutex mutex;
    return mutex;
}

std::unordered_set<void*>& registry() {
    static std::unordered_set<void*> objects;
    return objects;
}

//: FMU state objects: new_state makes one, state_bytes finds the bytes of one made here (null for any
//: other pointer), free_state deletes one (false if it is not one of ours).
void* new_state(std::vector<unsigned char> bytes) {
    auto* object = new StateObject{std::move(bytes)};
    std::lock_guard<std::mutex> lock(registry_mutex());
    registry().insert(object);
    return object;
}

std::vector<unsigned char>* state_bytes(void* state) {
    std::lock_guard<std::mutex> lock(registry_mutex());
    if (state == nullptr || registry().count(state) == 0) return nullptr;
    return &static_cast<StateObject*>(state)->bytes;
}

bool free_state(void* state) {
    {
        std::lock_guard<std::mutex> lock(registry_mutex());
        if (state == nullptr || registry().erase(state) == 0) return false;
    }
    delete static_cast<StateObject*>(state);
    return true;
}

}  // namespace

std::vector<unsigned char> Unit::state() const {
    std::vector<unsigned char> bytes;
    ByteWriter out{bytes};
    out.begin(STATE_MAGIC, MAGIC_SIZE, STATE_VERSION);
    out.put(static_cast<std::uint64_t>(variable_count()));
    for_each_field(values_, [&](const char*, const auto& v) { out.put(v); });
    for (const double v : colliders_) out.put(v);
    out.text(mesh_output_dir_);
    out.text(mesh_format_);
    out.put(static_cast<std::uint64_t>(refused_.size()));
    for (const auto& [vr, message] : refused_) {
        out.put(vr);
        out.text(message);
    }
    out.put(static_cast<std::uint8_t>(initialized_));
    out.put(static_cast<std::uint8_t>(clock_set_));
    out.put(start_time_);
    if (sim_ && initialized_) {
        const std::vector<unsigned char> simulation = sim_->snapshot();
        out.put(static_cast<std::uint64_t>(simulation.size()));
        bytes.insert(bytes.end(), simulation.begin(), simulation.end());
    } else {
        out.put(std::uint64_t{0});
    }
    out.seal();
    return bytes;
}

void Unit::check_state(const std::vector<unsigned char>& bytes) { parse(bytes); }

Outcome Unit::set_state(const std::vector<unsigned char>& bytes) {
    try {
        Parsed p = parse(bytes);
        std::unique_ptr<Simulation> fresh;
        if (p.initialized) {
            const Scene& scene = p.simulation.scene;
            if (sim_ && initialized_ && (scene.nx != sim_->scene().nx || scene.ny != sim_->scene().ny)) {
                throw StateError("the state is of a cloth of nx x ny = " + std::to_string(scene.nx) + " x " +
                                 std::to_string(scene.ny) + " particles, this unit runs " +
                                 std::to_string(sim_->scene().nx) + " x " + std::to_string(sim_->scene().ny) +
                                 " (fixed once it is initialized)");
            }
            try {
                if (sim_ && fixed_differences(sim_->scene(), scene).empty() &&
                    sim_->fixtures().colliders == collider_rows(p.colliders)) {
                    sim_->restore(p.simulation);  // checks everything before it changes anything
                } else {
                    fresh = new_simulation(scene, p.colliders);
                    fresh->restore(p.simulation);
                }
            } catch (const SnapshotError& exc) {
                throw StateError(exc.what());
            } catch (const std::invalid_argument& exc) {
                throw StateError(std::string("the state's scene is not valid: ") + exc.what());
            }
            if (fresh) sim_ = std::move(fresh);
        } else {
            sim_.reset();
        }
        values_ = p.values;
        colliders_ = p.colliders;
        mesh_output_dir_ = p.mesh_output_dir;
        mesh_format_ = p.mesh_format;
        refused_ = p.refused;
        entered_ = entered_ && !initialized_ && !p.initialized;  // back to before initialization: instantiated
        initialized_ = p.initialized;
        start_time_ = p.start_time;
        clock_set_ = clock_set_ || p.initialized || p.clock_set;
        preview_.reset();
        step_failed_ = false;
        changed();
        return Outcome::OK;
    } catch (const StateError& exc) {
        error(std::string("FMU state refused, the unit is unchanged: ") + exc.what());
    } catch (const std::bad_alloc&) {
        error("FMU state refused, the unit is unchanged: not enough memory");
    }
    return Outcome::ERROR;
}

Outcome get_fmu_state(Unit& unit, void** state) {
    if (state == nullptr) return Outcome::ERROR;
    std::vector<unsigned char> bytes = unit.state();
    if (std::vector<unsigned char>* existing = state_bytes(*state)) {
        *existing = std::move(bytes);  // the master passed a state to update
    } else {
        *state = new_state(std::move(bytes));
    }
    return Outcome::OK;
}

Outcome set_fmu_state(Unit& unit, void* state) {
    const std::vector<unsigned char>* bytes = state_bytes(state);
    if (bytes == nullptr) {
        unit.error("FMU state refused, the unit is unchanged: not a WetCloth FMU state (an object this unit did not "
                   "make, or one already freed)");
        return Outcome::ERROR;
    }
    return unit.set_state(*bytes);
}

Outcome free_fmu_state(Unit& unit, void** state, const char* function) {
    if (state == nullptr || *state == nullptr) return Outcome::OK;
    if (!free_state(*state)) {
        unit.error(std::string(function) + ": not a WetCloth FMU state (an object this unit did not make, or one "
                   "already freed)");
        return Outcome::ERROR;
    }
    *state = nullptr;
    return Outcome::OK;
}

Outcome serialized_state_size(Unit& unit, void* state, std::size_t* size, const char* function) {
    const std::vector<unsigned char>* bytes = state_bytes(state);
    if (bytes == nullptr || size == nullptr) {
        unit.error(std::string(function) + ": not a WetCloth FMU state");
        return Outcome::ERROR;
    }
    *size = bytes->size();
    return Outcome::OK;
}

Outcome serialize_fmu_state(Unit& unit, void* state, unsigned char* out, std::size_t size, const char* function) {
    const std::vector<unsigned char>* bytes = state_bytes(state);
    if (bytes == nullptr) {
        unit.error(std::string(function) + ": not a WetCloth FMU state");
        return Outcome::ERROR;
    }
    if (out == nullptr || size < bytes->size()) {
        unit.error(std::string(function) + ": the state needs " + std::to_string(bytes->size()) +
                   " bytes, the buffer has " + std::to_string(size));
        return Outcome::ERROR;
    }
    std::memcpy(out, bytes->data(), bytes->size());
    return Outcome::OK;
}

Outcome deserialize_fmu_state(Unit& unit, const unsigned char* data, std::size_t size, void** state) {
    if (state == nullptr) return Outcome::ERROR;
    std::vector<unsigned char> bytes;
    if (data != nullptr) bytes.assign(data, data + size);
    try {
        Unit::check_state(bytes);
    } catch (const StateError& exc) {
        unit.error(std::string("serialized FMU state refused: ") + exc.what());
        return Outcome::ERROR;
    }
    if (std::vector<unsigned char>* existing = state_bytes(*state)) {
        *existing = std::move(bytes);
    } else {
        *state = new_state(std::move(bytes));
    }
    return Outcome::OK;
}

}  // namespace wc::fmu
