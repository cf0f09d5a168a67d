// Bindings of the implicit steps (implicit.cpp), with implicit.py's names and arguments, and its
// constants (make_solver stays in Python).
#include "convert.hpp"
#include "wetcloth/implicit.hpp"

namespace wc::py {

WETCLOTH_BINDINGS(m) {
    m.attr("NEWTON_ITERATIONS_MAX") = NEWTON_ITERATIONS_MAX;
    m.attr("NEWTON_RELATIVE") = NEWTON_RELATIVE;
    m.attr("NEWTON_VELOCITY_TIME") = NEWTON_VELOCITY_TIME;
    m.attr("FIRST_ITERATION_TRUST") = FIRST_ITERATION_TRUST;
    m.attr("CG_TOLERANCE") = CG_TOLERANCE;
    m.attr("FIXED_STEP_CG_TOLERANCE") = FIXED_STEP_CG_TOLERANCE;
    m.attr("CG_FLOOR") = CG_FLOOR;
    m.attr("NEWTON_CG_ITERATIONS") = NEWTON_CG_ITERATIONS;
    m.attr("LINE") = LINE;
    m.attr("PARABOLA") = PARABOLA;
    m.attr("NEWTON_ITERATIONS") = static_cast<Index>(NEWTON_ITERATIONS);
    m.attr("CG_ITERATIONS") = static_cast<Index>(CG_ITERATIONS);
    m.attr("FACTORISATIONS") = static_cast<Index>(FACTORISATIONS);
    m.attr("UNCONVERGED") = static_cast<Index>(UNCONVERGED);
    m.attr("RESTARTS") = static_cast<Index>(RESTARTS);
    m.attr("SOLVER_COUNTERS") = static_cast<Index>(SOLVER_COUNTERS);
    m.def(
        "bdf2_step",
        [](nb::handle cloth, nb::handle phys, nb::handle work, nb::handle solver, nb::handle plane, nb::handle pos,
           nb::handle vel, nb::handle water, nb::handle step_water, nb::handle prev_pos, nb::handle prev_vel,
           nb::handle prev_water, nb::handle acceleration, double h, double h_prev, double newton_tolerance,
           double cg_tolerance, nb::handle memory, nb::handle out_pos, nb::handle out_vel, int mode, bool descent) {
            const Cloth c = cloth_from(cloth);
            const Index n = c.n;
            Work w = work_from(work, c);
            Solver s = solver_from(solver, n);
            Plane p = plane_from(plane, n);
            const StepEstimate e = bdf2_step(
                c, physics_from(phys), w, s, p, argument<const double>(pos, "pos", 3 * n),
                argument<const double>(vel, "vel", 3 * n), argument<const double>(water, "water", n),
                argument<const double>(step_water, "step_water", n), argument<const double>(prev_pos, "prev_pos", 3 * n),
                argument<const double>(prev_vel, "prev_vel", 3 * n), argument<const double>(prev_water, "prev_water", n),
                argument<const double>(acceleration, "acceleration", 3 * n), h, h_prev, newton_tolerance, cg_tolerance,
                static_cast<NewtonMode>(mode), descent, argument<double>(memory, "memory", 4), argument<double>(out_pos, "out_pos", 3 * n),
                argument<double>(out_vel, "out_vel", 3 * n));
            return nb::make_tuple(e.error, e.converged);
        },
        nb::arg("cloth"), nb::arg("phys"), nb::arg("work"), nb::arg("solver"), nb::arg("plane"), nb::arg("pos"),
        nb::arg("vel"), nb::arg("water"), nb::arg("step_water"), nb::arg("prev_pos"), nb::arg("prev_vel"),
        nb::arg("prev_water"), nb::arg("acceleration"), nb::arg("h"), nb::arg("h_prev"), nb::arg("newton_tolerance"),
        nb::arg("cg_tolerance"), nb::arg("memory"), nb::arg("out_pos"), nb::arg("out_vel"),
        nb::arg("mode") = 0, nb::arg("descent") = false);
}

}  // namespace wc::py
