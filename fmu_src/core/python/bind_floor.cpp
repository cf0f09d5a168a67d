// Bindings of the floor kernels (floor.cpp), with floor.py's names and arguments.
#include "convert.hpp"
#include "wetcloth/floor.hpp"

namespace wc::py {

WETCLOTH_BINDINGS(m) {
    m.def(
        "floor_contact",
        [](double z_min, double friction, nb::handle pos, nb::handle vel) {
            const Index n = size_of(pos) / 3;
            return floor_contact(n, z_min, friction, argument<double>(pos, "pos", 3 * n),
                                 argument<double>(vel, "vel", 3 * n));
        },
        nb::arg("z_min"), nb::arg("friction"), nb::arg("pos"), nb::arg("vel"));
    m.def(
        "hold_resting",
        [](double z_min, nb::handle pos, nb::handle vel, nb::handle free, nb::handle held) {
            const Index n = size_of(free);
            return hold_resting(n, z_min, argument<const double>(pos, "pos", 3 * n),
                                argument<const double>(vel, "vel", 3 * n), argument<double>(free, "free", n),
                                argument<double>(held, "held", n));
        },
        nb::arg("z_min"), nb::arg("pos"), nb::arg("vel"), nb::arg("free"), nb::arg("held"));
    m.def(
        "release_slipping",
        [](double friction, nb::handle force, nb::handle free, nb::handle held) {
            const Index n = size_of(free);
            return release_slipping(n, friction, argument<const double>(force, "force", 3 * n),
                                    argument<double>(free, "free", n), argument<double>(held, "held", n));
        },
        nb::arg("friction"), nb::arg("force"), nb::arg("free"), nb::arg("held"));
    m.def(
        "release_all",
        [](nb::handle free, nb::handle held) {
            const Index n = size_of(free);
            release_all(n, argument<double>(free, "free", n), argument<double>(held, "held", n));
        },
        nb::arg("free"), nb::arg("held"));
    m.def(
        "agree_history",
        [](double z_min, nb::handle pos, nb::handle vel, nb::handle prev_pos, nb::handle prev_vel, double h) {
            const Index n = size_of(pos) / 3;
            return agree_history(n, z_min, argument<const double>(pos, "pos", 3 * n),
                                 argument<const double>(vel, "vel", 3 * n),
                                 argument<double>(prev_pos, "prev_pos", 3 * n),
                                 argument<double>(prev_vel, "prev_vel", 3 * n), h);
        },
        nb::arg("z_min"), nb::arg("pos"), nb::arg("vel"), nb::arg("prev_pos"), nb::arg("prev_vel"), nb::arg("h"));
}

}  // namespace wc::py
