// Bindings of the plane preconditioner (plane.cpp) under the names of bf41571:fmu_src/wetcloth/kernels/plane.py.
// Where the numba kernels took the cloth's offsets (refresh, refresh_from_jacobian) or grid_x
// (follow_cloth), these take the cloth bundle, or that array or number as before.
#include "convert.hpp"
#include "wetcloth/plane.hpp"

namespace {

namespace nb = nanobind;
using namespace wc;

Index particles(nb::handle plane) { return py::size_of(plane.attr("normal")); }

//: The cloth bundle, or a cloth holding only the grid and the spring offsets (an int64 array).
Cloth cloth_or_offsets(nb::handle value, const Plane& plane, Index n) {
    if (nb::hasattr(value, "offsets")) return py::cloth_from(value);
    Cloth cloth;
    cloth.grid_x = plane.grid.levels[NX];
    cloth.grid_y = plane.grid.levels[NY];
    cloth.n = n;
    cloth.offsets = py::argument<const Index>(value, "offsets");
    cloth.families = py::size_of(value);
    return cloth;
}

}  // namespace

WETCLOTH_BINDINGS(m) {
    m.attr("REFACTOR_SCALE") = REFACTOR_SCALE;
    m.attr("REFACTOR_CHANGE") = REFACTOR_CHANGE;
    m.attr("JACOBIAN_REFRESH_AFTER") = JACOBIAN_REFRESH_AFTER;
    m.attr("MESH_REFRESH_AFTER") = MESH_REFRESH_AFTER;
    m.attr("MULTIGRID_SIDE") = MULTIGRID_SIDE;
    m.attr("COARSEST_SIDE") = COARSEST_SIDE;
    m.attr("ALGEBRAIC_SIZE") = ALGEBRAIC_SIZE;
    m.attr("COARSEST_SIZE") = COARSEST_SIZE;
    m.attr("ALGEBRAIC_COLUMNS") = static_cast<Index>(ALGEBRAIC_COLUMNS);
    m.attr("COMPONENTS") = COMPONENTS;
    m.attr("NORMAL") = NORMAL;
    m.def("refresh", [](nb::handle plane, nb::handle cloth, nb::handle mass, double scale) {
        const Index n = particles(plane);
        Plane p = py::plane_from(plane, n);
        const Cloth c = cloth_or_offsets(cloth, p, n);
        return wc::refresh(p, c, py::argument<const double>(mass, "mass", n), scale);
    });
    m.def("refresh_from_jacobian", [](nb::handle plane, nb::handle cloth, nb::handle mass, nb::handle along) {
        const Index n = particles(plane);
        Plane p = py::plane_from(plane, n);
        const Cloth c = cloth_or_offsets(cloth, p, n);
        return wc::refresh_from_jacobian(p, c, py::argument<const double>(mass, "mass", n),
                                         py::argument<const double>(along, "along", c.families * n));
    });
    m.def("jacobian_refresh_pays", [](nb::handle plane, double iterations) {
        return wc::jacobian_refresh_pays(py::plane_from(plane, particles(plane)), iterations);
    });
    m.def("banded", [](nb::handle plane) { return wc::banded(py::plane_from(plane, particles(plane))); });
    m.def("follow_cloth", [](nb::handle plane, nb::handle cloth, nb::handle pos) {
        const Index n = particles(plane);
        Plane p = py::plane_from(plane, n);
        Cloth c;
        if (nb::hasattr(cloth, "offsets")) {
            c = py::cloth_from(cloth);
        } else {  // grid_x
            c.grid_x = nb::cast<Index>(cloth);
            c.n = n;
        }
        wc::follow_cloth(p, c, py::argument<const double>(pos, "pos", 3 * n));
    });
    m.def("set_normal_diagonal", [](nb::handle plane, nb::handle mass, nb::handle diagonal_blocks, nb::handle blocks) {
        const Index n = particles(plane);
        Plane p = py::plane_from(plane, n);
        wc::set_normal_diagonal(p, n, py::argument<const double>(mass, "mass", n),
                                py::argument<const double>(diagonal_blocks, "diagonal_blocks", 6 * n),
                                py::argument<const double>(blocks, "blocks", 6 * n));
    });
    m.def("set_systems_from_jacobian", [](nb::handle plane, nb::handle cloth, nb::handle mass, nb::handle work) {
        const Index n = particles(plane);
        Plane p = py::plane_from(plane, n);
        const Cloth c = py::cloth_from(cloth);
        return wc::set_systems_from_jacobian(p, c, py::argument<const double>(mass, "mass", n), py::work_from(work, c));
    });
    m.def("apply", [](nb::handle plane, nb::handle free, nb::handle r, nb::handle z) {
        const Index n = particles(plane);
        Plane p = py::plane_from(plane, n);
        wc::apply(p, n, py::argument<const double>(free, "free", n), py::argument<const double>(r, "r", 3 * n),
                  py::argument<double>(z, "z", 3 * n));
    });
}
