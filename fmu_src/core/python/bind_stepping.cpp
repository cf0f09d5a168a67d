// The step loop as Python sees it: a Stepper holds the views of one simulation's bundles (kept alive
// with it) and self-collision's candidate lists, and advances them with the GIL released.
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>

#include "convert.hpp"
#include "wetcloth/reused_plane.hpp"
#include "wetcloth/self_contact.hpp"
#include "wetcloth/stepping.hpp"

namespace wc::py {
namespace {

class Stepper {
  public:
    Stepper(nb::object cloth, nb::object phys, nb::object control, nb::object work, nb::object solver,
            nb::object plane, nb::object contact, nb::object buffers, nb::object clock)
        : work_(work), solver_(solver), plane_(plane), contact_(contact), buffers_(buffers), clock_(clock) {
        set_cloth(cloth);
        set_physics(phys);
        set_control(control);
        const Index n = core_.cloth.n;
        core_.work = work_from(work, core_.cloth);
        core_.solver = solver_from(solver, n);
        core_.plane = plane_from(plane, n);
        if (reuses_jacobian(core_.plane)) {
            attach_reused(reused_, core_.plane, n);
            core_.reused = &reused_;
        }
        core_.contact = contact_from(contact, n, &lists_);
        core_.buf = buffers_from(buffers, n);
        core_.clock = argument<double>(clock, "clock", CLOCK_SIZE);
    }

    //: A new Cloth bundle (the scene's parameters changed its per-particle constants); same grid.
    void set_cloth(nb::object cloth) {
        Cloth view = cloth_from(cloth);
        if (cloth_.is_valid() && view.n != core_.cloth.n) throw nb::value_error("set_cloth: another grid");
        core_.cloth = view;
        cloth_ = cloth;
    }
    void set_physics(nb::object phys) {
        core_.phys = physics_from(phys);
        phys_ = phys;
    }
    void set_control(nb::object control) {
        core_.control = control_from(control);
        control_ = control;
    }

    Index advance(double target, Index max_steps, double pause_after) {
        nb::gil_scoped_release release;
        return wc::advance(core_, target, max_steps, pause_after);
    }

    std::tuple<Index, Index> advance_sampling(nb::handle times, nb::handle outputs, nb::handle errors, Index first,
                                              Index max_steps, double pause_after) {
        const Index count = size_of(times);
        const double* t = argument<const double>(times, "times", count);
        double* out = argument<double>(outputs, "outputs", count * OUTPUT_COUNT);
        double* err = argument<double>(errors, "errors", count);
        if (first < 0 || first > count) throw nb::index_error("advance_sampling: first out of range");
        SamplingResult result;
        {
            nb::gil_scoped_release release;
            result = wc::advance_sampling(core_, t, count, out, err, first, max_steps, pause_after);
        }
        return {result.status, result.next};
    }

    //: Build self-collision's candidate list from its reference positions with `margin` (m).
    void build_contact(double thickness, double margin) { wc::build(core_.contact, core_.cloth.n, thickness, margin); }
    void invalidate_contact() { wc::invalidate(core_.contact); }
    std::tuple<Index, Index> candidate_counts() const {
        return {lists_.point_triangle_count(), lists_.edge_edge_count()};
    }

    //: Size of the reused Jacobian systems' source (0: the cloth has none; reused_plane.hpp).
    Index reused_size() const { return core_.reused != nullptr ? static_cast<Index>(reused_.source.size()) : 0; }
    //: Copy the reused systems' source and rule into `source` (reused_size) and `rule` (REUSE_RULE_SIZE).
    void save_reused(nb::handle source, nb::handle rule) const {
        double* s = argument<double>(source, "source", reused_size());
        double* r = argument<double>(rule, "rule", REUSE_RULE_SIZE);
        std::copy(reused_.source.begin(), reused_.source.begin() + reused_size(), s);
        std::copy(reused_.rule.begin(), reused_.rule.end(), r);
    }
    //: Set the reused systems' source and rule and rebuild them from it (a restored run).
    void restore_reused(nb::handle source, nb::handle rule) {
        if (core_.reused == nullptr) return;
        const double* s = argument<const double>(source, "source", reused_size());
        const double* r = argument<const double>(rule, "rule", REUSE_RULE_SIZE);
        std::copy(s, s + reused_size(), reused_.source.begin());
        std::copy(r, r + REUSE_RULE_SIZE, reused_.rule.begin());
        rebuild_reused(reused_, core_.cloth);
    }

