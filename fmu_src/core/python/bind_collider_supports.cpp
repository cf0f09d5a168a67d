// Bindings of a moving mesh's supports inside the implicit step (collider_supports.cpp), for the tests.
#include <nanobind/stl/vector.h>

#include <vector>

#include "convert.hpp"
#include "wetcloth/collider_supports.hpp"

namespace wc::py {

namespace {

//: Supports given in the world: points (m, SUPPORT_POINTS) cloth particles or -1, weights (m, SUPPORT_POINTS),
//: normals (m, 3), offsets (m) m.
Supports given_supports(nb::handle points, nb::handle weights, nb::handle normals, nb::handle offsets) {
    Supports s;
    const Index count = size_of(offsets);
    const Index* pt = argument<const Index>(points, "points", SUPPORT_POINTS * count);
    const double* w = argument<const double>(weights, "weights", SUPPORT_POINTS * count);
    const double* nn = argument<const double>(normals, "normals", 3 * count);
    const double* off = argument<const double>(offsets, "offsets", count);
    s.points.assign(pt, pt + SUPPORT_POINTS * count);
    s.weights.assign(w, w + SUPPORT_POINTS * count);
    s.normal.assign(nn, nn + 3 * count);
    s.offset.assign(off, off + count);
    s.collider.assign(static_cast<std::size_t>(count), 0);
    s.pressing.assign(static_cast<std::size_t>(count), 0);
    s.anticipated.assign(static_cast<std::size_t>(count), 0);
    s.arrived.assign(static_cast<std::size_t>(count), 0);
    s.stiff.assign(static_cast<std::size_t>(count), 0);
    return s;
}

//: Adds supports s's forces (N) at x and v (3, n; v null: no friction) into force (3, n), their stiffness's
//: diagonal blocks into blocks (6, n) and the rest of it times p (3, n) into product (3, n), rows of free (n).
void add_terms(Supports& s, Index n, const double* x, const double* v, nb::handle free, nb::handle p,
               nb::handle force, nb::handle blocks, nb::handle product) {
    add_support_forces(s, n, x, v, argument<double>(force, "force", 3 * n), argument<double>(blocks, "blocks", 6 * n));
    add_support_product(s, n, argument<const double>(free, "free", n), argument<const double>(p, "p", 3 * n),
                        argument<double>(product, "product", 3 * n));
}

}  // namespace

WETCLOTH_BINDINGS(m) {
    m.attr("SUPPORT_DISTANCE") = SUPPORT_DISTANCE;
    m.attr("SUPPORT_POINTS") = SUPPORT_POINTS;
    m.attr("SUPPORT_STIFFNESS") = SUPPORT_STIFFNESS;
    m.def(
        "support_terms",
        [](nb::handle points, nb::handle weights, nb::handle normals, nb::handle offsets, double stiffness,
           double distance, double scale, nb::handle pos, nb::handle free, nb::handle p, nb::handle force,
           nb::handle blocks, nb::handle product) {
            Supports s = given_supports(points, weights, normals, offsets);
            const Index n = size_of(free);
            s.stiffness = stiffness, s.distance = distance, s.scale = scale;
            const double* x = argument<const double>(pos, "pos", 3 * n);
            add_terms(s, n, x, nullptr, free, p, force, blocks, product);
            return support_energy(s, n, x);
        },
        nb::arg("points"), nb::arg("weights"), nb::arg("normals"), nb::arg("offsets"), nb::arg("stiffness"),
        nb::arg("distance"), nb::arg("scale"), nb::arg("pos"), nb::arg("free"), nb::arg("p"), nb::arg("force"),
        nb::arg("blocks"), nb::arg("product"),
        "Supports' terms given in the world (points (m, SUPPORT_POINTS) int64 cloth particles or -1, weights "
        "(m, SUPPORT_POINTS), normals (m, 3), offsets (m) m; stiffness N/m, distance m, scale s^2) at pos (3, n): "
        "adds their forces (N) into "
        "force (3, n), their stiffness's diagonal blocks times scale into blocks (6, n) and the rest of their "
        "stiffness times scale times p (3, n) into product (3, n) (rows of free particles); returns the energy (J).");
    m.attr("SUPPORT_SLIP_SPEED") = SUPPORT_SLIP_SPEED;
    m.attr("SELF_SLIP_SPEED") = SELF_SLIP_SPEED;
    m.def(
        "support_friction_terms",
        [](nb::handle points, nb::handle weights, nb::handle normals, nb::handle offsets, double stiffness,
           double distance, nb::handle frictions, nb::handle normal_forces, nb::handle collider_velocities,
           double velocity_scale,
           nb::handle pos, nb::handle vel, nb::handle free, nb::handle p, nb::handle force, nb::handle blocks,
           nb::handle product, bool self_pairs) {
            Supports s = given_supports(points, weights, normals, offsets);
            const Index count = s.count();
            if (self_pairs) s.collider.assign(static_cast<std::size_t>(count), SELF_SUPPORT);
            const Index n = size_of(free);
            const double* mu = argument<const double>(frictions, "frictions", count);
            const double* normal_force = argument<const double>(normal_forces, "normal_forces", count);
            const double* cv = argument<const double>(collider_velocities, "collider_velocities", 3 * count);
            s.friction.assign(mu, mu + count);
            s.normal_force.assign(normal_force, normal_force + count);
            s.collider_velocity.assign(cv, cv + 3 * count);
            s.friction_block.assign(6 * static_cast<std::size_t>(count), 0.0);
            s.stiffness = s.self_stiffness = stiffness;
            s.distance = distance, s.scale = 0.0, s.velocity_scale = velocity_scale;
            for (Index t = 0; t < count; ++t) s.any_friction = s.any_friction || mu[t] > 0.0;
            const double* x = argument<const double>(pos, "pos", 3 * n);
            const double* v = argument<const double>(vel, "vel", 3 * n);
            add_terms(s, n, x, v, free, p, force, blocks, product);
            return support_dissipation(s, n, v);
        },
        nb::arg("points"), nb::arg("weights"), nb::arg("normals"), nb::arg("offsets"), nb::arg("stiffness"),
        nb::arg("distance"), nb::arg("frictions"), nb::arg("normal_forces"), nb::arg("collider_velocities"),
        nb::arg("velocity_scale"),
        nb::arg("pos"), nb::arg("vel"), nb::arg("free"), nb::arg("p"), nb::arg("force"), nb::arg("blocks"),
        nb::arg("product"), nb::arg("self_pairs") = false,
        "support_terms' terms with friction (frictions (m), normal forces at the step's start (m) N, the "
        "collider's points' weighted velocities (m, 3) m/s) at pos and vel (3, n), the position stiffness left "
        "out (scale 0): adds their forces (N, normal and friction) into force (3, n), their friction's stiffness in velocity times velocity_scale (s): the "
        "diagonal blocks into blocks (6, n), the rest times p (3, n) into product (3, n); returns the friction's "
        "dissipation potential (W).  self_pairs: the terms are pairs of the cloth with itself (SELF_SLIP_SPEED).");
    m.def(
        "support_arrivals",
        [](nb::handle points, nb::handle weights, nb::handle normals, nb::handle offsets, double stiffness,
           double distance, nb::handle frictions, nb::handle mass, nb::handle start_vel, nb::handle pos,
           nb::handle vel, double h) {
            Supports s = given_supports(points, weights, normals, offsets);
            const Index count = s.count();
            const Index n = size_of(mass);
            const double* mu = argument<const double>(frictions, "frictions", count);
            s.friction.assign(mu, mu + count);
            s.normal_force.assign(static_cast<std::size_t>(count), 0.0);
            s.collider_velocity.assign(3 * static_cast<std::size_t>(count), 0.0);
            s.friction_block.assign(6 * static_cast<std::size_t>(count), 0.0);
            s.stiffness = stiffness, s.distance = distance, s.velocity_scale = h;
            for (Index t = 0; t < count; ++t) s.any_friction = s.any_friction || mu[t] > 0.0;
            std::vector<double> force(3 * static_cast<std::size_t>(n)), blocks(6 * static_cast<std::size_t>(n));
            lag_arriving_normal_force(s, n, argument<const double>(mass, "mass", n),
                                      argument<const double>(start_vel, "start_vel", 3 * n),
                                      argument<const double>(pos, "pos", 3 * n),
                                      argument<const double>(vel, "vel", 3 * n), h, force.data(), blocks.data());
            return s.normal_force;
        },
        nb::arg("points"), nb::arg("weights"), nb::arg("normals"), nb::arg("offsets"), nb::arg("stiffness"),
        nb::arg("distance"), nb::arg("frictions"), nb::arg("mass"), nb::arg("start_vel"), nb::arg("pos"),
        nb::arg("vel"), nb::arg("h"),
        "support_terms' terms met within a step of h s (no normal force at its start; frictions (m)), the cloth's "
        "masses (n) kg and its velocities at the start (3, n) m/s, at an iterate pos, vel (3, n): the normal "
        "force (N) each term takes there for the rest of the step (lag_arriving_normal_force).");
}

}  // namespace wc::py
