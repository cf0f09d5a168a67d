// Bindings of the multigrid V-cycle (multigrid.cpp) under the names of bf41571:fmu_src/wetcloth/kernels/multigrid.py.
#include "convert.hpp"
#include "wetcloth/multigrid.hpp"

WETCLOTH_BINDINGS(m) {
    namespace nb = nanobind;
    m.attr("SWEEPS") = wc::SWEEPS;
    m.attr("CENTRE") = wc::CENTRE;
    m.def("padded_index", [](nb::handle levels, wc::Index level, wc::Index ix, wc::Index iy) {
        return wc::padded_index(wc::py::argument<const wc::Index>(levels, "levels", 4 * (level + 1)), level, ix, iy);
    });
    m.def("galerkin", [](nb::handle hierarchy, wc::Index level) {
        wc::Hierarchy h = wc::py::hierarchy_from(hierarchy);
        if (level < 0 || level + 1 >= h.level_count) throw nb::index_error("galerkin: no coarser level");
        wc::galerkin(h, level);
    });
    m.def("v_cycle_down", [](nb::handle hierarchy) {
        wc::Hierarchy h = wc::py::hierarchy_from(hierarchy);
        wc::v_cycle_down(h);
    });
    m.def("v_cycle_up", [](nb::handle hierarchy) {
        wc::Hierarchy h = wc::py::hierarchy_from(hierarchy);
        wc::v_cycle_up(h);
    });
}
