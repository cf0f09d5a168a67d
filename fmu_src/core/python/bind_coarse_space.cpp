// Bindings of the frame steps' coarse space (coarse_space.cpp): for tests, its matrix as a dense array; a
// CoarseSpace kept between calls, built and applied apart (tests; bench/sheet_kernels.py times each).
#include <algorithm>

#include "convert.hpp"
#include "wetcloth/coarse_space.hpp"

namespace wc::py {

WETCLOTH_BINDINGS(m) {
    m.attr("COARSE_SIDE") = COARSE_SIDE;
    m.attr("COARSE_UNKNOWNS") = COARSE_UNKNOWNS;
    m.def(
        "coarse_matrix",
        [](nb::handle cloth, nb::handle work, nb::handle mass, nb::handle pos, Index side, nb::handle out) {
            const Cloth c = cloth_from(cloth);
            const Work w = work_from(work, c);
            CoarseSpace coarse;
            shape_coarse_space(coarse, c, side);
            assemble_coarse_matrix(coarse, c, argument<const double>(mass, "mass", c.n), w,
                                   argument<const double>(pos, "pos", 3 * c.n));
            const Index size = COARSE_UNKNOWNS * coarse.count, stride = coarse.width + 1;
            double* dense = argument<double>(out, "out", size * size);
            for (Index row = 0; row < size; ++row) {
                for (Index col = 0; col < size; ++col) {
                    const Index hi = std::max(row, col), lo = std::min(row, col);
                    dense[row * size + col] = hi - lo <= coarse.width ? coarse.band[lo * stride + hi - lo] : 0.0;
                }
            }
        },
        nb::arg("cloth"), nb::arg("work"), nb::arg("mass"), nb::arg("pos"), nb::arg("side"), nb::arg("out"));
    nb::class_<CoarseSpace>(m, "CoarseSpace", "A grid cloth's coarse space of side x side aggregates, kept between calls.")
        .def(
            "__init__",
            [](CoarseSpace* self, nb::handle cloth, Index side) {
                new (self) CoarseSpace();
                shape_coarse_space(*self, cloth_from(cloth), side);
            },
            nb::arg("cloth"), nb::arg("side"))
        .def(
            "build",
            [](CoarseSpace& self, nb::handle cloth, nb::handle work, nb::handle mass, nb::handle pos) {
                const Cloth c = cloth_from(cloth);
                build_coarse_space(self, c, argument<const double>(mass, "mass", c.n), work_from(work, c),
                                   argument<const double>(pos, "pos", 3 * c.n));
                return self.factored;
            },
            nb::arg("cloth"), nb::arg("work"), nb::arg("mass"), nb::arg("pos"), "build_coarse_space: whether it factored.")
        .def(
            "add_correction",
            [](CoarseSpace& self, nb::handle cloth, nb::handle r, nb::handle z) {
                const Cloth c = cloth_from(cloth);
                add_coarse_correction(self, c, argument<const double>(r, "r", 3 * c.n), argument<double>(z, "z", 3 * c.n));
            },
            nb::arg("cloth"), nb::arg("r"), nb::arg("z"), "z += P (P^T A P)^-1 P^T r, after build.");
}

}  // namespace wc::py
