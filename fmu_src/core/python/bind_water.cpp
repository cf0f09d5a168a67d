// Bindings of the water kernels (bf41571:fmu_src/wetcloth/kernels/water.py) for tests: the same names and arguments as
// the numba kernels (arrays as NumPy arrays, C-contiguous).
#include "convert.hpp"
#include "wetcloth/water.hpp"

namespace nb = nanobind;

WETCLOTH_BINDINGS(m) {
    using namespace wc;
    using namespace wc::py;
    m.attr("DRAG_CELL_ROWS") = DRAG_CELL_ROWS;
    m.attr("MESH_RECORD_SLOTS") = MESH_RECORD_SLOTS;

    m.def(
        "submerged_fractions",
        [](nb::handle z, double water_level, double thickness, nb::handle smooth, nb::handle s) {
            const Index n = size_of(z);
            return submerged_fractions(n, argument<const double>(z, "z", n), water_level, thickness, truth(smooth),
                                       argument<double>(s, "s", n));
        },
        nb::arg("z"), nb::arg("water_level"), nb::arg("thickness"), nb::arg("smooth"), nb::arg("s"),
        "Write each particle's submerged fraction (0..1) into s; return the largest.");

    m.def(
        "buoyancy",
        [](nb::handle s, nb::handle volume, double density, double gravity, nb::handle force) {
            const Index n = size_of(s);
            buoyancy(n, argument<const double>(s, "s", n), argument<const double>(volume, "volume", n), density,
                     gravity, argument<double>(force, "force", 3 * n));
        },
        nb::arg("s"), nb::arg("volume"), nb::arg("density"), nb::arg("gravity"), nb::arg("force"),
        "Add Archimedes' upward force rho g V s to force[2].");

    m.def(
        "stokes_drag",
        [](nb::handle s, nb::handle coefficient, double current_x, double current_y, nb::handle vel,
           nb::handle force) {
            const Index n = size_of(s);
            stokes_drag(n, argument<const double>(s, "s", n), argument<const double>(coefficient, "coefficient", n),
                        current_x, current_y, argument<const double>(vel, "vel", 3 * n),
                        argument<double>(force, "force", 3 * n));
        },
        nb::arg("s"), nb::arg("coefficient"), nb::arg("current_x"), nb::arg("current_y"), nb::arg("vel"),
        nb::arg("force"), "Add -6 pi a eta s (v - v_water) (eq. 3.5) to force.");

    m.def(
        "face_drag",
        [](Index nx, Index ny, nb::handle pos, nb::handle vel, nb::handle s, double density, double c_normal,
           double c_tangential, double c_linear, double flow_x, double flow_y, nb::handle force, nb::handle cells,
           nb::handle skip_dry_rows, double flow_z, nb::handle above) {
            const Index n = nx * ny;
            const Fluid fluid{density, c_normal, c_tangential, c_linear, flow_x, flow_y, flow_z, truth(above)};
            face_drag(nx, ny, argument<const double>(pos, "pos", 3 * n), argument<const double>(vel, "vel", 3 * n),
                      argument<const double>(s, "s", n), fluid, argument<double>(force, "force", 3 * n),
                      argument<double>(cells, "cells", DRAG_CELL_ROWS * (n + nx + 1)), truth(skip_dry_rows));
        },
        nb::arg("nx"), nb::arg("ny"), nb::arg("pos"), nb::arg("vel"), nb::arg("s"), nb::arg("density"),
        nb::arg("c_normal"), nb::arg("c_tangential"), nb::arg("c_linear"), nb::arg("flow_x"), nb::arg("flow_y"),
        nb::arg("force"), nb::arg("cells"), nb::arg("skip_dry_rows") = true, nb::arg("flow_z") = 0.0,
        nb::arg("above") = false,
        "Add the face-model drag of a fluid flowing at (flow_x, flow_y, flow_z) m/s to force: the water's on each "
        "triangle's submerged part, or with above=True the air's on the rest; cells (DRAG_CELL_ROWS, n + nx + 1) scratch.");

    m.def(
        "face_drag_and_blocks",
        [](Index nx, Index ny, nb::handle pos, nb::handle vel, nb::handle s, double density, double c_normal,
           double c_tangential, double c_linear, double flow_x, double flow_y, double h, nb::handle force,
           nb::handle blocks, nb::handle cells, nb::handle skip_dry_rows, double flow_z, nb::handle above) {
            const Index n = nx * ny;
            const Fluid fluid{density, c_normal, c_tangential, c_linear, flow_x, flow_y, flow_z, truth(above)};
            face_drag_and_blocks(nx, ny, argument<const double>(pos, "pos", 3 * n),
                                 argument<const double>(vel, "vel", 3 * n), argument<const double>(s, "s", n), fluid,
                                 h, argument<double>(force, "force", 3 * n), argument<double>(blocks, "blocks", 6 * n),
                                 argument<double>(cells, "cells", DRAG_CELL_ROWS * (n + nx + 1)), truth(skip_dry_rows));
        },
        nb::arg("nx"), nb::arg("ny"), nb::arg("pos"), nb::arg("vel"), nb::arg("s"), nb::arg("density"),
        nb::arg("c_normal"), nb::arg("c_tangential"), nb::arg("c_linear"), nb::arg("flow_x"), nb::arg("flow_y"),
        nb::arg("h"), nb::arg("force"), nb::arg("blocks"), nb::arg("cells"), nb::arg("skip_dry_rows") = true,
        nb::arg("flow_z") = 0.0, nb::arg("above") = false,
        "Face drag as face_drag, plus h times its velocity Jacobian added to blocks (6, n).");
}
