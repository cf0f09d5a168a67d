// Bindings of the colliders' geometry (colliders.cpp, collider_mesh.cpp), for tests and callers that check a scene.
#include "convert.hpp"
#include "wetcloth/collider_mesh.hpp"
#include "wetcloth/collider_motion.hpp"
#include "wetcloth/colliders.hpp"

namespace wc::py {

WETCLOTH_BINDINGS(m) {
    m.attr("COLLIDER_COLUMNS") = static_cast<Index>(COLLIDER_COLUMNS);
    m.attr("MESH_COLUMNS") = static_cast<Index>(MESH_COLUMNS);
    m.attr("MOTION_COLUMNS") = static_cast<Index>(MOTION_COLUMNS);
    m.def(
        "collider_distance",
        [](nb::handle colliders, nb::handle meshes, Index k, nb::handle points, double reach, nb::handle distance,
           nb::handle normal) {
            Physics phys;
            phys.collider_count = size_of(colliders) / COLLIDER_COLUMNS;
            phys.colliders = argument<const double>(colliders, "colliders", phys.collider_count * COLLIDER_COLUMNS);
            phys.meshes = meshes_from(meshes);
            if (k < 0 || k >= phys.collider_count) throw std::out_of_range("collider index out of range");
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
        nb::arg("normal"),
        "Signed distance (m) of points (3, m) to collider k of the rows colliders (k, COLLIDER_COLUMNS) into distance "
        "(m), the outward normals into normal (3, m); a mesh collider's (its triangles in meshes, a ColliderMeshes) "
        "at most reach (m).");
}

}  // namespace wc::py
