// Bindings of the water exchange kernels (absorption.cpp), with absorption.py's names and arguments.
#include "convert.hpp"
#include "wetcloth/absorption.hpp"

namespace wc::py {

WETCLOTH_BINDINGS(m) {
    m.attr("SATURATED") = SATURATED;
    m.def("contact_fraction", &contact_fraction, nb::arg("z_start"), nb::arg("z_end"), nb::arg("vz_start"),
          nb::arg("vz_end"), nb::arg("h"), nb::arg("surface"));
    m.def(
        "uptake",
        [](nb::handle z_start, nb::handle z_end, nb::handle vz_start, nb::handle vz_end, double surface,
           nb::handle dry_mass, double capacity, double rate, double h, nb::handle water, nb::handle out) {
            const Index n = size_of(water);
            return uptake(n, argument<const double>(z_start, "z_start", n), argument<const double>(z_end, "z_end", n),
                          argument<const double>(vz_start, "vz_start", n), argument<const double>(vz_end, "vz_end", n),
                          surface, argument<const double>(dry_mass, "dry_mass", n), capacity, rate, h,
                          argument<const double>(water, "water", n), argument<double>(out, "out", n));
        },
        nb::arg("z_start"), nb::arg("z_end"), nb::arg("vz_start"), nb::arg("vz_end"), nb::arg("surface"),
        nb::arg("dry_mass"), nb::arg("capacity"), nb::arg("rate"), nb::arg("h"), nb::arg("water"), nb::arg("out"));
    m.def(
        "uptake_timing_error",
        [](nb::handle z_start, nb::handle z_end, nb::handle vz_start, nb::handle vz_end, double surface,
           nb::handle dry_mass, double capacity, double rate, double h, nb::handle water) {
            const Index n = size_of(water);
            return uptake_timing_error(
                n, argument<const double>(z_start, "z_start", n), argument<const double>(z_end, "z_end", n),
                argument<const double>(vz_start, "vz_start", n), argument<const double>(vz_end, "vz_end", n), surface,
                argument<const double>(dry_mass, "dry_mass", n), capacity, rate, h,
                argument<const double>(water, "water", n));
        },
        nb::arg("z_start"), nb::arg("z_end"), nb::arg("vz_start"), nb::arg("vz_end"), nb::arg("surface"),
        nb::arg("dry_mass"), nb::arg("capacity"), nb::arg("rate"), nb::arg("h"), nb::arg("water"));
    m.def(
        "keep_momentum",
        [](nb::handle mass_before, nb::handle dry_mass, nb::handle water, nb::handle vel) {
            const Index n = size_of(water);
            keep_momentum(n, argument<const double>(mass_before, "mass_before", n),
                          argument<const double>(dry_mass, "dry_mass", n), argument<const double>(water, "water", n),
                          argument<double>(vel, "vel", 3 * n));
        },
        nb::arg("mass_before"), nb::arg("dry_mass"), nb::arg("water"), nb::arg("vel"));
    m.def(
        "dry",
        [](nb::handle z_start, nb::handle z_end, nb::handle vz_start, nb::handle vz_end, double surface, double rate,
           double h, nb::handle water) {
            const Index n = size_of(water);
            return dry(n, argument<const double>(z_start, "z_start", n), argument<const double>(z_end, "z_end", n),
                       argument<const double>(vz_start, "vz_start", n), argument<const double>(vz_end, "vz_end", n),
                       surface, rate, h, argument<double>(water, "water", n));
        },
        nb::arg("z_start"), nb::arg("z_end"), nb::arg("vz_start"), nb::arg("vz_end"), nb::arg("surface"),
        nb::arg("rate"), nb::arg("h"), nb::arg("water"));
    m.def(
        "wick",
        [](nb::handle cloth, Index substeps, double h, nb::handle water, nb::handle vel, nb::handle buf) {
            const Cloth c = cloth_from(cloth);
            const Index n = c.n;
            return wick(c, substeps, h, argument<double>(water, "water", n), argument<double>(vel, "vel", 3 * n),
                        argument<double>(buf, "buf", 6 * n));
        },
        nb::arg("cloth"), nb::arg("substeps"), nb::arg("h"), nb::arg("water"), nb::arg("vel"), nb::arg("buf"),
        "Wick water (kg, (n)) between the cloth's neighbours over h (s) in `substeps` sub-steps, carrying momentum "
        "(vel (3, n) m/s); buf (6, n) scratch.  Returns the largest amount moved over one link in one sub-step (kg).");
}

}  // namespace wc::py
