// Bindings of the frame steps' coarse space (coarse_space.cpp), for tests: its matrix and its correction.
#include <algorithm>

#include "convert.hpp"
#include "wetcloth/coarse_space.hpp"

namespace wc::py {

WETCLOTH_BINDINGS(m) {
    m.attr("COARSE_SIDE") = COARSE_SIDE;
    m.def(
        "coarse_matrix",
        [](nb::handle cloth, nb::handle work, nb::handle mass, Index side, nb::handle out) {
            const Cloth c = cloth_from(cloth);
            const Work w = work_from(work, c);
            CoarseSpace coarse;
            shape_coarse_space(coarse, c, side);
            assemble_coarse_matrix(coarse, c, argument<const double>(mass, "mass", c.n), w);
            const Index size = 3 * coarse.count, stride = coarse.width + 1;
            double* dense = argument<double>(out, "out", size * size);
            for (Index row = 0; row < size; ++row) {
                for (Index col = 0; col < size; ++col) {
                    const Index hi = std::max(row, col), lo = std::min(row, col);
                    dense[row * size + col] = hi - lo <= coarse.width ? coarse.band[lo * stride + hi - lo] : 0.0;
                }
            }
        },
        nb::arg("cloth"), nb::arg("work"), nb::arg("mass"), nb::arg("side"), nb::arg("out"));
    m.def(
        "add_coarse_correction",
        [](nb::handle cloth, nb::handle work, nb::handle mass, Index side, nb::handle r, nb::handle z) {
            const Cloth c = cloth_from(cloth);
            const Work w = work_from(work, c);
            CoarseSpace coarse;
            shape_coarse_space(coarse, c, side);
            build_coarse_space(coarse, c, argument<const double>(mass, "mass", c.n), w);
            add_coarse_correction(coarse, c, argument<const double>(r, "r", 3 * c.n),
                                  argument<double>(z, "z", 3 * c.n));
        },
        nb::arg("cloth"), nb::arg("work"), nb::arg("mass"), nb::arg("side"), nb::arg("r"), nb::arg("z"));
}

}  // namespace wc::py
