// Bindings of the integrators' update kernels and the conjugate-gradient solve (integration.cpp), with
// integration.py's names and arguments; system_matvec also takes the bundles.
#include "convert.hpp"
#include "wetcloth/integration.hpp"

namespace wc::py {

namespace {

//: The views integration.py's array-argument kernels work on: the spring blocks and per-particle blocks
//: as a Work, the spring offsets and free flags as a Cloth of n = p.size / 3 particles.
struct Parts {
    Cloth cloth;
    Work work;
};

Parts parts(nb::handle offsets, nb::handle direction, nb::handle along, nb::handle across, nb::handle blocks,
            nb::handle free, nb::handle p, nb::handle buf) {
    Parts s;
    const Index n = size_of(p) / 3;
    s.cloth.n = n;
    s.cloth.grid_x = n;
    s.cloth.grid_y = 1;
    s.cloth.offsets = argument<const Index>(offsets, "offsets");
    s.cloth.families = size_of(offsets);
    const Index f = s.cloth.families;
    s.cloth.free = argument<double>(free, "free", n);
    s.work.direction = argument<double>(direction, "direction", f * 3 * n);
    s.work.along = argument<double>(along, "along", f * n);
    s.work.across = argument<double>(across, "across", f * n);
    s.work.blocks = argument<double>(blocks, "blocks", 6 * n);
    s.work.buf = argument<double>(buf, "buf", 2 * n);
    return s;
}

}  // namespace

WETCLOTH_BINDINGS(m) {
    m.def(
        "euler_update",
        [](nb::handle pos, nb::handle vel, nb::handle force, nb::handle dry_mass, nb::handle water, nb::handle free,
           double h, bool symplectic, nb::handle out_pos, nb::handle out_vel) {
            const Index n = size_of(water);
            return euler_update(n, argument<const double>(pos, "pos", 3 * n), argument<const double>(vel, "vel", 3 * n),
                                argument<const double>(force, "force", 3 * n),
                                argument<const double>(dry_mass, "dry_mass", n),
                                argument<const double>(water, "water", n), argument<const double>(free, "free", n), h,
                                symplectic, argument<double>(out_pos, "out_pos", 3 * n),
                                argument<double>(out_vel, "out_vel", 3 * n));
        },
        nb::arg("pos"), nb::arg("vel"), nb::arg("force"), nb::arg("dry_mass"), nb::arg("water"), nb::arg("free"),
        nb::arg("h"), nb::arg("symplectic"), nb::arg("out_pos"), nb::arg("out_vel"));
    m.def(
        "speed_and_finiteness",
        [](nb::handle pos, nb::handle vel, nb::handle water) {
            const Index n = size_of(water);
            const SpeedCheck s = speed_and_finiteness(n, argument<const double>(pos, "pos", 3 * n),
                                                      argument<const double>(vel, "vel", 3 * n),
                                                      argument<const double>(water, "water", n));
            return nb::make_tuple(s.speed, s.finite);
        },
        nb::arg("pos"), nb::arg("vel"), nb::arg("water"));
    m.def(
        "largest_deviation",
        [](nb::handle pos, nb::handle anchor) {
            const Index n = size_of(pos) / 3;
            return largest_deviation(n, argument<const double>(pos, "pos", 3 * n),
                                     argument<const double>(anchor, "anchor", 3 * n));
        },
        nb::arg("pos"), nb::arg("anchor"));
    m.def(
        "copy",
        [](nb::handle source, nb::handle target) {
            const Index count = size_of(source);
            copy(count, argument<const double>(source, "source", count), argument<double>(target, "target", count));
        },
        nb::arg("source"), nb::arg("target"));
    m.def(
        "total", [](nb::handle a) { return total(size_of(a), argument<const double>(a, "a")); }, nb::arg("a"));
    // system_matvec in double precision, and as CG takes it (the families' blocks from work.single_blocks).
    const auto system_matvec_in = [](Precision precision) {
        return [precision](nb::handle cloth, nb::handle work, nb::handle mass, nb::handle p, nb::handle out) {
            const Cloth c = cloth_from(cloth);
            const Work w = work_from(work, c);
            system_matvec(c, w, argument<const double>(mass, "mass", c.n), argument<const double>(p, "p", 3 * c.n),
                          argument<double>(out, "out", 3 * c.n), precision);
        };
    };
    m.def("system_matvec", system_matvec_in(Precision::DOUBLE), nb::arg("cloth"), nb::arg("work"), nb::arg("mass"),
          nb::arg("p"), nb::arg("out"));
    m.def("_system_matvec_single", system_matvec_in(Precision::SINGLE), nb::arg("cloth"), nb::arg("work"),
          nb::arg("mass"), nb::arg("p"), nb::arg("out"),
          "system_matvec as CG takes it: the families' blocks from work.single_blocks.");
    m.def(
        "_system_matvec",
        [](nb::handle offsets, nb::handle direction, nb::handle along, nb::handle across, nb::handle mass,
           nb::handle blocks, nb::handle free, nb::handle p, nb::handle out, nb::handle buf) {
            const Parts s = parts(offsets, direction, along, across, blocks, free, p, buf);
            const Index n = s.cloth.n;
            system_matvec(s.cloth, s.work, argument<const double>(mass, "mass", n),
                          argument<const double>(p, "p", 3 * n), argument<double>(out, "out", 3 * n));
        },
        nb::arg("offsets"), nb::arg("direction"), nb::arg("along"), nb::arg("across"), nb::arg("mass"),
        nb::arg("blocks"), nb::arg("free"), nb::arg("p"), nb::arg("out"), nb::arg("buf"));
    auto dot_binding = [](nb::handle a, nb::handle b) {
        const Index n = size_of(a) / 3;
        return dot(n, argument<const double>(a, "a", 3 * n), argument<const double>(b, "b", 3 * n));
    };
    m.def("dot", dot_binding, nb::arg("a"), nb::arg("b"));
    m.def("_dot", dot_binding, nb::arg("a"), nb::arg("b"));
    m.def(
        "symmetric_adjugate",
        [](double a, double b, double c, double d, double e, double f) {
            const Adjugate j = symmetric_adjugate(a, b, c, d, e, f);
            return nb::make_tuple(j.c11, j.c22, j.c33, j.c12, j.c13, j.c23, j.det);
        },
        nb::arg("a"), nb::arg("b"), nb::arg("c"), nb::arg("d"), nb::arg("e"), nb::arg("f"));
    m.def(
        "conjugate_gradient_step",
        [](double alpha, nb::handle p, nb::handle ap, nb::handle x, nb::handle r) {
            const Index n = size_of(x) / 3;
            conjugate_gradient_step(n, alpha, argument<const double>(p, "p", 3 * n),
                                    argument<const double>(ap, "ap", 3 * n), argument<double>(x, "x", 3 * n),
                                    argument<double>(r, "r", 3 * n));
        },
        nb::arg("alpha"), nb::arg("p"), nb::arg("ap"), nb::arg("x"), nb::arg("r"));
    m.def(
        "next_search_direction",
        [](double beta, nb::handle z, nb::handle p) {
            const Index n = size_of(p) / 3;
            next_search_direction(n, beta, argument<const double>(z, "z", 3 * n), argument<double>(p, "p", 3 * n));
        },
        nb::arg("beta"), nb::arg("z"), nb::arg("p"));
}

}  // namespace wc::py
