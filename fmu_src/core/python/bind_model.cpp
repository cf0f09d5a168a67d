// Bindings of the scene's rules as a whole (model.cpp) that scene.validate applies as the native units do.
#include <nanobind/stl/string.h>

#include "convert.hpp"
#include "wetcloth/model.hpp"

namespace wc::py {

WETCLOTH_BINDINGS(m) {
    m.def(
        "grid_start_problem",
        [](Index nx, Index ny, double width, double length, double thickness, double initial_height,
           double initial_tilt, double floor_level) {
            Scene scene;
            scene.nx = nx, scene.ny = ny, scene.width = width, scene.length = length, scene.thickness = thickness;
            scene.initial_height = initial_height, scene.initial_tilt = initial_tilt, scene.floor_level = floor_level;
            return grid_start_problem(scene, nullptr);
        },
        nb::arg("nx"), nb::arg("ny"), nb::arg("width"), nb::arg("length"), nb::arg("thickness"),
        nb::arg("initial_height"), nb::arg("initial_tilt"), nb::arg("floor_level"),
        "'' or the ParameterError's text of a grid whose cells are more than LONGEST_CELL times longer one way "
        "than the other, or that starts at or below the floor");
    m.def(
        "mesh_floor_problem",
        [](nb::handle pos, double thickness, double floor_level, bool placed) {
            const Index n = size_of(pos) / 3;
            Scene scene;
            scene.thickness = thickness, scene.floor_level = floor_level;
            scene.place_mesh = placed ? SWITCH_ON : SWITCH_OFF;
            return mesh_floor_problem(scene, argument<const double>(pos, "pos", 3 * n), n);
        },
        nb::arg("pos"), nb::arg("thickness"), nb::arg("floor_level"), nb::arg("placed"),
        "'' or the ParameterError's text of a mesh cloth whose start positions pos (3, n) m reach the floor");
    m.def(
        "stability_problem", [](nb::handle control) { return stability_problem(control_from(control)); },
        nb::arg("control"),
        "'' or the ParameterError's text of an explicit scheme stable on this cloth at rest only at steps below "
        "the smallest step, naming what sets that bound");
}

}  // namespace wc::py
