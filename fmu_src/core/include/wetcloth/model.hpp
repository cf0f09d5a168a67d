// The native model: a scene and every array the step loop works on, in storage of its own (the native
// FMU's; the Python package keeps its arrays in NumPy and views them through the bindings).
//
// A port of what the Python package does before and between the compiled calls:
//   * wetcloth/scene.py: the Scene's fields (string choices as codes into the name lists below) and its
//     one cross-parameter rule (scene_problem);
//   * wetcloth/topology.py (build_topology), model.py (the Model.scene setter, _set_wicking),
//     integrators.py (Integrator.__init__ and control()), state.py (initial_state);
//   * the allocations of wetcloth/preconditioner.py (make_plane, level_sizes, make_hierarchy),
//     self_collision.py (make_contact, rest_gap, grid_edges) and bundles.py (make_work, make_solver);
//   * wetcloth/simulation.py: set_inputs, advance, outputs, positions, wetness, the blow-up message and
//     snapshot / restore (the same values: state, BDF2 history, clock, preconditioner reference,
//     self-collision reference and margin).
// Every formula keeps the Python's order of operations, so that the arrays agree to the bit.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "wetcloth/colliders.hpp"
#include "wetcloth/core.hpp"

namespace wc {

// ------------------------------------------------------------------------------------------ the scene
//: The allowed values of each string parameter, in the order of wetcloth/scene.py; a Scene holds the
//: index into its list (INTEGRATORS follows core.hpp's Integrator codes).
inline constexpr const char* DAMPING_MODELS[] = {"projected", "thesis"};
inline constexpr const char* DRAG_MODELS[] = {"face", "stokes"};
inline constexpr const char* BUOYANCY_MODELS[] = {"smooth", "thesis"};
inline constexpr const char* SWITCHES[] = {"on", "off"};
inline constexpr const char* EDGES[] = {"none", "x_min", "x_max", "y_min", "y_max"};
inline constexpr const char* INTEGRATOR_NAMES[] = {"explicit_euler", "symplectic_euler", "implicit_euler", "bdf2"};
//: The one value the native model takes of a free-text parameter (cloth_mesh, pinned_vertices) by default:
//: none.  A native FMU built for a mesh cloth takes its scene's values instead (its generated table), and
//: the mesh comes built in (ClothMesh).
inline constexpr const char* NO_TEXT[] = {""};
enum DampingModel : Index { DAMPING_PROJECTED = 0, DAMPING_THESIS = 1 };
enum DragModel : Index { DRAG_FACE = 0, DRAG_STOKES = 1 };
enum BuoyancyModel : Index { BUOYANCY_SMOOTH = 0, BUOYANCY_THESIS = 1 };
enum Switch : Index { SWITCH_ON = 0, SWITCH_OFF = 1 };
enum Edge : Index { EDGE_NONE = 0, EDGE_X_MIN, EDGE_X_MAX, EDGE_Y_MIN, EDGE_Y_MAX };

struct Choices {
    const char* const* names = nullptr;
    Index count = 0;
};

//: The choices of a string parameter by its name (none for a number parameter).
constexpr Choices scene_choices(std::string_view field) {
    if (field == "damping_model") return {DAMPING_MODELS, 2};
    if (field == "drag_model") return {DRAG_MODELS, 2};
    if (field == "buoyancy_model") return {BUOYANCY_MODELS, 2};
    if (field == "self_collision") return {SWITCHES, 2};
    if (field == "pinned_edge") return {EDGES, 5};
    if (field == "integrator") return {INTEGRATOR_NAMES, 4};
    if (field == "place_mesh") return {SWITCHES, 2};
    if (field == "cloth_mesh" || field == "pinned_vertices") return {NO_TEXT, 1};
    return {};
}

//: A scene: every parameter of wetcloth.scene.Scene, in its order, with its default (the towel).
//: Units are SI.  Nothing here checks ranges: the FMU checks each value against the range of the
//: Python metadata (its generated variable table), and scene_problem the scene as a whole.
struct Scene {
    Index nx = 21, ny = 29;                                      // particles along x, y
    double width = 0.5, length = 0.7;                            // m
    Index cloth_mesh = 0;                                        // 0: the one allowed (the ClothMesh, if any)
    Index place_mesh = SWITCH_OFF;
    double areal_density = 0.45;                                 // kg/m2
    double thickness = 0.002;                                    // m
    double stretch_stiffness = 2000.0, bend_stiffness = 20.0;    // N/m
    double bend_rigidity = 0.0;                                  // N m
    double damping = 0.2;                                        // N s/m
    Index damping_model = DAMPING_PROJECTED;
    double water_level = 0.0;                                    // m (input)
    double water_density = 1000.0;                               // kg/m3 (input)
    double water_viscosity = 1.0e-3;                             // Pa s
    Index drag_model = DRAG_FACE;
    double drag_normal = 1.2, drag_tangential = 0.03;            // -
    double drag_linear = 2.0;                                    // N s/m3
    Index buoyancy_model = BUOYANCY_SMOOTH;
    double absorption_capacity = 3.8;                            // kg/kg (input)
    double absorption_rate = 0.15;                               // 1/s (input)
    double wicking_rate = 0.0;                                   // m2/s
    double drying_rate = 0.0;                                    // 1/s
    double wet_stiffness_factor = 0.0;                           // -
    double current_x = 0.0, current_y = 0.0;                     // m/s (inputs)
    double air_density = 1.2;                                    // kg/m3
    double wind_x = 0.0, wind_y = 0.0, wind_z = 0.0;             // m/s (inputs)
    double initial_saturation = 0.0;                             // -
    double initial_height = 0.1;                                 // m
    double initial_tilt = 10.0;                                  // deg
    double floor_level = -1.0;                                   // m
    double floor_friction = 0.5;                                 // -
    Index self_collision = SWITCH_ON;
    double self_friction = 0.4;                                  // -
    Index pinned_edge = EDGE_NONE;
    Index pinned_vertices = 0;                                   // 0: the one allowed (the built-in Pins)
    double grip_x = 0.0, grip_y = 0.0, grip_z = 0.0;             // m (inputs)
    Index integrator = BDF2;
    double tolerance = 5e-6;                                     // -
    double max_step = 0.1;                                       // s
};

//: The field names of Scene, in its order (the generated FMU variable table checks them against Python's).
inline constexpr const char* SCENE_FIELDS[] = {
    "nx", "ny", "width", "length", "cloth_mesh", "place_mesh", "areal_density", "thickness", "stretch_stiffness", "bend_stiffness", "bend_rigidity", "damping",
    "damping_model", "water_level", "water_density", "water_viscosity", "drag_model", "drag_normal",
    "drag_tangential", "drag_linear", "buoyancy_model", "absorption_capacity", "absorption_rate", "wicking_rate",
    "drying_rate", "wet_stiffness_factor", "current_x", "current_y", "air_density", "wind_x", "wind_y", "wind_z",
    "initial_saturation", "initial_height", "initial_tilt", "floor_level", "floor_friction", "self_collision",
    "self_friction", "pinned_edge", "pinned_vertices", "grip_x", "grip_y", "grip_z", "integrator", "tolerance",
    "max_step"};
inline constexpr Index SCENE_FIELD_COUNT = sizeof(SCENE_FIELDS) / sizeof(SCENE_FIELDS[0]);

//: Whether a parameter may change while the simulation runs (scene.py's fmu=INPUT).
constexpr bool scene_input(std::string_view field) {
    return field == "water_level" || field == "water_density" || field == "absorption_capacity" ||
           field == "absorption_rate" || field == "current_x" || field == "current_y" || field == "wind_x" ||
           field == "wind_y" || field == "wind_z" || field == "grip_x" || field == "grip_y" || field == "grip_z";
}

//: Call visit(name, member) for every field of a Scene (const or not), in SCENE_FIELDS order; member is a
//: double& or an Index&.
template <class S, class Visit>
void for_each_field(S& s, Visit&& visit) {
    visit("nx", s.nx); visit("ny", s.ny); visit("width", s.width); visit("length", s.length);
    visit("cloth_mesh", s.cloth_mesh); visit("place_mesh", s.place_mesh);
    visit("areal_density", s.areal_density); visit("thickness", s.thickness);
    visit("stretch_stiffness", s.stretch_stiffness); visit("bend_stiffness", s.bend_stiffness);
    visit("bend_rigidity", s.bend_rigidity);
    visit("damping", s.damping); visit("damping_model", s.damping_model); visit("water_level", s.water_level);
    visit("water_density", s.water_density); visit("water_viscosity", s.water_viscosity);
    visit("drag_model", s.drag_model); visit("drag_normal", s.drag_normal);
    visit("drag_tangential", s.drag_tangential); visit("drag_linear", s.drag_linear);
    visit("buoyancy_model", s.buoyancy_model); visit("absorption_capacity", s.absorption_capacity);
    visit("absorption_rate", s.absorption_rate); visit("wicking_rate", s.wicking_rate);
    visit("drying_rate", s.drying_rate); visit("wet_stiffness_factor", s.wet_stiffness_factor);
    visit("current_x", s.current_x); visit("current_y", s.current_y); visit("air_density", s.air_density);
    visit("wind_x", s.wind_x); visit("wind_y", s.wind_y); visit("wind_z", s.wind_z);
    visit("initial_saturation", s.initial_saturation); visit("initial_height", s.initial_height);
    visit("initial_tilt", s.initial_tilt); visit("floor_level", s.floor_level);
    visit("floor_friction", s.floor_friction); visit("self_collision", s.self_collision);
    visit("self_friction", s.self_friction); visit("pinned_edge", s.pinned_edge);
    visit("pinned_vertices", s.pinned_vertices);
    visit("grip_x", s.grip_x); visit("grip_y", s.grip_y); visit("grip_z", s.grip_z); visit("integrator", s.integrator);
    visit("tolerance", s.tolerance); visit("max_step", s.max_step);
}

//: The names of the fixed (non-input) fields whose values differ between a and b, comma-separated.
std::string fixed_differences(const Scene& a, const Scene& b);

struct ClothMesh;
struct Pins;

//: scene.validate's rule on the scene as a whole: "" or the ParameterError's text ("parameter
//: 'initial_height': the cloth starts at or below the floor ...").  Ranges are the caller's.  With a
//: cloth `mesh`: its start above the floor (_check_mesh_start) and the parameters its built-in structure
//: fixes (ClothMesh::fixed_problem); with `pins`, a box that holds a particle (pinned_mask).
std::string scene_problem(const Scene& scene, const ClothMesh* mesh = nullptr, const Pins* pins = nullptr);

//: The most a grid's cells may be longer one way than the other (dx/dy or dy/dx; grid_start_problem, which
//: scene.validate calls too).  A spring's stiffness goes as its strip's width over its length, so springs
//: across a cell dx/dy as long as wide are (dx/dy)^2 stiffer than those along it: at 455 (a 0.5 m wide, 1.1 mm
//: long cloth of 7 x 7) a floating cloth's steps fell to microseconds, 60 s of CPU for 1 s.  And the most
//: particles along a side (scene.MOST_ALONG).
constexpr double LONGEST_CELL = 100.0;
constexpr Index MOST_ALONG = 1024;

//: "" or the ParameterError's text of a bend_rigidity on a native unit's grid built without hinges
//: (native_mesh.GRID_RIGIDITY): its families have none (built with them, the grid's springs are listed,
//: topology._hinged_grid: a ClothMesh with hinged_grid).
std::string grid_rigidity_problem(const Scene& scene);

//: The grid's particle positions (3, n) m at t = 0 (topology.initial_positions).
std::vector<double> grid_start(const Scene& scene);

//: scene_problem's rule on the grid's start: above the floor, and `pins`' box holding a particle there.
std::string grid_start_problem(const Scene& scene, const Pins* pins);

//: "" or the ParameterError's text of an explicit scheme (control.integrator) that is stable on this cloth at
//: rest only at steps below control.smallest_step (it would creep on at under 1e-9 s a step), naming what sets
//: that bound: the springs' damping, the drag at rest or the springs' stiffness.  Simulation checks it at
//: the start and when inputs change, as the Python API does.
std::string stability_problem(const Control& control);

//: Whether particle i of the scene's nx x ny grid is on its pinned_edge (pinned_mask).
bool on_pinned_edge(const Scene& scene, Index i);

// ------------------------------------------------------------------------------------------ formatting
//: Python's repr of a float ('0.1', '1e-05', '1e+16', 'inf', 'nan') and of a str ('text').
std::string py_repr(double value);
std::string py_repr(std::string_view text);
//: Python's format(value, f".{precision}g") ('0.1', '1e-05', 'inf').
std::string py_g(double value, int precision = 6);

// ------------------------------------------------------------------------------------------ blow-ups
//: What may keep `scene` from blowing up ("use integrator 'implicit_euler' (stable at any step), a smaller
//: max_step (now 0.01 s) or a smaller tolerance (now 5e-06)"), leaving out what it already does; where its
//: fixed steps exceed `stable` (s), the scheme's stability bound at rest (stable_step(control, 0)), naming it.
std::string blow_up_advice(const Scene& scene, double stable);
//: A blow-up's cause where the grip or a keyed collider moves fast in the failed step of h s from t s, in a
//: call that steps to `end` s: the fastest move under way, if at least FAST_MOVE times blow_up_speed (m/s), and
//: what to change; else ''.  The moves: each between consecutive keys of the grip and of each collider (phys's
//: rows; the collider keys numbered `numbers` (one per row: their places in the scene, from 1), or 1, 2, ... if
//: null) and the grip inputs' part, reached linearly by `end`, as the first pinned particle not held (free and
//: held (n) 0) of pos (3, n) m has it against phys.grip_origin.
std::string fast_move_cause(const Physics& phys, const Index* numbers, Index n, const double* pos, const double* free,
                            const double* held, double t, double h, double end, double blow_up_speed);
//: A blow-up's cause where a step ending at pos (3, n) m leaves a pinned particle (free (n) 0) pressed into a
//: collider of phys (pinned_pressed): which, into which, and what to move; else ''.
std::string pinned_cause(const Physics& phys, Index n, const double* free, const double* pos);
//: The BlowUpError's text, the Python API's and the native units' alike: a step of h s from t s ended
//: non-finite or at `speed` m/s (over control.blow_up_speed; below it, no step was accepted), its likely
//: cause `cause` (a fast move of the grip or a collider, a pinned particle pressed into a collider) or,
//: if empty, the scene's settings with blow_up_advice's.  Reads the scene's integrator, tolerance, max_step
//: and stretch_stiffness.
std::string blow_up_text(const Scene& scene, const Control& control, bool finite, double speed, double t, double h,
                         const std::string& cause);

// ------------------------------------------------------------------------------------------ topology
//: Spring families (topology.py), in the order they are built.
enum Family : Index { STRUCTURAL_X = 0, STRUCTURAL_Y, SHEAR_UP_RIGHT, SHEAR_UP_LEFT, BEND_X, BEND_Y };
inline constexpr const char* FAMILY_NAMES[] = {"structural_x", "structural_y", "shear_up_right", "shear_up_left",
                                               "bend_x", "bend_y"};

//: Kinds of a mesh's listed springs (topology.py's STRETCH, SHEAR, BEND, HINGE).
enum PairKind : Index { PAIR_STRETCH = 0, PAIR_SHEAR = 1, PAIR_BEND = 2, PAIR_HINGE = 3 };

//: Pins by pinned_vertices, built into a native FMU with its scene (topology.pinned_mask): a box over the
//: particles' start positions, or a mesh file's point attribute (its nonzero vertices).
struct Pins {
    bool box = false;
    double corners[6] = {};        // the box's lower corner, upper corner (m)
    std::vector<Index> attribute;  // (n) 1 pinned by the attribute, or empty
    std::string text, allowed;     // pinned_vertices' value (its repr) and scene.PINS_ALLOWED, for messages
    //: Mark in `pinned` (n) the particles these pins hold at the start positions pos (3, n); "" or the
    //: ParameterError's text of a box that holds none.
    std::string pin(Index n, const double* pos, std::vector<char>& pinned) const;
};

//: A cloth from a mesh file: what depends on the file alone, computed once by the Python front end
//: (topology.py's _mesh, listed_springs, corner_shares, placed's centroid;
//: self_collision.make_contact's gaps; preconditioner.make_mesh_plane's band order and algebraic
//: hierarchy) and built into the native FMU as arrays (wetcloth/fmu/native_mesh.py).  The Simulation turns
//: it, with a scene's values, into what the Python front end hands the core: spring constants by the
//: moduli, masses by areal_density, the start by place_mesh, initial_height and initial_tilt.
struct ClothMesh {
    std::string source;              // the mesh file, for messages
    Index n = 0;                     // particles (the file's vertices)
    std::vector<double> rest_pos;    // (3, n) m, the file's coordinates
    std::vector<double> rest_xy;     // (2, n) m, the flat rest sheet (flat_coordinates)
    std::vector<double> area;        // (n) m2 (vertex_areas)
    double centre[3] = {};           // m, the area-weighted centroid of rest_pos (placed)
    double size = 0.0;               // m, the rest sheet's larger side (Topology.size)
    double rest_gap = 0.0, typical_gap = 0.0, least_margin = 0.0;  // m (make_contact)
    std::vector<Index> pairs;        // (2, S) listed springs, the first pair_tension_count tension-only
    std::vector<double> pair_rest;   // (S) m
    std::vector<double> pair_shape;  // (S) strip area / rest length^2 (-)
    std::vector<Index> pair_kind;    // (S) PairKind
    Index pair_tension_count = 0, pair_buckling_count = 0;  // then the next pair_buckling_count buckling
    std::vector<Index> triangles;    // (m, 3)
    std::vector<double> corner_shares;  // (m, 3)
    // The preconditioner (make_mesh_plane): the coarsest level's band order, its rank and half-bandwidth,
    // the algebraic hierarchy's arrays (core.hpp's Algebraic; the values filled by the core at each refresh).
    std::vector<Index> order, rank;
    Index kd = 0;
    std::vector<Index> levels, a_start, diagonal, p_start, r_start, spring_entries;
    std::vector<Column> a_column, p_column, r_column;
    std::vector<double> p_value, r_value;
    Index marker_size = 0;
    // What the structure was built for: whether it has bending springs (bend_stiffness != 0), and, with an
    // algebraic hierarchy (more than one level), the stretch_stiffness its aggregation weighed (N/m).
    bool bends = false;
    double hierarchy_stretch_stiffness = 0.0;
    // A file whose vertices form the built-in grid (topology.file_grid): its grid_nx x grid_ny particles and
    // grid_width x grid_length (m).  It runs with the grid's springs, preconditioner and self-collision gaps,
    // from the file's start (rest_pos, centre); the listed springs and hierarchy are empty.  0: a mesh.
    // The built-in grid bent by hinges (topology._hinged_grid; hinged_grid true): the listed springs and hinges
    // of its quads, started and pinned as the grid (grid_start, pinned_edge), for the grid_nx x grid_ny,
    // grid_width x grid_length it was built for, which the scene must keep.
    Index grid_nx = 0, grid_ny = 0;
    double grid_width = 0.0, grid_length = 0.0;
    bool hinged_grid = false;
    bool forms_grid() const { return grid_nx > 0 && !hinged_grid; }
    //: The hinges' terms among the listed springs (PAIR_HINGE: built with bend_rigidity > 0), the last this many.
    Index hinge_count() const;
    //: `scene` with the grid's nx, ny, width and length, if this file forms one (else `scene`).
    Scene on_grid(const Scene& scene) const;
    Index level_count() const { return static_cast<Index>(levels.size() / ALGEBRAIC_COLUMNS); }
    //: "" or the ParameterError's text of a scene value that this built-in structure cannot take.
    std::string fixed_problem(const Scene& scene) const;
    //: The particle positions (3, n) m at t = 0 for `scene` (topology.placed).
    std::vector<double> start_positions(const Scene& scene) const;
    //: The pinned particles (n, 1 pinned) at the start positions `pos` (3, n) by `pins` (pinned_mask), or
    //: the ParameterError's text in `problem` (pinned_edge, which a mesh has not; a box holding none).
    std::vector<char> pinned_at(const Scene& scene, const std::vector<double>& pos, const Pins* pins,
                                std::string& problem) const;
};

//: The grid and per-spring constants of a scene (topology.py's Topology).  Particle i = row * nx + col.  A
//: mesh cloth (`mesh` set) has no families, its springs listed (pair_*), nx = n and ny = 1.
struct Topology {
    Index nx = 0, ny = 0, n = 0;
    double dx = 0, dy = 0;                 // m, rest spacing
    std::vector<double> rest_xy;           // (2, n) m, the flat rest sheet centred on 0
    std::vector<double> area;              // (n) m2
    std::vector<Index> family;             // (F) Family of each family present
    std::vector<Index> offset;             // (F)
    std::vector<double> rest;              // (F) m
    std::unique_ptr<bool[]> tension_only;  // (F)
    std::vector<double> stiffness;         // (F, n) N/m
    std::vector<double> damping;           // (F, n) N s/m
    std::vector<double> shape;             // (F, n) strip area / rest length^2 (-)
    std::vector<Index> triangles;          // (m, 3)
    std::vector<double> free;              // (n) 0 for pinned particles, else 1
    double size = 0.0;                     // m, the cloth's larger side (integrators.control)
    const ClothMesh* mesh = nullptr;       // a mesh cloth's built-in structure, else null
    std::vector<double> pair_stiffness, pair_damping;  // (S) N/m, N s/m: a mesh's listed springs
    std::vector<double> start;             // (3, n) m: the positions at t = 0
    Index families() const { return static_cast<Index>(offset.size()); }
    Index triangle_count() const { return static_cast<Index>(triangles.size() / 3); }
    //: Sum (n) over the springs touching each particle of per-spring values (F', n) of the families
    //: with offsets (F'), as Topology.per_particle_sum.
    std::vector<double> per_particle_sum(const double* per_spring, const std::vector<Index>& offsets) const;
};

//: The topology of `scene`: its nx x ny grid, or the cloth `mesh`, with its `pins` (std::invalid_argument
//: for a scene_problem of the mesh or the pins).  A mesh that forms the grid (ClothMesh::forms_grid) wants
//: a `scene` with its nx, ny, width and length (ClothMesh::on_grid).
Topology build_topology(const Scene& scene, const ClothMesh* mesh = nullptr, const Pins* pins = nullptr);

//: The nx x ny grid's topology of `scene`, pinned by pinned_edge and `pins` at grid_start.
Topology grid_topology(const Scene& scene, const Pins* pins);

//: "" or the ParameterError's text of a mesh cloth whose start positions `pos` (3, n) m, thickness/2 included,
//: reach the floor (naming initial_height if the scene places the mesh, else cloth_mesh; scene.validate calls
//: it too).
std::string mesh_floor_problem(const Scene& scene, const double* pos, Index n);

//: scene_problem and build_topology of a cloth from a mesh (cloth_mesh.cpp).
std::string mesh_scene_problem(const Scene& scene, const ClothMesh& mesh, const Pins* pins);
Topology mesh_topology(const Scene& scene, const ClothMesh& mesh, const Pins* pins);

//: The distinct edges (k, 2) of a triangle mesh (m, 3), each (lower, higher), sorted (grid_edges).
std::vector<Index> grid_edges(const std::vector<Index>& triangles);

//: The grids of the multigrid hierarchy, finest first (multigrid.level_sizes).
std::vector<std::pair<Index, Index>> level_sizes(Index nx, Index ny, Index coarsest_side);

// ------------------------------------------------------------------------------------------ control
//: integrators.py's settings (the CG tolerances are implicit.hpp's).
inline constexpr double SMALLEST_STEP = 1e-9;
inline constexpr double STEP_GROWTH = 2.0, STEP_SHRINK = 0.2;
inline constexpr double BLOW_UP_SPEED = 1.0e3;
//: fast_move_cause: a move of the grip or of a collider at this fraction of the blow-up speed or faster is
//: named as a blow-up's likely cause.
inline constexpr double FAST_MOVE = 0.1;
inline constexpr double NEWTON_FRACTION = 0.1;
inline constexpr double FIXED_STEP_NEWTON_TOLERANCE = 1e-6;
inline constexpr double SLEEP_DISTANCE = 5e-4, SLEEP_AFTER = 1.0;
//: self_contact.MARGIN_FRACTION: a candidate list's least margin as a fraction of the smaller spacing.
inline constexpr double MARGIN_FRACTION = 0.05;
//: simulation.STEPS_PER_CALL: particle-steps per call of the step loop.
inline constexpr Index STEPS_PER_CALL = 2'000'000;

// ------------------------------------------------------------------------------------------ simulation
//: A snapshot that does not fit (another grid or scene, values not finite, bytes not written by snapshot()).
struct SnapshotError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

//: The arrays of a Checkpoint's values, in their order: pos, vel, water, prev_pos, prev_vel, prev_water,
//: acceleration, anchor (3n, 3n, n, 3n, 3n, n, 3n, 3n), reference_mass (n), jacobian_along (F n on a grid,
//: a mesh's S springs), jacobian_mass (n), contact reference (3n), the reused Jacobian systems' rule
//: (REUSE_RULE_SIZE) and, on a grid with a multigrid hierarchy, their source (reused_plane.hpp; else empty).
enum KeptArray : int {
    K_POS = 0, K_VEL, K_WATER, K_PREV_POS, K_PREV_VEL, K_PREV_WATER, K_ACCELERATION, K_ANCHOR, K_REFERENCE_MASS,
    K_JACOBIAN_ALONG, K_JACOBIAN_MASS, K_CONTACT_REFERENCE, K_REUSE_RULE, K_REUSE_SOURCE, KEPT
};
//: Where each of a Checkpoint's arrays starts in its values (doubles); the last entry: their end.
using KeptOffsets = std::array<std::size_t, KEPT + 1>;

//: What evolves, copied out of a Simulation (Simulation.snapshot's values): the scene (its inputs may
//: differ from the simulation's), the clock, the preconditioner's reference, self-collision's margin and
//: the arrays `values` (KeptArray).
struct Checkpoint {
    Scene scene;
    Index families = 0;
    double clock[CLOCK_SIZE] = {};
    double plane_reference[3] = {};
    double contact_margin = 0.0;
    std::vector<double> values;
};

//: What a scene holds beside its fields, fixed for a run (Scene.colliders, Scene.grip_keys): the rows of its
//: colliders (colliders.hpp), the arrays of the mesh colliders among them (ColliderMeshes, owned here) and
//: its grip's keys (grip.hpp).  Empty: no collider, no key.
struct Fixtures {
    std::vector<double> colliders;  // (k, COLLIDER_COLUMNS) rows
    // mesh colliders: their headers (one row of MESH_COLUMNS each) and arrays
    std::vector<double> mesh_headers, mesh_vertices, face_normals, edge_normals, vertex_normals;
    std::vector<Index> mesh_triangles, cell_start, cell_items;
    std::vector<double> grip_keys;  // (g, 4) rows: time s, x, y, z m
    //: (c, COLLIDER_KEY_COLUMNS) rows: collider (from 0), time s, x, y, z m, rotation vector rad; by collider,
    //: then time (scene.collider_key_rows).
    std::vector<double> collider_keys;
    //: Each row's k (from 1) among the scene's [[collider_key]] tables, by which a blow-up's message names it
    //: collider_key<k>; empty: the rows' own places (the scene listed its keys collider by collider).
    std::vector<Index> collider_key_numbers;
    std::shared_ptr<const ClothMesh> cloth_mesh;  // the cloth from a mesh file, or none: the nx x ny grid
    std::shared_ptr<const Pins> pins;             // the pins by pinned_vertices, or none
    Index collider_count() const { return static_cast<Index>(colliders.size() / COLLIDER_COLUMNS); }
    //: The mesh arrays as the kernels read them (pointing into this object).
    ColliderMeshes meshes() const;
};

//: A cloth on water with every array it needs (wetcloth.Simulation's set-up), exposing them as a Core.
class Simulation {
public:
    //: Build the simulation of `scene` with its `fixtures` (its values within their ranges;
    //: std::invalid_argument for a grid below 2 x 2, a scene_problem, or a collider within thickness / 2 of
    //: a particle at t = 0).
    explicit Simulation(const Scene& scene, Fixtures fixtures = {});
    Simulation(const Simulation&) = delete;
    Simulation& operator=(const Simulation&) = delete;

