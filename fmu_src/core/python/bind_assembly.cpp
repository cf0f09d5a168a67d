// Bindings of the force assembly (bf41571:fmu_src/wetcloth/kernels/assembly.py): forces, forces_and_blocks and submerged
// with the numba kernels' arguments (the Cloth, Physics and Work named tuples, arrays, numbers).
#include "convert.hpp"
#include "wetcloth/assembly.hpp"

WETCLOTH_BINDINGS(m) {
    using namespace wc;
    using namespace wc::py;

    m.attr("GRAVITY") = GRAVITY;

    m.def(
        "submerged",
        [](nb::handle phys, nb::handle z, nb::handle out) {
            const Index n = size_of(z);
            return submerged(physics_from(phys), n, argument<const double>(z, "z", n),
                             argument<double>(out, "out", n));
        },
        nb::arg("phys"), nb::arg("z"), nb::arg("out"),
        "Fill out with each particle's submerged fraction (0..1); return the largest.");

    m.def(
        "forces",
        [](nb::handle cloth, nb::handle phys, nb::handle work, nb::handle pos, nb::handle vel, nb::handle water) {
            const Cloth c = cloth_from(cloth);
            Work w = work_from(work, c);
            forces(c, physics_from(phys), w, argument<const double>(pos, "pos", 3 * c.n),
                   argument<const double>(vel, "vel", 3 * c.n), argument<const double>(water, "water", c.n));
        },
        nb::arg("cloth"), nb::arg("phys"), nb::arg("work"), nb::arg("pos"), nb::arg("vel"), nb::arg("water"),
        "Total force (N) on every particle into work.force; the submerged fractions into work.submerged.");

    m.def(
        "forces_and_blocks",
        [](nb::handle cloth, nb::handle phys, nb::handle work, nb::handle pos, nb::handle vel, nb::handle water,
           double h, double slack_slope) {
            const Cloth c = cloth_from(cloth);
            Work w = work_from(work, c);
            forces_and_blocks(c, physics_from(phys), w, argument<const double>(pos, "pos", 3 * c.n),
                              argument<const double>(vel, "vel", 3 * c.n),
                              argument<const double>(water, "water", c.n), h, slack_slope);
        },
        nb::arg("cloth"), nb::arg("phys"), nb::arg("work"), nb::arg("pos"), nb::arg("vel"), nb::arg("water"),
        nb::arg("h"), nb::arg("slack_slope") = 0.0,
        "Forces as forces, plus the pieces of the system matrix M - h dF/dv - h^2 dF/dx in work.");
}