  private:
    Core core_;
    ReusedPlane reused_;
    ContactLists lists_;
    nb::object cloth_, phys_, control_, work_, solver_, plane_, contact_, buffers_, clock_;
};

}  // namespace

WETCLOTH_BINDINGS(m) {
    nb::class_<Stepper>(m, "Stepper",
                        "The step loop over one simulation's bundles (Cloth, Physics, Control, Work, Solver, "
                        "Plane, Contact, Buffers and the clock), which it keeps alive")
        .def(nb::init<nb::object, nb::object, nb::object, nb::object, nb::object, nb::object, nb::object,
                      nb::object, nb::object>(),
             "cloth"_a, "phys"_a, "control"_a, "work"_a, "solver"_a, "plane"_a, "contact"_a, "buffers"_a, "clock"_a)
        .def("set_cloth", &Stepper::set_cloth)
        .def("set_physics", &Stepper::set_physics)
        .def("set_control", &Stepper::set_control)
        .def("advance", &Stepper::advance, "target"_a, "max_steps"_a, "pause_after"_a = PAUSE_AFTER,
             "Step until the clock reaches target (s); DONE, BLOWN_UP, or PAUSED after max_steps steps or "
             "pause_after s of wall-clock time (which never changes what is computed)")
        .def("advance_sampling", &Stepper::advance_sampling, "times"_a, "outputs"_a, "errors"_a, "first"_a,
             "max_steps"_a, "pause_after"_a = PAUSE_AFTER,
             "Advance to each of times (s) from index first and record the outputs, and in errors (zeroed "
             "before the first call) the largest error (m) a step up to each time estimated for itself; "
             "(status, next index)")
        .def("build_contact", &Stepper::build_contact, "thickness"_a, "margin"_a)
        .def("invalidate_contact", &Stepper::invalidate_contact)
        .def("candidate_counts", &Stepper::candidate_counts)
        .def("reused_size", &Stepper::reused_size)
        .def("save_reused", &Stepper::save_reused, "source"_a, "rule"_a)
        .def("restore_reused", &Stepper::restore_reused, "source"_a, "rule"_a);
    m.attr("REUSE_RULE_SIZE") = Index(REUSE_RULE_SIZE);
    m.def(
        "record_outputs",
        [](nb::handle dry_mass, double water_level, nb::handle pos, nb::handle water, nb::handle row) {
            const Index n = size_of(dry_mass);
            wc::record_outputs(n, argument<const double>(dry_mass, "dry_mass", n), water_level,
                               argument<const double>(pos, "pos", 3 * n), argument<const double>(water, "water", n),
                               argument<double>(row, "row", OUTPUT_COUNT));
        },
        "dry_mass"_a, "water_level"_a, "pos"_a, "water"_a, "row"_a);
    m.def(
        "state_problem",
        [](nb::handle cloth, nb::handle phys, nb::handle control, nb::handle pos, nb::handle vel, nb::handle water,
           nb::handle prev_pos, nb::handle prev_vel, nb::handle prev_water, nb::handle acceleration, nb::handle anchor,
           nb::handle contact_reference, double contact_margin, nb::handle clock, nb::handle others) {
            const Cloth c = cloth_from(cloth);
            const Index n = c.n;
            StateView s;
            s.pos = argument<const double>(pos, "pos", 3 * n);
            s.vel = argument<const double>(vel, "vel", 3 * n);
            s.water = argument<const double>(water, "water", n);
            s.prev_pos = argument<const double>(prev_pos, "prev_pos", 3 * n);
            s.prev_vel = argument<const double>(prev_vel, "prev_vel", 3 * n);
            s.prev_water = argument<const double>(prev_water, "prev_water", n);
            s.acceleration = argument<const double>(acceleration, "acceleration", 3 * n);
            s.anchor = argument<const double>(anchor, "anchor", 3 * n);
            s.contact_reference = argument<const double>(contact_reference, "contact_reference", 3 * n);
            s.contact_margin = contact_margin;
            s.clock = argument<const double>(clock, "clock", CLOCK_SIZE);
            s.other_count = size_of(others);
            s.others = argument<const double>(others, "others", s.other_count);
            const Physics p = physics_from(phys);
            const Control k = control_from(control);
            nb::gil_scoped_release release;
            return wc::state_problem(c, p, k, s);
        },
        "cloth"_a, "phys"_a, "control"_a, "pos"_a, "vel"_a, "water"_a, "prev_pos"_a, "prev_vel"_a, "prev_water"_a,
        "acceleration"_a, "anchor"_a, "contact_reference"_a, "contact_margin"_a, "clock"_a, "others"_a,
        "What makes a state one the cloth cannot be in ('' if nothing): stepping.hpp, state_problem");
    m.def("stable_step", [](nb::handle control, double speed) { return wc::stable_step(control_from(control), speed); });
    m.attr("DONE") = Index(DONE);
    m.attr("BLOWN_UP") = Index(BLOWN_UP);
    m.attr("PAUSED") = Index(PAUSED);
    m.attr("CLOCK_SIZE") = Index(CLOCK_SIZE);
    m.attr("OUTPUT_COUNT") = OUTPUT_COUNT;
    m.attr("MAX_REJECTIONS") = MAX_REJECTIONS;
    m.attr("PAUSE_AFTER") = PAUSE_AFTER;
    m.attr("MAX_TIME") = MAX_TIME;
    m.attr("MAX_COORDINATE") = MAX_COORDINATE;
    m.attr("ENERGY_NOISE") = ENERGY_NOISE;
    m.attr("MAX_WATER_RATIO") = MAX_WATER_RATIO;
    const char* slots[] = {"TIME", "NEXT_STEP", "LAST_STEP", "SPEED", "CALM_TIME", "UNCHECKED_TIME", "EXCHANGING",
                           "SLEEPING", "STEPS", "REJECTED", "FAILED_STEP", "NEWTON_RATE", "RATE_CORRECTION",
                           "FIRST_GUESS", "LAST_SOLVE", "LARGEST_ERROR"};
    static_assert(sizeof slots / sizeof slots[0] == CLOCK_SIZE, "a clock slot without its name");
    for (Index k = 0; k < CLOCK_SIZE; ++k) m.attr(slots[k]) = k;
    m.attr("EXPLICIT_EULER") = Index(EXPLICIT_EULER);
    m.attr("SYMPLECTIC_EULER") = Index(SYMPLECTIC_EULER);
    m.attr("IMPLICIT_EULER") = Index(IMPLICIT_EULER);
    m.attr("BDF2") = Index(BDF2);
    m.attr("STABILITY_SAFETY") = STABILITY_SAFETY;
    m.attr("CONTACT_COUNTERS") = CONTACT_COUNTERS;
    m.attr("WICK_SUBSTEP_FRACTION") = WICK_SUBSTEP_FRACTION;
}

}  // namespace wc::py
