// The bundles' views (convert.hpp), field by field.
#include "convert.hpp"

#include <stdexcept>

#include "wetcloth/collider_mesh.hpp"
#include "wetcloth/collider_motion.hpp"
#include "wetcloth/colliders.hpp"

namespace wc::py {

std::vector<std::function<void(nb::module_&)>>& registry() {
    static std::vector<std::function<void(nb::module_&)>> bindings;
    return bindings;
}

Cloth cloth_from(nb::handle h) {
    Cloth c;
    c.grid_x = number<Index>(h, "grid_x");
    c.grid_y = number<Index>(h, "grid_y");
    c.n = size_of(h.attr("dry_mass"));
    const Index n = c.n;
    c.offsets = array<const Index>(h, "offsets");
    c.families = size_of(h.attr("offsets"));
    const Index f = c.families;
    c.rest = array<const double>(h, "rest", f);
    c.tension_only = array<const bool>(h, "tension_only", f);
    c.stiffness = array<const double>(h, "stiffness", f * n);
    c.damping = array<const double>(h, "damping", f * n);
    c.free = array<double>(h, "free", n);
    c.dry_mass = array<const double>(h, "dry_mass", n);
    c.volume = array<const double>(h, "volume", n);
    c.stokes_coefficient = array<const double>(h, "stokes_coefficient", n);
    c.capacity = array<const double>(h, "capacity", n);
    c.wick_offsets = array<const Index>(h, "wick_offsets");
    c.wick_families = size_of(h.attr("wick_offsets"));
    c.wick_conductance = array<const double>(h, "wick_conductance", c.wick_families * n);
    c.pair_count = size_of(h.attr("pair_rest"));
    c.pair_tension_count = number<Index>(h, "pair_tension_count");
    c.pair_buckling_count = number<Index>(h, "pair_buckling_count");
    c.pair_hinge_count = number<Index>(h, "pair_hinge_count");
    c.pairs = array<const Index>(h, "pairs", 2 * c.pair_count);
    c.pair_rest = array<const double>(h, "pair_rest", c.pair_count);
    c.pair_stiffness = array<const double>(h, "pair_stiffness", c.pair_count);
    c.pair_damping = array<const double>(h, "pair_damping", c.pair_count);
    c.wick_pair_count = size_of(h.attr("wick_pair_conductance"));
    c.wick_pairs = array<const Index>(h, "wick_pairs", 2 * c.wick_pair_count);
    c.wick_pair_conductance = array<const double>(h, "wick_pair_conductance", c.wick_pair_count);
    c.triangle_count = size_of(h.attr("triangles")) / 3;
    c.triangles = array<const Index>(h, "triangles", 3 * c.triangle_count);
    c.corner_shares = array<const double>(h, "corner_shares", 3 * c.triangle_count);
    if (c.grid_x * c.grid_y != (is_mesh(c) ? 0 : n) || c.pair_tension_count < 0 || c.pair_buckling_count < 0 ||
        c.pair_hinge_count < 0 || in_plane_count(c) + c.pair_hinge_count > c.pair_count)
        throw std::invalid_argument("cloth: grid_x * grid_y must be the particle count (0 for a mesh) and "
                                    "pair_tension_count + pair_buckling_count + pair_hinge_count within the listed springs");
    return c;
}

ColliderMeshes meshes_from(nb::handle h) {
    ColliderMeshes m;
    m.count = size_of(h.attr("headers")) / MESH_COLUMNS;
    if (m.count == 0) return m;
    m.headers = array<const double>(h, "headers", m.count * MESH_COLUMNS);
    m.vertex_count = size_of(h.attr("vertices")) / 3;
    const Index triangles = size_of(h.attr("triangles")) / 3;
    m.vertices = array<const double>(h, "vertices", 3 * m.vertex_count);
    m.triangles = array<const Index>(h, "triangles", 3 * triangles);
    m.face_normals = array<const double>(h, "face_normals", 3 * triangles);
    m.edge_normals = array<const double>(h, "edge_normals", 9 * triangles);
    m.vertex_normals = array<const double>(h, "vertex_normals", 3 * m.vertex_count);
    m.cell_start = array<const Index>(h, "cell_start");
    m.cell_items = array<const Index>(h, "cell_items");
    return m;
}

Physics physics_from(nb::handle h) {
    Physics p;
    p.projected = number<bool>(h, "projected");
    p.wet_factor = number<double>(h, "wet_factor");
    p.water_level = number<double>(h, "water_level");
    p.water_density = number<double>(h, "water_density");
    p.thickness = number<double>(h, "thickness");
    p.smooth = number<bool>(h, "smooth");
    p.stokes = number<bool>(h, "stokes");
    p.drag_normal = number<double>(h, "drag_normal");
    p.drag_tangential = number<double>(h, "drag_tangential");
    p.drag_linear = number<double>(h, "drag_linear");
    p.current_x = number<double>(h, "current_x");
    p.current_y = number<double>(h, "current_y");
    p.air_density = number<double>(h, "air_density");
    p.wind_x = number<double>(h, "wind_x");
    p.wind_y = number<double>(h, "wind_y");
    p.wind_z = number<double>(h, "wind_z");
    p.floor_z = number<double>(h, "floor_z");
    p.floor_friction = number<double>(h, "floor_friction");
    p.absorption_capacity = number<double>(h, "absorption_capacity");
    p.absorption_rate = number<double>(h, "absorption_rate");
    p.drying_rate = number<double>(h, "drying_rate");
    p.wicking_rate = number<double>(h, "wicking_rate");
    p.wick_step_limit = number<double>(h, "wick_step_limit");
    p.skip_idle = number<bool>(h, "skip_idle");
    p.collider_count = size_of(h.attr("colliders")) / COLLIDER_COLUMNS;
    p.colliders = p.collider_count > 0 ? array<const double>(h, "colliders", p.collider_count * COLLIDER_COLUMNS)
                                       : nullptr;
    p.meshes = meshes_from(h.attr("meshes"));
    p.grip_x = number<double>(h, "grip_x");
    p.grip_y = number<double>(h, "grip_y");
    p.grip_z = number<double>(h, "grip_z");
    p.grip_key_count = size_of(h.attr("grip_keys")) / 4;
    p.grip_keys = p.grip_key_count > 0 ? array<const double>(h, "grip_keys", 4 * p.grip_key_count) : nullptr;
    p.grip_origin = size_of(h.attr("grip_origin")) > 0 ? array<const double>(h, "grip_origin") : nullptr;
    p.collider_key_count = size_of(h.attr("collider_keys")) / COLLIDER_KEY_COLUMNS;
    p.collider_keys = p.collider_key_count > 0
                          ? array<const double>(h, "collider_keys", COLLIDER_KEY_COLUMNS * p.collider_key_count)
                          : nullptr;
    p.collider_motion = p.collider_key_count > 0
                            ? array<double>(h, "collider_motion", MOTION_COLUMNS * p.collider_count)
                            : nullptr;
    return p;
}

Control control_from(nb::handle h) {
    Control c;
    c.integrator = number<Index>(h, "integrator");
    c.tolerance = number<double>(h, "tolerance");
    c.allowed = number<double>(h, "allowed");
    c.max_step = number<double>(h, "max_step");
    c.newton_tolerance = number<double>(h, "newton_tolerance");
    c.cg_tolerance = number<double>(h, "cg_tolerance");
    c.omega_squared = number<double>(h, "omega_squared");
    c.buoyancy_omega_squared = number<double>(h, "buoyancy_omega_squared");
    c.damping_rate = number<double>(h, "damping_rate");
    c.spring_limit = number<double>(h, "spring_limit");
    c.drag_rate_offset = number<double>(h, "drag_rate_offset");
    c.drag_rate_slope = number<double>(h, "drag_rate_slope");
    c.smallest_step = number<double>(h, "smallest_step");
    c.growth = number<double>(h, "growth");
    c.shrink = number<double>(h, "shrink");
    c.blow_up_speed = number<double>(h, "blow_up_speed");
    c.sleep_distance = number<double>(h, "sleep_distance");
    c.sleep_after = number<double>(h, "sleep_after");
    return c;
}

Work work_from(nb::handle h, const Cloth& cloth) {
    const Index n = cloth.n, f = cloth.families;
    Work w;
    w.force = array<double>(h, "force", 3 * n);
    w.submerged = array<double>(h, "submerged", n);
    w.saturation = array<double>(h, "saturation", n);
    w.blocks = array<double>(h, "blocks", 6 * n);
    w.diagonal_blocks = array<double>(h, "diagonal_blocks", 6 * n);
    w.direction = array<double>(h, "direction", f * 3 * n);
    w.along = array<double>(h, "along", f * n);
    w.across = array<double>(h, "across", f * n);
    w.buf = array<double>(h, "buf", 4 * n);
    w.cells = array<double>(h, "cells", DRAG_CELL_ROWS * cells_length(cloth));
    w.wick_buffer = array<double>(h, "wick_buffer", 6 * n);
    w.pair_direction = array<double>(h, "pair_direction", 3 * cloth.pair_count);
    w.pair_along = array<double>(h, "pair_along", cloth.pair_count);
    w.pair_across = array<double>(h, "pair_across", cloth.pair_count);
    w.single_blocks = array<float>(h, "single_blocks", f * 5 * n);
    w.single_buf = array<float>(h, "single_buf", 6 * n);
    return w;
}

Solver solver_from(nb::handle h, Index n) {
    Solver s;
    s.mass = array<double>(h, "mass", n);
    s.rhs = array<double>(h, "rhs", 3 * n);
    s.dv = array<double>(h, "dv", 3 * n);
    s.r = array<double>(h, "r", 3 * n);
    s.z = array<double>(h, "z", 3 * n);
    s.p = array<double>(h, "p", 3 * n);
    s.ap = array<double>(h, "ap", 3 * n);
    s.hat_pos = array<double>(h, "hat_pos", 3 * n);
    s.hat_vel = array<double>(h, "hat_vel", 3 * n);
    s.predicted = array<double>(h, "predicted", 3 * n);
    s.step_acceleration = array<double>(h, "step_acceleration", 3 * n);
    s.counters = array<Index>(h, "counters", SOLVER_COUNTERS);
    return s;
}

Hierarchy hierarchy_from(nb::handle h) {
    Hierarchy g;
    g.levels = array<Index>(h, "levels");
    g.level_count = size_of(h.attr("levels")) / 4;
    g.size = size_of(h.attr("x")) / COMPONENTS;
    g.coef = array<double>(h, "coef", COMPONENTS * 9 * g.size);
    g.inverse_diagonal = array<double>(h, "inverse_diagonal", COMPONENTS * g.size);
    g.x = array<double>(h, "x", COMPONENTS * g.size);
    g.b = array<double>(h, "b", COMPONENTS * g.size);
    g.row = g.level_count > 0 ? array<double>(h, "row", g.levels[NX] + 3) : nullptr;
    g.single_coef = array<float>(h, "single_coef", COMPONENTS * 9 * g.size);
    g.single_inverse_diagonal = array<float>(h, "single_inverse_diagonal", COMPONENTS * g.size);
    g.single_x = array<float>(h, "single_x", COMPONENTS * g.size);
    g.single_b = array<float>(h, "single_b", COMPONENTS * g.size);
    g.single_r = array<float>(h, "single_r", COMPONENTS * g.size);
    return g;
}

Algebraic algebraic_from(nb::handle h) {
    Algebraic a;
    a.levels = array<const Index>(h, "levels");
    a.level_count = size_of(h.attr("levels")) / ALGEBRAIC_COLUMNS;
    a.entries = size_of(h.attr("a_column"));
    a.vectors = size_of(h.attr("diagonal"));
    a.a_start = array<const Index>(h, "a_start");
    a.a_column = array<const Column>(h, "a_column");
    a.a_value = array<double>(h, "a_value", COMPONENTS * a.entries);
    a.diagonal = array<const Index>(h, "diagonal");
    a.p_start = array<const Index>(h, "p_start");
    a.p_column = array<const Column>(h, "p_column");
    a.p_value = array<const double>(h, "p_value", size_of(h.attr("p_column")));
    a.r_start = array<const Index>(h, "r_start");
    a.r_column = array<const Column>(h, "r_column");
    a.r_value = array<const double>(h, "r_value", size_of(h.attr("r_column")));
    a.spring_entries = array<const Index>(h, "spring_entries");
    a.coupled = size_of(h.attr("spring_entries")) / 2;
    a.inverse_diagonal = array<double>(h, "inverse_diagonal", COMPONENTS * a.vectors);
    a.x = array<double>(h, "x", COMPONENTS * a.vectors);
    a.b = array<double>(h, "b", COMPONENTS * a.vectors);
    a.r = array<double>(h, "r", COMPONENTS * a.vectors);
    a.marker = array<Index>(h, "marker");
    return a;
}

Plane plane_from(nb::handle h, Index n) {
    Plane p;
    p.stiffness = array<const double>(h, "stiffness");
    p.grid = hierarchy_from(h.attr("grid"));
    p.families = p.grid.level_count > 0 ? size_of(h.attr("stiffness")) / n : 0;  // a mesh's: (S) listed springs
    p.slots = array<const Index>(h, "slots", p.families);
    p.order = array<const Index>(h, "order");
    p.coarse_n = size_of(h.attr("order"));
    p.kd = size_of(h.attr("bands")) / (COMPONENTS * p.coarse_n) - 1;
    p.rank = array<const Index>(h, "rank");
    p.rank_size = size_of(h.attr("rank"));
    p.bands = array<double>(h, "bands", COMPONENTS * p.coarse_n * (p.kd + 1));
    p.rows = array<double>(h, "rows", COMPONENTS * p.coarse_n * (p.kd + 1));
    p.reference = array<double>(h, "reference", 4);
    p.reference_mass = array<double>(h, "reference_mass", n);
    p.shares = array<const double>(h, "shares", 2 * p.families);
    p.jacobian_along = array<double>(h, "jacobian_along", p.families > 0 ? p.families * n
                                                                          : size_of(h.attr("jacobian_along")));
    p.jacobian_mass = array<double>(h, "jacobian_mass", n);
    p.frame = array<double>(h, "frame", 9 * n);
    p.normal = array<double>(h, "normal", n);
    p.local = array<double>(h, "local", COMPONENTS * p.coarse_n);
    p.algebraic = algebraic_from(h.attr("algebraic"));
    return p;
}

Contact contact_from(nb::handle h, Index n, ContactLists* lists) {
    Contact c;
    c.enabled = number<bool>(h, "enabled");
    c.friction = number<double>(h, "friction");
    c.least_margin = number<double>(h, "least_margin");
    c.rest_gap = number<double>(h, "rest_gap");
    c.typical_gap = number<double>(h, "typical_gap");
    c.triangles = array<const Index>(h, "triangles");
    c.triangle_count = size_of(h.attr("triangles")) / 3;
    c.edges = array<const Index>(h, "edges");
    c.edge_count = size_of(h.attr("edges")) / 2;
    c.rest = array<const double>(h, "rest", 3 * n);
    c.reference = array<double>(h, "reference", 3 * n);
    c.margin = array<double>(h, "margin", 1);
    c.zone = array<Index>(h, "zone", n);
    c.zone_sums = array<double>(h, "zone_sums", ZONE_ROWS * n);
    c.counters = array<Index>(h, "counters", CONTACT_COUNTERS);
    c.lists = lists;
    return c;
}

Buffers buffers_from(nb::handle h, Index n) {
    Buffers b;
    b.pos = array<double>(h, "pos", 3 * n);
    b.vel = array<double>(h, "vel", 3 * n);
    b.water = array<double>(h, "water", n);
    b.trial_pos = array<double>(h, "trial_pos", 3 * n);
    b.trial_vel = array<double>(h, "trial_vel", 3 * n);
    b.trial_water = array<double>(h, "trial_water", n);
    b.prev_pos = array<double>(h, "prev_pos", 3 * n);
    b.prev_vel = array<double>(h, "prev_vel", 3 * n);
    b.prev_water = array<double>(h, "prev_water", n);
    b.acceleration = array<double>(h, "acceleration", 3 * n);
    b.anchor = array<double>(h, "anchor", 3 * n);
    b.held = array<double>(h, "held", n);
    return b;
}

}  // namespace wc::py
