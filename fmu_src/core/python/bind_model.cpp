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
    m.def(
        "fast_move_cause",
        [](nb::handle phys, nb::handle numbers, nb::handle pos, nb::handle free, nb::handle held, double t, double h,
           double end, double blow_up_speed) {
            const Physics p = physics_from(phys);
            const Index n = size_of(free);
            const Index* places = p.collider_key_count > 0
                                      ? argument<const Index>(numbers, "numbers", p.collider_key_count)
                                      : nullptr;
            return fast_move_cause(p, places, n, argument<const double>(pos, "pos", 3 * n),
                                   argument<const double>(free, "free", n), argument<const double>(held, "held", n), t,
                                   h, end, blow_up_speed);
        },
        nb::arg("phys"), nb::arg("numbers"), nb::arg("pos"), nb::arg("free"), nb::arg("held"), nb::arg("time"),
        nb::arg("step"), nb::arg("end"), nb::arg("blow_up_speed"),
        "A blow-up's cause where the grip or a keyed collider of phys moves fast in the failed step of `step` s from "
        "`time` s, in a call to `end` s (the grip inputs' part as the first pinned particle not held, free and held "
        "(n) 0, of pos (3, n) m has it; numbers (int64, one per collider key row) the keys' places in the scene, "
        "from 1): the fastest move, if at least FAST_MOVE times blow_up_speed (m/s), and what to change; else ''.");
    m.def(
        "pinned_cause",
        [](nb::handle phys, nb::handle free, nb::handle pos) {
            const Index n = size_of(free);
            return pinned_cause(physics_from(phys), n, argument<const double>(free, "free", n),
                                argument<const double>(pos, "pos", 3 * n));
        },
        nb::arg("phys"), nb::arg("free"), nb::arg("pos"),
        "A blow-up's cause where a step ending at pos (3, n) m leaves a pinned particle (free (n) 0) pressed into a "
        "collider of phys, where the colliders are now (no farther out than thickness / 2): which, into which and "
        "what to move; else ''.");
    //: The Scene fields blow_up_advice and blow_up_text read.
    const auto settings = [](Index integrator, double tolerance, double max_step, double stretch_stiffness) {
        Scene scene;
        scene.integrator = integrator, scene.tolerance = tolerance, scene.max_step = max_step;
        scene.stretch_stiffness = stretch_stiffness;
        return scene;
    };
    m.def(
        "blow_up_advice",
        [settings](Index integrator, double tolerance, double max_step, double stable_step) {
            return blow_up_advice(settings(integrator, tolerance, max_step, 0.0), stable_step);
        },
        nb::arg("integrator"), nb::arg("tolerance"), nb::arg("max_step"), nb::arg("stable_step"),
        "What may keep a scene with these settings (integrator code, tolerance, max_step s) from blowing up, "
        "leaving out what it already does; where fixed steps exceed stable_step (s, the scheme's stability bound "
        "at rest), that bound");
    m.def(
        "blow_up_text",
        [settings](Index integrator, double tolerance, double max_step, double stretch_stiffness, nb::handle control,
                   bool finite, double speed, double t, double h, const std::string& cause) {
            return blow_up_text(settings(integrator, tolerance, max_step, stretch_stiffness), control_from(control),
                                finite, speed, t, h, cause);
        },
        nb::arg("integrator"), nb::arg("tolerance"), nb::arg("max_step"), nb::arg("stretch_stiffness"),
        nb::arg("control"), nb::arg("finite"), nb::arg("speed"), nb::arg("time"), nb::arg("step"), nb::arg("cause"),
        "The BlowUpError's text of a step of `step` s from `time` s that ended non-finite or at `speed` m/s (below "
        "the control's blow_up_speed: no step accepted), its likely cause `cause` or, if '', the settings' advice");
}

}  // namespace wc::py
