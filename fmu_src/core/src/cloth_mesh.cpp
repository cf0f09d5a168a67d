// A cloth from a mesh file in the native model (model.hpp's ClothMesh): what a scene's values make of the
// structure the Python front end built once (wetcloth/topology.py's placed, pinned_mask, listed_springs'
// constants; scene.py's _check_mesh_start), with the Python's order of operations, so that the arrays agree
// to the bit.
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "wetcloth/model.hpp"

namespace wc {

namespace {

constexpr double PI = 3.141592653589793;  // math.pi

std::string parameter_error(const char* name, const std::string& message) {
    return std::string("parameter '") + name + "': " + message;
}

}  // namespace

Scene ClothMesh::on_grid(const Scene& scene) const {
    if (!forms_grid()) return scene;
    Scene grid = scene;
    grid.nx = grid_nx;
    grid.ny = grid_ny;
    grid.width = grid_width;
    grid.length = grid_length;
    return grid;
}

Index ClothMesh::hinge_count() const {
    Index count = 0;
    for (const Index kind : pair_kind) count += kind == PAIR_HINGE ? 1 : 0;
    return count;
}

std::string ClothMesh::fixed_problem(const Scene& scene) const {
    if (forms_grid()) return grid_rigidity_problem(scene);  // the grid's families: any bend and stretch stiffness
    if (hinged_grid) {
        const std::string rebuild = " (rebuild the unit with wetcloth build-fmu --native --scene for another)";
        if (scene.nx != grid_nx || scene.ny != grid_ny) {
            const bool x = scene.nx != grid_nx;
            return parameter_error(x ? "nx" : "ny", std::to_string(x ? scene.nx : scene.ny) + " is not allowed in "
                                   "this unit: the hinges of its grid were built for " + std::to_string(grid_nx) + " x " +
                                   std::to_string(grid_ny) + " particles; allowed: " +
                                   std::to_string(x ? grid_nx : grid_ny) + rebuild);
        }
        if (scene.width != grid_width || scene.length != grid_length) {
            const bool x = scene.width != grid_width;
            return parameter_error(x ? "width" : "length", py_repr(x ? scene.width : scene.length) + " is not allowed "
                                   "in this unit: the hinges of its grid were built for " + py_repr(grid_width) +
                                   " x " + py_repr(grid_length) + " m; allowed: " +
                                   py_repr(x ? grid_width : grid_length) + " m" + rebuild);
        }
    }
    const bool hinged = hinge_count() > 0;
    if ((scene.bend_rigidity != 0.0) != hinged) {
        return parameter_error("bend_rigidity", py_repr(scene.bend_rigidity) + " is not allowed in this unit: its mesh "
                               "was built " + (hinged ? "with" : "without") + " hinges; allowed: " +
                               (hinged ? "0 < bend_rigidity <= 100 N m" : "0 N m") +
                               " (rebuild the unit with wetcloth build-fmu --native --scene for another)");
    }
    if (!hinged && (scene.bend_stiffness != 0.0) != bends) {  // (hinges bend every face: bend_stiffness unused)
        return parameter_error("bend_stiffness", py_repr(scene.bend_stiffness) + " is not allowed in this unit: its mesh's "
                               "springs were built " + (bends ? "with" : "without") + " bending springs; allowed: " +
                               (bends ? "0 < bend_stiffness <= 1e+08 N/m" : "0 N/m") +
                               " (rebuild the unit with wetcloth build-fmu --native --scene for another)");
    }
    if (level_count() > 1 && scene.stretch_stiffness != hierarchy_stretch_stiffness) {
        return parameter_error("stretch_stiffness", py_repr(scene.stretch_stiffness) + " is not allowed in this unit: "
                               "the algebraic multigrid hierarchy of its mesh (" + std::to_string(n) +
                               " vertices) was built for stretch_stiffness = " + py_repr(hierarchy_stretch_stiffness) +
                               " N/m; allowed: " + py_repr(hierarchy_stretch_stiffness) +
                               " N/m (rebuild the unit with wetcloth build-fmu --native --scene for another)");
    }
    return "";
}

std::vector<double> ClothMesh::start_positions(const Scene& scene) const {
    if (hinged_grid) return grid_start(scene);
    if (scene.place_mesh == SWITCH_OFF) return rest_pos;
    const double tilt = scene.initial_tilt * (PI / 180.0);  // math.radians
    const double c = std::cos(tilt), s = std::sin(tilt);
    std::vector<double> pos(3 * static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i) {
        const double y = rest_pos[n + i] - centre[1], z = rest_pos[2 * n + i] - centre[2];
        pos[i] = rest_pos[i];
        pos[n + i] = centre[1] + y * c - z * s;
        pos[2 * n + i] = scene.initial_height + y * s + z * c;
    }
    return pos;
}

std::string Pins::pin(Index n, const double* pos, std::vector<char>& pinned) const {
    if (box) {
        bool any = false;
        for (Index i = 0; i < n; ++i) {
            bool inside = true;
            for (Index k = 0; k < 3; ++k) inside = inside && pos[k * n + i] >= corners[k] && pos[k * n + i] <= corners[3 + k];
            pinned[i] = pinned[i] || inside;
            any = any || inside;
        }
        if (!any) {
            std::string span;
            for (Index k = 0; k < 3; ++k) {
                double lo = pos[k * n], hi = pos[k * n];
                for (Index i = 0; i < n; ++i) {
                    lo = std::fmin(lo, pos[k * n + i]);
                    hi = std::fmax(hi, pos[k * n + i]);
                }
                span += std::string(k ? ", " : "") + "xyz"[k] + " " + py_g(lo) + " .. " + py_g(hi);
            }
            return parameter_error("pinned_vertices", "the box " + text + " holds no vertex of the cloth at t = 0 "
                                   "(it spans " + span + " m); allowed: " + allowed);
        }
    }
    for (std::size_t i = 0; i < attribute.size(); ++i) pinned[i] = pinned[i] || attribute[i] != 0;
    return "";
}

std::vector<char> ClothMesh::pinned_at(const Scene& scene, const std::vector<double>& pos, const Pins* pins,
                                       std::string& problem) const {
    std::vector<char> pinned(static_cast<std::size_t>(n), 0);
    problem.clear();
    if (hinged_grid) {
        for (Index i = 0; i < n; ++i) pinned[i] = on_pinned_edge(scene, i) ? 1 : 0;
    } else if (scene.pinned_edge != EDGE_NONE) {
        problem = parameter_error("pinned_edge", py_repr(std::string_view(EDGES[scene.pinned_edge])) +
                                  " is an edge of the nx x ny rectangle, but the cloth comes from cloth_mesh (pin its "
                                  "vertices with pinned_vertices: a point attribute or a box); allowed here: 'none'");
        return pinned;
    }
    if (pins != nullptr) problem = pins->pin(n, pos.data(), pinned);
    return pinned;
}

std::string mesh_floor_problem(const Scene& scene, const double* pos, Index n) {
    double lowest = pos[2 * n];
    for (Index i = 0; i < n; ++i) lowest = std::fmin(lowest, pos[2 * n + i]);
    lowest -= 0.5 * scene.thickness;
    if (lowest > scene.floor_level) return "";
    const bool placed = scene.place_mesh == SWITCH_ON;
    return parameter_error(placed ? "initial_height" : "cloth_mesh",
                           "the cloth starts at or below the floor (lowest point " + py_g(lowest) +
                               " m with thickness/2, floor_level " + py_g(scene.floor_level) + " m): " +
                               (placed ? "raise initial_height" :
                                         "raise the mesh in its file, or place it: place_mesh = 'on'") +
                               "; allowed: every vertex above floor_level + thickness/2");
}

namespace {

//: Where the mesh starts (3, n) m and which particles are pinned there, for `scene`; `problem` "" or the
//: first thing the scene asks that the mesh cannot be (scene.py's _check_mesh_start).
struct MeshStart {
    std::vector<double> pos;
    std::vector<char> pinned;
    std::string problem;
};

MeshStart mesh_start(const Scene& scene, const ClothMesh& mesh, const Pins* pins) {
    MeshStart start;
    start.problem = mesh.fixed_problem(scene);
    if (!start.problem.empty()) return start;
    start.pos = mesh.start_positions(scene);
    // (the built-in grid bent by hinges starts as the grid, checked as the grid is)
    start.problem = mesh.hinged_grid ? grid_start_problem(scene, pins)
                                     : mesh_floor_problem(scene, start.pos.data(), mesh.n);
    if (!start.problem.empty()) return start;
    start.pinned = mesh.pinned_at(scene, start.pos, pins, start.problem);
    return start;
}

//: The listed springs' topology of a mesh that does not form the grid (its start and pins unset).
Topology listed_topology(const Scene& scene, const ClothMesh& mesh) {
    Topology t;
    const Index n = mesh.n, count = static_cast<Index>(mesh.pair_rest.size());
    t.nx = n;
    t.ny = 1;
    t.n = n;
    t.mesh = &mesh;
    t.size = mesh.size;
    t.rest_xy = mesh.rest_xy;
    t.area = mesh.area;
    t.tension_only.reset(new bool[1]);
    t.triangles = mesh.triangles;
    t.pair_stiffness.resize(count);
    t.pair_damping.resize(count);
    for (Index k = 0; k < count; ++k) {  // listed_springs: modulus * shape, damping * shape
        const Index kind = mesh.pair_kind[k];
        const double modulus = kind == PAIR_BEND    ? scene.bend_stiffness
                               : kind == PAIR_HINGE ? scene.bend_rigidity
                                                    : scene.stretch_stiffness;
        const double damping = kind == PAIR_HINGE ? scene.damping / scene.stretch_stiffness * scene.bend_rigidity
                                                  : scene.damping;
        t.pair_stiffness[k] = modulus * mesh.pair_shape[k];
        t.pair_damping[k] = damping * mesh.pair_shape[k];
    }
    t.free.assign(n, 1.0);
    return t;
}

}  // namespace

std::string mesh_scene_problem(const Scene& scene, const ClothMesh& mesh, const Pins* pins) {
    return mesh_start(scene, mesh, pins).problem;
}

Topology mesh_topology(const Scene& scene, const ClothMesh& mesh, const Pins* pins) {
    MeshStart start = mesh_start(scene, mesh, pins);
    if (!start.problem.empty()) throw std::invalid_argument(start.problem);
    Topology t = mesh.forms_grid() ? grid_topology(scene, nullptr) : listed_topology(scene, mesh);
    t.start = std::move(start.pos);
    for (Index i = 0; i < mesh.n; ++i) t.free[i] = start.pinned[i] ? 0.0 : 1.0;
    return t;
}

}  // namespace wc
