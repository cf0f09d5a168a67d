// The cloth's mechanical energy as the core weighs it (wetcloth.energy; the fixed-step mode's check of its steps).
#include "convert.hpp"
#include "wetcloth/energy.hpp"

namespace wc::py {

WETCLOTH_BINDINGS(m) {
    m.def(
        "mechanical_energy",
        [](nb::handle cloth, double wet_factor, nb::handle mass, nb::handle water, nb::handle pos, nb::handle vel) {
            const Cloth c = cloth_from(cloth);
            return mechanical_energy(c, wet_factor, argument<const double>(mass, "mass", c.n),
                                     argument<const double>(water, "water", c.n),
                                     argument<const double>(pos, "pos", 3 * c.n),
                                     argument<const double>(vel, "vel", 3 * c.n));
        },
        nb::arg("cloth"), nb::arg("wet_factor"), nb::arg("mass"), nb::arg("water"), nb::arg("pos"), nb::arg("vel"),
        "Kinetic + gravitational (zero at z = 0) + elastic energy (J) of the cloth at pos, vel ((3, n)) with the "
        "particles' masses and water (n, kg), every spring's stiffness grown by wet_factor times its ends' mean "
        "saturation (wetcloth.energy's).");
    m.def(
        "buoyancy_energy",
        [](nb::handle cloth, nb::handle phys, nb::handle pos) {
            const Cloth c = cloth_from(cloth);
            return buoyancy_energy(c, physics_from(phys), argument<const double>(pos, "pos", 3 * c.n));
        },
        nb::arg("cloth"), nb::arg("phys"), nb::arg("pos"),
        "Buoyancy's potential energy (J) of the cloth at pos ((3, n)): minus its gradient is the buoyancy force.");
}

}  // namespace wc::py