    const Scene& scene() const { return scene_; }
    const Fixtures& fixtures() const { return fixtures_; }
    const Topology& topology() const { return topo_; }
    Core& core() { return core_; }
    const Core& core() const { return core_; }
    const ContactLists& contact_lists() const { return lists_; }
    Index n() const { return topo_.n; }
    double time() const { return clock_[TIME]; }
    //: The stability data of the integrator (Integrator.__init__): 1/s2, 1/s, s.
    double omega_squared() const { return omega_squared_; }
    double damping_rate() const { return damping_rate_; }
    double spring_limit() const { return spring_limit_; }
    //: The model's derived values (Model.scene): wick_step_limit s, floor_z m.
    double wick_step_limit() const { return wick_step_limit_; }

    //: Take new input values (Simulation.set_inputs): `next` must differ in inputs only
    //: (std::invalid_argument naming the fixed ones that differ); a changed scene wakes a sleeping cloth.
    //: Returns whether anything changed.
    bool set_inputs(const Scene& next);

    //: Simulate `duration` s (finite, >= 0) more: DONE, or BLOWN_UP with the last good state current
    //: (blow_up_message says what happened; it names the call's end, remembered here, for the grip inputs'
    //: move).
    Status advance(double duration);
    //: The largest local position error (m) a step of the last advance estimated for itself
    //: (Simulation.error_estimate).
    double error_estimate() const { return clock_[LARGEST_ERROR]; }

