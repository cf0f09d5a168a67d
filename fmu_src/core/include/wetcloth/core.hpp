// The compiled core's data: views over flat arrays, one struct per bundle.
//
// Every array is C-contiguous and owned by the caller (NumPy in the Python package, the native
// FMU's own storage there); a struct holds pointers into it, nothing more.  A (rows, n) array of
// doubles is stored row after row: row r of `pos` (3, n) is `pos + r * n` (x, y, z rows), which
// keeps every per-particle loop over contiguous memory that the compiler vectorises.
//
// The structs mirror the Python bundles field for field (wetcloth.kernels' named tuples), so that
// the bindings fill them by name.  No dependency beyond the standard library.
#pragma once

#include <cstddef>
#include <array>
#include <cstdint>
#include <vector>

namespace wc {

using Index = std::int64_t;
//: A column of the algebraic hierarchy's sparse matrices (Algebraic): half an Index's bytes to read.
using Column = std::int32_t;

//: Acceleration of gravity (m/s2), acting along -z.
inline constexpr double GRAVITY = 9.81;

//: The fixed cloth: grid size, spring families (offset, rest length m, tension only, stiffness N/m,
//: damping N s/m per spring), 1 for moving particles, dry mass kg, envelope volume m3, Stokes
//: coefficient 6 pi a eta (N s/m), water capacity kg, wicking links (offsets, conductance kg/s).
//: A cloth from a mesh (grid_x = grid_y = 0, no families) has its springs and wicking links listed
//: instead (listed.hpp): each joins the particles of a column of `pairs` (2, count), the tension-only
//: springs first; its face drag goes over `triangles` (m, 3).  A grid lists none.
struct Cloth {
    Index grid_x = 0, grid_y = 0, n = 0;  // particles per row, rows (both 0 for a mesh), particles
    Index families = 0;                   // F
    const Index* offsets = nullptr;       // (F)
    const double* rest = nullptr;         // (F) m
    const bool* tension_only = nullptr;   // (F)
    const double* stiffness = nullptr;    // (F, n) N/m, zero where a family has no spring
    const double* damping = nullptr;      // (F, n) N s/m
    double* free = nullptr;               // (n) 1 moving, 0 pinned or held (the floor changes it during a step)
    const double* dry_mass = nullptr;     // (n) kg
    const double* volume = nullptr;       // (n) m3
    const double* stokes_coefficient = nullptr;  // (n) N s/m
    const double* capacity = nullptr;     // (n) kg
    Index wick_families = 0;              // W
    const Index* wick_offsets = nullptr;  // (W)
    const double* wick_conductance = nullptr;  // (W, n) kg/s
    Index pair_count = 0, pair_tension_count = 0;  // listed springs S, the first T of them tension-only
    Index pair_buckling_count = 0;                 // the B after them buckling (spring_law.hpp), the rest both ways,
    Index pair_hinge_count = 0;                    // the last H of those hinges' terms: rest length 0, isotropic damping
    const Index* pairs = nullptr;                  // (2, S) first ends, then second ends
    const double* pair_rest = nullptr;             // (S) m
    const double* pair_stiffness = nullptr;        // (S) N/m
    const double* pair_damping = nullptr;          // (S) N s/m
    Index wick_pair_count = 0;                     // listed wicking links L
    const Index* wick_pairs = nullptr;             // (2, L)
    const double* wick_pair_conductance = nullptr;  // (L) kg/s
    Index triangle_count = 0;                      // a mesh's triangles (face drag)
    const Index* triangles = nullptr;              // (m, 3)
    const double* corner_shares = nullptr;         // (m, 3) each corner's share of its triangle (sum 1)
};

//: Whether the cloth is a mesh (listed springs, drag over its triangle list) rather than a grid.
inline bool is_mesh(const Cloth& cloth) { return cloth.grid_x == 0; }

//: The listed springs in the cloth's plane, tension-only and buckling: the first this many.
inline Index in_plane_count(const Cloth& cloth) { return cloth.pair_tension_count + cloth.pair_buckling_count; }

//: The first of the listed springs that are hinges' terms (the last pair_hinge_count).
inline Index first_hinge(const Cloth& cloth) { return cloth.pair_count - cloth.pair_hinge_count; }

//: Doubles a mesh's Work::cells holds per particle: its records (mesh_records.hpp), and room to align them.
inline constexpr Index MESH_RECORD_SLOTS = 32;

//: Rows of Work::cells a grid's face drag uses (water.cpp's drag_forces): both triangles' drag rows (9 each)
//: and their shapes' (5 each: normal, half area, mean submerged fraction, computed once for the three corners).
inline constexpr Index DRAG_CELL_ROWS = 28;

//: Length of each of the DRAG_CELL_ROWS rows of Work::cells: a grid's n + grid_x + 1 slots (water.hpp); for a
//: mesh, whose cells hold its records, MESH_RECORD_SLOTS (n + 1) / DRAG_CELL_ROWS rounded up.
inline Index cells_length(const Cloth& cloth) {
    if (!is_mesh(cloth)) return cloth.n + cloth.grid_x + 1;
    return (MESH_RECORD_SLOTS * (cloth.n + 1) + DRAG_CELL_ROWS - 1) / DRAG_CELL_ROWS;
}

//: The triangle meshes of mesh colliders (collider_mesh.hpp), all in one set of arrays: headers (count,
//: MESH_COLUMNS) each mesh's grid of cells and bounds; vertices (3, V) m where the scene puts them;
//: triangles (T, 3); the unit normals of the faces (T, 3), of their edges (T, 3, 3; edge e from corner e
//: to e + 1: the mean of its two faces') and of the vertices (V, 3; angle-weighted); each mesh's cells
//: as cell_start (cells + 1, from the mesh's first cell) into cell_items (triangle indices).
struct ColliderMeshes {
    Index count = 0, vertex_count = 0;
    const double* headers = nullptr;
    const double* vertices = nullptr;
    const Index* triangles = nullptr;
    const double* face_normals = nullptr;
    const double* edge_normals = nullptr;
    const double* vertex_normals = nullptr;
    const Index* cell_start = nullptr;
    const Index* cell_items = nullptr;
};

//: Scene parameters as the kernels use them (SI units).  `wet_factor` is 0 unless wetness-dependent
//: stiffness is active; `air_density` 0 switches the drag in air off; `floor_z` is the lowest particle
//: centre (m); `colliders` the rows of the analytic colliders (colliders.hpp); `grip_*` the grip that moves
//: the pinned particles (grip.hpp).
struct Physics {
    bool projected = false;
    double wet_factor = 0, water_level = 0, water_density = 0, thickness = 0;
    bool smooth = false, stokes = false;
    double drag_normal = 0, drag_tangential = 0, drag_linear = 0, current_x = 0, current_y = 0;
    double air_density = 0, wind_x = 0, wind_y = 0, wind_z = 0;
    double floor_z = 0, floor_friction = 0, absorption_capacity = 0, absorption_rate = 0;
    double drying_rate = 0, wicking_rate = 0, wick_step_limit = 0;
    bool skip_idle = true;
    Index collider_count = 0;            // analytic colliders (colliders.hpp), none by default
    const double* colliders = nullptr;   // (collider_count, COLLIDER_COLUMNS) rows
    ColliderMeshes meshes;               // the triangles of the mesh colliders among them
    double grip_x = 0, grip_y = 0, grip_z = 0;  // m (inputs): the grip's displacement at the interval's end (grip.hpp)
    Index grip_key_count = 0;            // the grip's keys (grip.hpp), none by default
    const double* grip_keys = nullptr;   // (grip_key_count, 4) rows: time s, x, y, z m
    const double* grip_origin = nullptr; // (3, n) m: where the grip's zero displacement holds the particles (t = 0)
    Index collider_key_count = 0;          // the colliders' keys (collider_motion.hpp), none by default
    const double* collider_keys = nullptr; // (collider_key_count, 8) rows: collider (from 0), time s, x, y, z m,
                                           // rotation vector rx, ry, rz rad
    double* collider_motion = nullptr;     // (collider_count, MOTION_COLUMNS) scratch the step loop sets; null
                                           // without keys (every collider still)
};

//: Scratch and results: force (3, n) N; submerged (n) fraction; saturation (n); blocks (6, n)
//: per-particle symmetric 3x3 blocks (xx, yy, zz, xy, xz, yz) of the system matrix;
//: diagonal_blocks (6, n) the springs' part of its diagonal blocks; direction (F, 3, n), along,
//: across (F, n) each spring's block; buf (4, n); cells (DRAG_CELL_ROWS,
//: cells_length) face-drag rows; wick_buffer (6, n);
//: pair_direction (3, S), pair_along, pair_across (S) the listed springs' blocks; single_blocks (F, 5, n)
//: each family spring's block in single precision for CG's products (rows ux, uy, uz, across, along - across);
//: single_buf (6, n) those products' scratch.
struct Work {
    double* force = nullptr;
    double* submerged = nullptr;
    double* saturation = nullptr;
    double* blocks = nullptr;
    double* diagonal_blocks = nullptr;
    double* direction = nullptr;
    double* along = nullptr;
    double* across = nullptr;
    double* buf = nullptr;
    double* cells = nullptr;
    double* wick_buffer = nullptr;
    double* pair_direction = nullptr;
    double* pair_along = nullptr;
    double* pair_across = nullptr;
    float* single_blocks = nullptr;
    float* single_buf = nullptr;
};

//: t^T S t for the symmetric 3x3 block S of slots s (xx, yy, zz, xy, xz, yz; a Work::blocks layout) and
//: the vector t = (tx, ty, tz).
inline double block_quadratic(const double* s, double tx, double ty, double tz) {
    return s[0] * tx * tx + s[1] * ty * ty + s[2] * tz * tz + 2.0 * (s[3] * tx * ty + s[4] * tx * tz + s[5] * ty * tz);
}

//: Integrator codes (Control::integrator).
enum Integrator : Index { EXPLICIT_EULER = 0, SYMPLECTIC_EULER = 1, IMPLICIT_EULER = 2, BDF2 = 3 };

//: Integrator and controller settings (see wetcloth/integrators.py): tolerance (-), allowed local
//: position error per step (m, 0 = fixed steps of max_step s), newton_tolerance (m), cg_tolerance
//: (-), the explicit schemes' stability data, step limits and factors, the blow-up speed (m/s) and
//: the sleep rule (sleep_distance m for sleep_after s).
struct Control {
    Index integrator = BDF2;
    double tolerance = 0, allowed = 0, max_step = 0, newton_tolerance = 0, cg_tolerance = 0;
    double omega_squared = 0, buoyancy_omega_squared = 0, damping_rate = 0, spring_limit = 0;
    double drag_rate_offset = 0, drag_rate_slope = 0, smallest_step = 0, growth = 0, shrink = 0;
    double blow_up_speed = 0, sleep_distance = 0, sleep_after = 0;
};

//: Slots of Solver::counters.
enum SolverCounter : Index {
    NEWTON_ITERATIONS = 0, CG_ITERATIONS = 1, FACTORISATIONS = 2, UNCONVERGED = 3, RESTARTS = 4, SOLVER_COUNTERS
};

//: Scratch of the implicit steps, each (3, n) unless noted: mass (n) kg; rhs, dv, r, z, p, ap of the
//: linear solves; hat_pos, hat_vel the BDF2 history terms; predicted the extrapolated positions;
//: step_acceleration (3, n) m/s2; counters (4) int64.
//: The particles sliding during a step: index (count), the surface's unit outward normal (3 per particle),
//: its friction coefficient, the direction of sliding at the step's start (3 per particle, a unit vector
//: along the surface), the prescribed velocity along the normal (m/s, set by the step) and whether the
//: support is the floor (1) or a collider (0); the collider (-1: the floor).  On a curved collider the
//: normal turns as the particle slides, at `turning` (3 per particle, 1/s: the surface's shape operator
//: applied to the sliding velocity at the step's start, zero on a flat surface), and the step takes the
//: surface at the path's predicted end: `normal` and `direction` are the surface's there, start_normal and
//: start_direction those at the step's start; `centripetal` is the path's kappa s^2 (m/s2) and `curving`
//: h^2 kappa s^2 / 2 (m) how much farther out along `normal` the end's tangent plane stands than the start.
struct Sliding {
    std::vector<Index> index;
    std::vector<double> normal;
    std::vector<double> friction;
    std::vector<double> direction;
    std::vector<double> normal_speed;
    std::vector<char> on_floor;
    std::vector<double> surface_velocity;  // (3 each) m/s: a moving collider's, else 0
    std::vector<Index> collider;
    std::vector<double> start_normal, start_direction, turning;  // (3 each)
    std::vector<double> centripetal;
    std::vector<double> curving;
    //: Friction by IPC's smoothed law on the velocity at the step's end (fixed steps: a frame-long step's
    //: friction held to its start's direction reversed particles' motion and stop_reversed took back cm),
    //: else Coulomb's against the start's direction, stopped particles put at rest (adaptive steps).
    bool smoothed = false;
    //: With it, each particle's normal force (N) for the step: lag_normal_force's.
    std::vector<double> lagged_onto;
    Index count() const { return static_cast<Index>(index.size()); }
    //: Keep the first `count` particles of the set (0: none); their per-step values (normal_speed, curving:
    //: prescribe_normal_speed's) zero.  (sliding.cpp)
    void resize(Index count);
    //: Particle `from`'s entries, all but the per-step values, at place `to` (compacting the set: to <= from).
    void move_entry(Index to, Index from);
};

//: A mesh collider's features near the cloth's elements at a step's start (a moving mesh's; at fixed steps a
//: still mesh's too, and a free particle against a still analytic collider's tangent plane:
//: collider_analytic_supports.hpp), and at fixed steps the cloth's pairs with itself near then
//: (self_contact/supports.hpp), as supports the implicit step sees (collider_supports.hpp): per term, the pair's
//: cloth particles (SUPPORT_POINTS, -1 where unused) and their weights (the pair's closest-point weights,
//: self_contact/geometry.hpp), and in the collider's table frame the contact normal at the start (3) and the
//: weighted sum of its own points (3, m); its collider.
//: For the step being tried: each term's world normal (3) and offset (m), so that its gap is
//: g = offset + sum_k weight_k normal . x_k, and whether it presses (g below `distance`); stiffness (N/m),
//: distance (m) and scale (bh^2, s^2: the position Jacobian's factor in the step's matrix).  Friction: each
//: term's collider's coefficient (-), its normal force at the step's start (N, lagged: fixed for the step) and
//: the collider's points' weighted velocity at the step's end (3, m/s), so that the pair's relative velocity
//: is that plus sum_k weight_k v_k; at the last force evaluation, its friction's stiffness in that velocity
//: (6 per term, xx yy zz xy xz yz, N s/m); velocity_scale (bh, s: the velocity Jacobian's factor in the
//: step's matrix); any_friction whether a term has a coefficient above 0; self_stiffness (N/m) and self_friction
//: (-) the penalty's stiffness and the coefficient of the cloth's pairs with itself.
//: anticipated: the terms the step's matrix holds stiff before they press (those a Newton correction pressed
//: at its full length where the line search stalled short of it, bdf2_step: the wall it met within the step);
//: stiff: whether a term's stiffness is in the matrix at the last force evaluation (pressing or anticipated).
//: arrived: whether a term's normal force was lagged from an iterate within the step (collider_supports.hpp,
//: lag_arriving_normal_force; drop_departed undoes it where a converged solve leaves the term apart).
struct Supports {
    std::vector<Index> points;
    std::vector<double> weights;
    std::vector<double> table_normal, table_part;
    std::vector<Index> collider;
    std::vector<double> normal, offset;
    std::vector<char> pressing, anticipated, stiff, arrived;
    std::vector<double> friction, normal_force, collider_velocity, friction_block;
    double stiffness = 0.0, distance = 0.0, scale = 0.0, velocity_scale = 0.0;
    double self_stiffness = 0.0, self_friction = 0.0;
    bool any_friction = false;
    Index count() const { return static_cast<Index>(collider.size()); }
};

struct Solver {
    double* mass = nullptr;
    double* rhs = nullptr;
    double* dv = nullptr;
    double* r = nullptr;
    double* z = nullptr;
    double* p = nullptr;
    double* ap = nullptr;
    double* hat_pos = nullptr;
    double* hat_vel = nullptr;
    double* predicted = nullptr;
    double* step_acceleration = nullptr;
    Index* counters = nullptr;
    Sliding* sliding = nullptr;  // the particles sliding on a surface during the step (sliding.hpp), or none
    Supports* supports = nullptr;  // mesh colliders' features the step's solve sees (collider_supports.hpp), or none
    bool near_itself = false;  // whether the cloth's self-collision list holds candidate pairs at the step's start
};

//: Columns of Hierarchy::levels.
enum LevelColumn : Index { NX = 0, NY = 1, START = 2, PAD_X = 3 };

//: The preconditioner's scalar systems, one per component of each particle's frame: t1 and t2 (the
//: in-plane stiffness, factored when the step or the masses change much) and the normal (from the
//: Jacobian, at every Newton iteration).
inline constexpr Index COMPONENTS = 3;
inline constexpr Index NORMAL = 2;

//: The multigrid hierarchy (multigrid.cpp): levels (L, 4) int64 (nx, ny, first padded index, padded
//: row length), level 0 the particles' grid; coef (COMPONENTS, 9, size) the components' 9-point
//: stencils; inverse_diagonal, x, b (COMPONENTS, size); row (grid_x + 3) scratch.  The V-cycle runs
//: in single precision on its own copies: single_coef (COMPONENTS, 9, size) and single_inverse_diagonal
//: (COMPONENTS, size) of every level but the coarsest (galerkin writes them), and its vectors single_x,
//: single_b, single_r (COMPONENTS, size); it takes b of level 0 and x of the coarsest level from the
//: double vectors and gives back b of the coarsest level and x of level 0 there.
struct Hierarchy {
    Index level_count = 0;
    Index size = 0;
    Index* levels = nullptr;
    double* coef = nullptr;
    double* inverse_diagonal = nullptr;
    double* x = nullptr;
    double* b = nullptr;
    double* row = nullptr;
    float* single_coef = nullptr;
    float* single_inverse_diagonal = nullptr;
    float* single_x = nullptr;
    float* single_b = nullptr;
    float* single_r = nullptr;
};

//: Columns of Algebraic::levels.
enum AlgebraicColumn : Index { SIZE = 0, VECTOR = 1, A_ROWS = 2, P_ROWS = 3, R_ROWS = 4, ALGEBRAIC_COLUMNS = 5 };

//: A mesh's algebraic multigrid hierarchy (mesh_plane.cpp; aggregation from the spring graph, built once
//: in Python): levels (L, ALGEBRAIC_COLUMNS) int64 per level its size n_l, its first index in the
//: per-level vectors, and its first index in a_start, p_start and r_start.  Level l's matrix in CSR:
//: rows a_start[A_ROWS + i] .. a_start[A_ROWS + i + 1] of a_column (level-local columns, int32) and of
//: a_value (COMPONENTS, entries); diagonal (vectors) the position of each row's diagonal entry.  For
//: l < L - 1 the prolongator P_l (n_l, n_{l+1}) in p_start, p_column, p_value and its transpose R_l in
//: r_start, r_column, r_value (columns int32).  spring_entries (2, coupled) the positions of each coupled listed
//: spring's (i, j) and (j, i) entries at level 0: the in-plane springs (in_plane_count), then the hinges' terms
//: when the systems from the Jacobian couple them (fixed steps: preconditioner.plane_for); inverse_diagonal, x,
//: b, r (COMPONENTS, vectors: r a level's residual after its forward sweep, which R restricts row by row; the
//: cycle keeps x, b and r's first two rows as t1 and t2 side by side, [2 v + c]: mesh_plane.cpp); marker (n_0)
//: scratch.  The coarsest level is solved by the plane's band factors.  A grid has none (L = 0).
struct Algebraic {
    Index level_count = 0;
    Index entries = 0, vectors = 0;
    const Index* levels = nullptr;
    const Index* a_start = nullptr;
    const Column* a_column = nullptr;
    double* a_value = nullptr;
    const Index* diagonal = nullptr;
    const Index* p_start = nullptr;
    const Column* p_column = nullptr;
    const double* p_value = nullptr;
    const Index* r_start = nullptr;
    const Column* r_column = nullptr;
    const double* r_value = nullptr;
    const Index* spring_entries = nullptr;
    Index coupled = 0;
    double* inverse_diagonal = nullptr;
    double* x = nullptr;
    double* b = nullptr;
    double* r = nullptr;
    Index* marker = nullptr;
};

//: The plane preconditioner (plane.cpp): per-spring stiffness (F, n) N/m; slots (F) each family's
//: stencil slot (-1: left out); the hierarchy; on the coarsest level order (n_c) the padded index
//: of each band position and rank (rank_size) its inverse (-1 off the grid); bands and rows
//: (COMPONENTS, n_c, kd + 1) the banded Cholesky factors (band.cpp); reference (4) [factored scale
//: s2, factored?, from the Jacobian?, normal component by its system (1) or its diagonal (0)?],
//: reference_mass (n) kg; shares (2, F); jacobian_along (F, n)
//: kg, jacobian_mass (n) kg; frame (3, 3, n) each particle's axes t1, t2, n; normal (n) the normal
//: component's diagonal (kg); local (COMPONENTS, n_c); algebraic a mesh's hierarchy, whose coarsest
//: level order and rank number (a mesh has no grid levels).
struct Plane {
    Index families = 0;
    const double* stiffness = nullptr;
    const Index* slots = nullptr;
    Hierarchy grid;
    Index coarse_n = 0;  // n_c
    Index kd = 0;        // half-bandwidth of the coarsest level's band matrices
    const Index* order = nullptr;
    const Index* rank = nullptr;
    Index rank_size = 0;
    double* bands = nullptr;
    double* rows = nullptr;
    double* reference = nullptr;
    double* reference_mass = nullptr;
    const double* shares = nullptr;
    double* jacobian_along = nullptr;
    double* jacobian_mass = nullptr;
    double* frame = nullptr;
    double* normal = nullptr;
    double* local = nullptr;
    Algebraic algebraic;  // a mesh's hierarchy (mesh_plane.cpp)
};

//: The in-plane systems of the plane preconditioner built from the Jacobian at one Newton iteration and
//: reused for the linear solves of the adaptive steps after it (reused_plane.hpp), while `Core::plane`
//: keeps the rest-stiffness systems that filter the step's error estimate.  `plane` views `storage` for
//: what it factors (stencils, inverse diagonals, band factors, reference), `single_storage` for the
//: V-cycle's single-precision stencils and inverse diagonals, and shares everything else with
//: Core::plane (its frame and normal diagonal among them); frame_at_build (3, 3, n) is the frame it was
//: projected on.  `source` holds what it was built from, so that a restored run rebuilds the same
//: factors: positions (3, n) m, mass (n) kg, blocks (6, n), direction (F, 3, n), along, across (F, n)
//: (Work's); `rule` the state of the rule that decides when to rebuild it (reused_plane.hpp).
struct ReusedPlane {
    Plane plane;
    std::vector<double> storage;
    std::vector<float> single_storage;
    std::vector<double> frame_at_build;
    std::vector<double> source;
    std::array<double, 3> rule{};
};

//: The cloth's pairs with mesh colliders' features near the reference positions, kept across steps
//: (collider_edges.cpp), in the frame they were gathered in.
struct ColliderPairList {
    std::vector<std::array<Index, 7>> pairs;  // with the bits of their distances at the reference (m)
    std::vector<double> reference;  // (3, n) the positions the pairs were gathered at, m
    std::vector<double> allowance;  // (n) m: how far each particle may be from them at a step's start
    std::vector<double> stride;     // (n) m: how far each particle may move in a step
    std::vector<double> motion;     // (n) m: each particle's motion over the last step the edges' pass looked at
    double margin = 0.0;            // m: the least allowance (0: no list)
    bool clear = false;             // gathered with the cloth far from every mesh: no pairs, one allowance for all
    const void* key[2] = {nullptr, nullptr};  // the meshes and collider rows it was gathered from
};

//: What the checks of a candidate list keep between steps (self_contact/tiers.cpp): per tier (the fine tier
//: last), its windows' shapes in the reference positions `reference` (3, n) m, if `shaped`, and their fits at
//: the positions `end` (3, n) m where the last step checked ended, if `kept` (the next step starts there: its
//: check then fits only its own end); both for the tiers as cut `tiers_made` times.  `next` and `made`: the
//: fits of the current check at its end; `cells`, `shape`, `start_fit`, `end_fit`: scratch.
struct WindowFits {
    std::vector<double> reference, end;
    Index tiers_made = -1;
    std::vector<std::vector<double>> shapes, at, next;
    std::vector<char> shaped, kept, made;
    std::vector<double> cells, shape, start_fit, end_fit;
};

//: Self-collision's candidate lists and scratch, owned by the core (self_contact/*.cpp): the
//: point-triangle (particle, triangle) and edge-edge (edge, edge) candidate pairs, and whatever
//: scratch the broad phase and the response need between calls; the rest sheet's tiers of cells and
//: the list's allowance in each (self_contact/tiers.hpp), derived from the reference and the margin.
struct ContactLists {
    std::vector<Index> point_triangle;  // (2, count): first row particles, then triangles
    std::vector<Index> edge_edge;       // (2, count)
    std::vector<double> scratch;        // start distances and other per-step scratch
    std::vector<Index> index_scratch;   // hash tables and other integer scratch
    std::vector<Index> tiers;           // each tier's cells of the rest sheet (self_contact/tiers.hpp)
    std::vector<double> allowances;     // (tiers) m: how far each tier's windows may move beyond a rigid motion
    std::vector<double> particle_allowances;  // (2, n) m: how far each particle may in the finest tier, for the
                                              // pairs of the fine tier's windows, then the others (empty: none)
    std::vector<double> tier_scratch;   // the tiers' sums and fits
    Index tiers_made = 0;               // how many times `tiers` was cut
    std::vector<double> tiers_rest;     // (3, n) m: the rest sheet `tiers` was last cut from
    std::vector<Index> tiers_elements;  // and its triangles' and edges' rows, one after the other
    std::vector<std::vector<Index>> far_cells;  // per tier, its cells' elements for the far pairs' search, or
                                                // empty (far_pairs.cpp); for the tiers as cut `far_cells_made` times
    Index far_cells_made = -1;
    // The rest sheet's figures for showing windows free of pairs (self_contact/flat_windows.cpp), for the tiers
    // as cut `flat_made` times: whether the rest sheet is convex; each triangle's rest edges' inverse (2 x 2);
    // each cell of the finest tier's holding a particle of the sheet's rim (1) or not (0).
    Index flat_made = -1;
    bool flat_convex = false;
    std::vector<double> flat_inverse;
    std::vector<char> flat_rim;
    std::vector<double> flat_triangles;           // per triangle, figures of the positions
    std::vector<std::vector<double>> flat_cells;  // per local tier, its cells' figures
    std::vector<char> flat_inside;                // (n) the particles of the windows not shown free of pairs
    WindowFits fits;                    // the tiers' shapes and fits kept between steps
    std::vector<Index> resting;         // (n, 3) what a particle held on a layer rests on (-1 padding)
    std::vector<double> resting_normal;  // (n, 3) the unit normal from that support to the particle
    std::vector<double> supported_normal;  // (3, n) the outward normal of the collider a particle lay or slid on
                                           // through the step, zero if none (empty: none at all); the stage does
                                           // not push it into that collider (self_contact/response.hpp)
    std::vector<std::array<Index, 7>> collider_pairs;  // the cloth's pairs with mesh colliders' features (collider_edges.hpp)
    ColliderPairList collider_kept;      // the still meshes' pairs, in the world
    std::vector<ColliderPairList> collider_moving_kept;  // (collider_count) a moving mesh k's, in its table frame
    std::vector<double> collider_frame;  // (3, 3, n) scratch: the cloth's start, end and end velocity in a table frame
    std::vector<double> collider_free;   // (n) Cloth::free during the step: 0 also for the particles held in it
    std::vector<double> collider_rest;   // (4, n) a particle resting on a mesh's edge or vertex: its normal (3), friction
    std::vector<Index> collider_items;   // their search's scratch
    std::vector<Index> collider_stamp;  // (mesh triangles) scratch: the last element that saw each
    std::vector<Index> collider_vertex_stamp;  // (mesh vertices) scratch: the last cloth edge that took each as an end
    std::vector<double> collider_start;  // (count) their distances at the step's start, m
    std::vector<double> collider_end;    // (3, n) the end positions when they were gathered, m
    std::vector<double> collider_moved;  // (n) scratch: each particle's move from the kept list's reference, m
    std::vector<Index> collider_pushed;  // (n) 1 for the particles they pushed
    std::vector<double> collider_normals;  // (3, n) the direction of each one's last push
    std::vector<Index> settle_moved;     // (n) scratch: the settling passes' clock when a push last moved each particle
    std::vector<Index> settle_checked;   // (count) scratch: and, times 2, when each candidate pair was last checked
                                         // (plus 1 if that check left it to the impact zones)
    Index point_triangle_count() const { return static_cast<Index>(point_triangle.size() / 2); }
    Index edge_edge_count() const { return static_cast<Index>(edge_edge.size() / 2); }
};

//: Slots of Contact::counters: candidate lists built; steps that had candidates; passes over them;
//: pairs pushed apart; rounds of impact zones; steps undone as a last resort.
enum ContactCounter : Index { REBUILDS = 0, BUSY_STEPS = 1, PASSES = 2, RESPONSES = 3, ZONE_ROUNDS = 4, FREEZES = 5 };
inline constexpr Index CONTACT_COUNTERS = 6;
inline constexpr Index ZONE_ROWS = 25;

//: Self-collision (self_contact/): enabled; friction (-); least_margin (m); rest_gap (m); typical_gap (m);
//: triangles (m, 3) and edges (k, 2) particle indices; rest positions (3, n) m; the candidate
//: list's reference positions (3, n) and margin (1) m (0: none); zone (n) and zone_sums
//: (ZONE_ROWS, n) scratch of the impact zones; counters (CONTACT_COUNTERS); the lists.
struct Contact {
    bool enabled = false;
    bool layers_solved = false;  // this step's solve held the listed pairs (self_contact/supports.hpp): the stage
                                 // leaves pairs KEPT_FRACTION of the thickness apart (self_contact/response.hpp)
    double friction = 0, least_margin = 0, rest_gap = 0, typical_gap = 0;
    Index triangle_count = 0;
    const Index* triangles = nullptr;
    Index edge_count = 0;
    const Index* edges = nullptr;
    const double* rest = nullptr;
    double* reference = nullptr;
    double* margin = nullptr;
    Index* zone = nullptr;
    double* zone_sums = nullptr;
    Index* counters = nullptr;
    ContactLists* lists = nullptr;
};

//: State buffers: current and trial (pos, vel (3, n), water (n)), the BDF2 history (state before the
//: last step; acceleration (3, n) m/s2 the last step implied at its end), the sleep anchor (3, n)
//: and held (n): 1 for the particles the floor holds during the current step.
struct Buffers {
    double* pos = nullptr;
    double* vel = nullptr;
    double* water = nullptr;
    double* trial_pos = nullptr;
    double* trial_vel = nullptr;
    double* trial_water = nullptr;
    double* prev_pos = nullptr;
    double* prev_vel = nullptr;
    double* prev_water = nullptr;
    double* acceleration = nullptr;
    double* anchor = nullptr;
    double* held = nullptr;
};

//: Slots of the clock (double): simulated time (s); the controller's next step (s); the last accepted
//: step (s; 0: no history for BDF2); the fastest particle's speed (m/s); time spent still (s), time
//: since stillness was last checked (s), whether water moved since, whether asleep; accepted and
//: rejected steps; the step that blew up (s); BDF2's last Newton rate (-) and the correction it
//: followed (m/s), the kind of its first guess, its last solve's CG iterations; the largest local
//: position error (m) an accepted step estimated for itself since the caller last reset it.
enum ClockSlot : Index {
    TIME = 0, NEXT_STEP, LAST_STEP, SPEED, CALM_TIME, UNCHECKED_TIME, EXCHANGING, SLEEPING, STEPS, REJECTED,
    FAILED_STEP, NEWTON_RATE, RATE_CORRECTION, FIRST_GUESS, LAST_SOLVE, LARGEST_ERROR, CLOCK_SIZE
};

//: What the step loop returns.
enum Status : Index { DONE = 0, BLOWN_UP = 1, PAUSED = 2 };

//: Everything one step loop works on.
struct Core {
    Cloth cloth;
    Physics phys;
    Control control;
    Work work;
    Solver solver;
    Plane plane;
    ReusedPlane* reused = nullptr;  // adaptive steps' Jacobian systems (reused_plane.hpp), or none
    Contact contact;
    Buffers buf;
    Sliding sliding;
    Supports supports;
    double* clock = nullptr;  // (CLOCK_SIZE)
};

}  // namespace wc
