// Bindings of the spring kernels (bf41571:fmu_src/wetcloth/kernels/springs.py) for tests and benchmarks: the same names
// and arguments as the numba kernels (arrays as NumPy arrays, C-contiguous; n from pos / p).
#include <vector>

#include "convert.hpp"
#include "wetcloth/springs.hpp"

namespace {

using namespace wc;
using namespace wc::py;

//: A Cloth holding only the spring families (what the spring kernels read).
Cloth spring_cloth(Index n, nb::handle offsets, nb::handle rest, nb::handle tension_only, nb::handle stiffness,
                   nb::handle damping) {
    Cloth c;
    c.n = n;
    c.offsets = argument<const Index>(offsets, "offsets");
    c.families = size_of(offsets);
    c.rest = argument<const double>(rest, "rest", c.families);
    c.tension_only = argument<const bool>(tension_only, "tension_only", c.families);
    c.stiffness = argument<const double>(stiffness, "stiffness", c.families * n);
    c.damping = argument<const double>(damping, "damping", c.families * n);
    return c;
}

}  // namespace

WETCLOTH_BINDINGS(m) {
    m.attr("TENSION_ROUNDING") = TENSION_ROUNDING;
    m.attr("BUCKLING_ROUNDING") = BUCKLING_ROUNDING;
    m.attr("BUCKLING_STRAIN") = BUCKLING_STRAIN;

    m.def(
        "pulling_stretch",
        [](double stretch, double width) {
            const Stretch s = pulling_stretch(stretch, width);
            return nb::make_tuple(s.value, s.slope);
        },
        nb::arg("stretch"), nb::arg("width"),
        "(the stretch (m) a tension-only spring pulls with, its derivative (-)) for a stretch L - l0 (m).");

    m.def(
        "spring_forces",
        [](nb::handle offsets, nb::handle rest, nb::handle tension_only, nb::handle stiffness, nb::handle damping,
           nb::handle projected, double wet_factor, nb::handle saturation, nb::handle pos, nb::handle vel,
           nb::handle force, nb::handle buf) {
            const Index n = size_of(pos) / 3;
            const Cloth cloth = spring_cloth(n, offsets, rest, tension_only, stiffness, damping);
            Physics phys;
            phys.projected = truth(projected);
            phys.wet_factor = wet_factor;
            spring_forces(cloth, phys, argument<const double>(saturation, "saturation", n),
                          argument<const double>(pos, "pos", 3 * n), argument<const double>(vel, "vel", 3 * n),
                          argument<double>(force, "force", 3 * n), argument<double>(buf, "buf", n));
        },
        nb::arg("offsets"), nb::arg("rest"), nb::arg("tension_only"), nb::arg("stiffness"), nb::arg("damping"),
        nb::arg("projected"), nb::arg("wet_factor"), nb::arg("saturation"), nb::arg("pos"), nb::arg("vel"),
        nb::arg("force"), nb::arg("buf"),
        "Add tension (eq. 3.1) and damping (eq. 3.2) of every spring to force (N, (3, n)); buf: a row of n scratch.");

    m.def(
        "spring_forces_and_blocks",
        [](nb::handle offsets, nb::handle rest, nb::handle tension_only, nb::handle stiffness, nb::handle damping,
           nb::handle projected, double wet_factor, nb::handle saturation, nb::handle pos, nb::handle vel, double h,
           nb::handle force, nb::handle diagonal_blocks, nb::handle direction, nb::handle along,
           nb::handle across, nb::handle buf, double slack_slope) {
            const Index n = size_of(pos) / 3;
            const Cloth cloth = spring_cloth(n, offsets, rest, tension_only, stiffness, damping);
            const Index f = cloth.families;
            Physics phys;
            phys.projected = truth(projected);
            phys.wet_factor = wet_factor;
            Work work;
            work.force = argument<double>(force, "force", 3 * n);
            work.diagonal_blocks = argument<double>(diagonal_blocks, "diagonal_blocks", 6 * n);
            work.direction = argument<double>(direction, "direction", f * 3 * n);
            work.along = argument<double>(along, "along", f * n);
            work.across = argument<double>(across, "across", f * n);
            work.buf = argument<double>(buf, "buf", n);
            std::vector<float> single_blocks(static_cast<std::size_t>(f * 5 * n));  // written, not returned
            work.single_blocks = single_blocks.data();
            spring_forces_and_blocks(cloth, phys, argument<const double>(saturation, "saturation", n),
                                     argument<const double>(pos, "pos", 3 * n),
                                     argument<const double>(vel, "vel", 3 * n), h, slack_slope, work);
        },
        nb::arg("offsets"), nb::arg("rest"), nb::arg("tension_only"), nb::arg("stiffness"), nb::arg("damping"),
        nb::arg("projected"), nb::arg("wet_factor"), nb::arg("saturation"), nb::arg("pos"), nb::arg("vel"),
        nb::arg("h"), nb::arg("force"), nb::arg("diagonal_blocks"), nb::arg("direction"),
        nb::arg("along"), nb::arg("across"), nb::arg("buf"), nb::arg("slack_slope") = 0.0,
        "Forces as spring_forces, the springs' blocks into diagonal_blocks (6, n) and "
        "each spring's block into direction (F, 3, n), along, across (F, n); tension-only springs' slope along "
        "themselves at least slack_slope in the blocks.");

    m.def(
        "spring_matvec",
        [](nb::handle offsets, nb::handle direction, nb::handle along, nb::handle across, nb::handle p,
           nb::handle out, nb::handle buf) {
            const Index n = size_of(p) / 3;
            Cloth cloth;
            cloth.n = n;
            cloth.offsets = argument<const Index>(offsets, "offsets");
            cloth.families = size_of(offsets);
            const Index f = cloth.families;
            Work work;
            work.direction = argument<double>(direction, "direction", f * 3 * n);
            work.along = argument<double>(along, "along", f * n);
            work.across = argument<double>(across, "across", f * n);
            work.buf = argument<double>(buf, "buf", 2 * n);
            spring_matvec(cloth, work, argument<const double>(p, "p", 3 * n), argument<double>(out, "out", 3 * n));
        },
        nb::arg("offsets"), nb::arg("direction"), nb::arg("along"), nb::arg("across"), nb::arg("p"), nb::arg("out"),
        nb::arg("buf"), "Add the springs' part of the system matrix times p (3, n) to out; buf (2, n) scratch.");
}