    //: The outputs (OUTPUT_COUNT): centroid x, y, z, depth (m), wet mass, water mass (kg).
    void outputs(double* row) const;
    //: Vertex positions (n, 3) m, vertex after vertex; saturation (n) of each vertex, 0 to 1.
    void positions(double* xyz) const;
    void wetness(double* out) const;
    //: The BlowUpError's message after advance returned BLOWN_UP.
    std::string blow_up_message() const;

    //: Copy what evolves into `checkpoint` (no allocation once it has held one of this simulation).
    void save(Checkpoint& checkpoint) const;
    //: Return to a checkpoint of this scene (inputs may differ): the run continues exactly as from there.
    //: SnapshotError, with nothing changed, for another grid or scene or values that are not finite.
    void restore(const Checkpoint& checkpoint);
    //: A checkpoint as bytes and back (little-endian, with a checksum); from_bytes refuses (SnapshotError)
    //: bytes that snapshot() did not write.
    std::vector<unsigned char> snapshot() const;
    static Checkpoint from_bytes(const unsigned char* data, std::size_t size);
    void restore(const unsigned char* data, std::size_t size) { restore(from_bytes(data, size)); }

private:
    void set_scene(const Scene& scene);  // Model.scene setter + Simulation._set_scene
    void set_control();                  // Integrator.control()
    void check(const Checkpoint& checkpoint) const;
    void build_plane();                  // make_plane, make_hierarchy
    void build_mesh_plane();             // make_mesh_plane from the ClothMesh's arrays
    Index along_count() const;           // size of the plane's jacobian_along: F n (grid), S (mesh)
    //: The arrays a Checkpoint's values keep, in their order (const for a const self), and where each
    //: starts there (doubles; the last entry: their end).
    template <class Self>
    static auto kept_arrays(Self& self);
    KeptOffsets offsets() const;

