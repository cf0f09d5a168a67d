// Bindings of the colliders' geometry (colliders.cpp, collider_mesh.cpp) and of where the grip's keys put the pinned
// particles (grip.cpp), for tests and callers that check a scene.
#include <nanobind/stl/tuple.h>

#include <vector>

#include "convert.hpp"
#include "wetcloth/grip.hpp"
#include "wetcloth/collider_mesh.hpp"
#include "wetcloth/collider_motion.hpp"
#include "wetcloth/colliders.hpp"

namespace wc::py {

namespace {

//: Physics holding only the collider rows (k, COLLIDER_COLUMNS) and their meshes (a ColliderMeshes).
Physics with_colliders(nb::handle colliders, nb::handle meshes) {
    Physics phys;
    phys.collider_count = size_of(colliders) / COLLIDER_COLUMNS;
    phys.colliders = argument<const double>(colliders, "colliders", phys.collider_count * COLLIDER_COLUMNS);
    phys.meshes = meshes_from(meshes);
    return phys;
}

//: The meshes (a ColliderMeshes), having mesh `mesh`.
ColliderMeshes mesh_of(nb::handle meshes, Index mesh) {
    const ColliderMeshes m = meshes_from(meshes);
    if (mesh < 0 || mesh >= m.count) throw std::out_of_range("mesh index out of range");
    return m;
}

}  // namespace

WETCLOTH_BINDINGS(m) {
    m.attr("COLLIDER_COLUMNS") = static_cast<Index>(COLLIDER_COLUMNS);
    m.attr("MESH_COLUMNS") = static_cast<Index>(MESH_COLUMNS);
    m.attr("MOTION_COLUMNS") = static_cast<Index>(MOTION_COLUMNS);
    m.attr("GRIP_RESOLUTION") = GRIP_RESOLUTION;
    m.def(
        "collider_distance",
        [](nb::handle colliders, nb::handle meshes, Index k, nb::handle points, double reach, nb::handle distance,
           nb::handle normal, nb::handle keys, double t) {
            Physics phys = with_colliders(colliders, meshes);
            if (k < 0 || k >= phys.collider_count) throw std::out_of_range("collider index out of range");
            std::vector<double> motion;
            if (!keys.is_none()) {
                phys.collider_key_count = size_of(keys) / COLLIDER_KEY_COLUMNS;
                phys.collider_keys = argument<const double>(keys, "keys", phys.collider_key_count * COLLIDER_KEY_COLUMNS);
                motion.assign(static_cast<std::size_t>(phys.collider_count * MOTION_COLUMNS), 0.0);
                phys.collider_motion = motion.data();
                start_collider_motion(phys, t);
            }
            const Index count = size_of(distance);
            const double* p = argument<const double>(points, "points", 3 * count);
            double* d = argument<double>(distance, "distance", count);
            double* nrm = argument<double>(normal, "normal", 3 * count);
            for (Index i = 0; i < count; ++i) {
                const double q[3] = {p[i], p[count + i], p[2 * count + i]};
                double out[3] = {0.0, 0.0, 0.0};
                d[i] = collider_distance(phys, k, q, reach, out);
                for (Index c = 0; c < 3; ++c) nrm[c * count + i] = out[c];
            }
        },
        nb::arg("colliders"), nb::arg("meshes"), nb::arg("k"), nb::arg("points"), nb::arg("reach"), nb::arg("distance"),
        nb::arg("normal"), nb::arg("keys") = nb::none(), nb::arg("t") = 0.0,
        "Signed distance (m) of points (3, m) to collider k of the rows colliders (k, COLLIDER_COLUMNS) into distance "
        "(m), the outward normals into normal (3, m); a mesh collider's (its triangles in meshes, a ColliderMeshes) "
        "at most reach (m).  With keys (rows (j, 8), collider_motion.hpp), where they have moved it at t (s).");
    m.def(
        "grip_key_displacement",
        [](nb::handle keys, double t) {
            Physics phys;
            phys.grip_key_count = size_of(keys) / 4;
            phys.grip_keys = argument<const double>(keys, "keys", 4 * phys.grip_key_count);
            double d[3];
            key_displacement(phys, t, d);
            return nb::make_tuple(d[0], d[1], d[2]);
        },
        nb::arg("keys"), nb::arg("t"),
        "(x, y, z) m: the grip keys' displacement of the pinned particles at t (s), keys the rows (k, 4) of time s and "
        "x, y, z m (scene.grip_key_rows): 0 at t = 0, linear between keys, the last key's after it.");
    m.def(
        "mesh_triangles_in",
        [](nb::handle meshes, Index mesh, nb::handle lo, nb::handle hi) {
            const ColliderMeshes m = mesh_of(meshes, mesh);
            std::vector<Index> found;
            mesh_triangles_in(m, mesh, argument<const double>(lo, "lo", 3), argument<const double>(hi, "hi", 3), found);
            nb::list out;
            for (const Index t : found) out.append(t);
            return out;
        },
        nb::arg("meshes"), nb::arg("mesh"), nb::arg("lo"), nb::arg("hi"),
        "The triangles (a list, one entry per cell that lists it) of mesh `mesh` of meshes (a ColliderMeshes) in the "
        "cells that the box [lo, hi] (3 each, m) overlaps.");
    m.def(
        "mesh_lists_triangles_in",
        [](nb::handle meshes, Index mesh, nb::handle lo, nb::handle hi) {
            return mesh_lists_triangles_in(mesh_of(meshes, mesh), mesh, argument<const double>(lo, "lo", 3),
                                           argument<const double>(hi, "hi", 3));
        },
        nb::arg("meshes"), nb::arg("mesh"), nb::arg("lo"), nb::arg("hi"),
        "Whether a cell of mesh `mesh` of meshes (a ColliderMeshes) that the box [lo, hi] (3 each, m) overlaps lists "
        "a triangle.");
    m.def(
        "slip_on_supports",
        [](nb::handle colliders, nb::handle meshes, double thickness, double floor_z, double floor_friction,
           nb::handle force, nb::handle mass, double h, double limit, nb::handle held, nb::handle pos, nb::handle vel) {
            Physics phys = with_colliders(colliders, meshes);
            phys.thickness = thickness;
            phys.floor_z = floor_z;
            phys.floor_friction = floor_friction;
            const Index n = size_of(mass);
            double* p = argument<double>(pos, "pos", 3 * n);
            const std::vector<double> start(p, p + 3 * n);
            return slip_on_supports(n, phys, argument<const double>(force, "force", 3 * n),
                                    argument<const double>(mass, "mass", n), nullptr, nullptr, h, limit,
                                    argument<const double>(held, "held", n), start.data(), p,
                                    argument<double>(vel, "vel", 3 * n));
        },
        nb::arg("colliders"), nb::arg("meshes"), nb::arg("thickness"), nb::arg("floor_z"), nb::arg("floor_friction"),
        nb::arg("force"), nb::arg("mass"), nb::arg("h"), nb::arg("limit"), nb::arg("held"), nb::arg("pos"),
        nb::arg("vel"),
        "Move the particles held (n) on the floor or a still collider that force (3, n) N slips, as a step of h s "
        "would have (pos, vel (3, n) in place, from rest at pos); their masses (n) kg.  Returns the farthest move "
        "(m), or -1 with nothing moved if one would move farther than limit (m).");
}

}  // namespace wc::py