    Scene scene_;
    Fixtures fixtures_;
    Topology topo_;
    // Model
    std::vector<double> dry_mass_, volume_, stokes_, capacity_, wick_conductance_;
    std::vector<Index> wick_offsets_;
    std::vector<Index> wick_pairs_, wick_pair_springs_;  // a mesh's wicking links (2, L): its stretch springs
    std::vector<double> wick_pair_conductance_;           // (L) kg/s
    std::vector<Index> cloth_triangles_;                  // a mesh's triangles (m, 3) by their first vertex
    std::vector<double> cloth_shares_;                    // (m, 3) their corner shares (topology.cloth_order)
    double wick_step_limit_ = 0.0, floor_z_ = 0.0;
    std::vector<double> grip_origin_;  // (3, n) m, the start positions; empty when nothing is pinned
    std::vector<double> collider_motion_;  // (colliders, MOTION_COLUMNS) the step loop's scratch; empty without keys
    // Integrator
    double omega_squared_ = 0.0, damping_rate_ = 0.0, spring_limit_ = 0.0;
    // Work, Solver
    std::vector<double> work_;
    std::vector<float> single_work_;  // Work::single_blocks, single_buf
    std::vector<double> solver_;
    std::vector<Index> counters_;
    // Plane and its hierarchy
    std::vector<Index> slots_, order_, rank_, levels_, marker_;
    std::vector<double> plane_, grid_, algebraic_;  // algebraic_: a mesh's hierarchy's values and vectors
    std::vector<float> single_grid_;                 // the V-cycle's single-precision stencils and vectors
    ReusedPlane reused_;
    // Contact
    std::vector<Index> edges_, zone_, contact_counters_;
    std::vector<double> contact_;
    ContactLists lists_;
    // Buffers, clock
    std::vector<double> buffers_;
    double clock_[CLOCK_SIZE] = {};
    double advance_end_ = 0.0;  // s, where the last advance was to end (its blow-up's grip inputs' move)
    Core core_;
};

}  // namespace wc
