// The step loop (stepping.hpp).
#include "wetcloth/stepping.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "wetcloth/absorption.hpp"
#include "wetcloth/assembly.hpp"
#include "wetcloth/collider_analytic_supports.hpp"
#include "wetcloth/collider_edges.hpp"
#include "wetcloth/collider_motion.hpp"
#include "wetcloth/collider_supports.hpp"
#include "wetcloth/colliders.hpp"
#include "wetcloth/energy.hpp"
#include "wetcloth/floor.hpp"
#include "wetcloth/grip.hpp"
#include "wetcloth/implicit.hpp"
#include "wetcloth/integration.hpp"
#include "wetcloth/self_contact.hpp"
#include "wetcloth/self_contact/broad_phase.hpp"
#include "wetcloth/self_contact/supports.hpp"
#include "wetcloth/sliding.hpp"

namespace wc {

namespace {

//: Python's min/max (the first argument wins ties and NaN comparisons the same way).
inline double pymin(double a, double b) { return b < a ? b : a; }
inline double pymax(double a, double b) { return b > a ? b : a; }

//: Height (m) below which a particle's centre touches water (its submerged fraction is positive).
double surface(const Physics& phys) { return phys.water_level + (phys.smooth ? 0.5 * phys.thickness : 0.0); }

bool absorbing(const Physics& phys) { return phys.absorption_capacity > 0.0 && phys.absorption_rate > 0.0; }

//: The exponent at which a step's error ratio fell from ratio_1 at step h_1 to ratio_2 at h_2 < h_1, within
//: LEAST_OBSERVED_ORDER and the scheme's order + 1 (its local error's).
double observed_order(double h_1, double ratio_1, double h_2, double ratio_2, int order) {
    const double exponent = ratio_2 > 0.0 && ratio_1 > ratio_2 ? std::log(ratio_1 / ratio_2) / std::log(h_1 / h_2) : 0.0;
    return std::clamp(exponent, LEAST_OBSERVED_ORDER, static_cast<double>(order + 1));
}

struct Trial {
    double error;  // m, local position error estimate
    int order;     // order of that estimate
    bool converged;
};

//: The integrator's step of h s from the current state into the trial buffers; the particle masses it
//: used are left in solver.mass.
Trial take_step(Core& core, double h, const GripMove& grip) {
    const Cloth& cloth = core.cloth;
    const Physics& phys = core.phys;
    Buffers& buf = core.buf;
    Solver& solver = core.solver;
    const Index n = cloth.n;
    if (core.control.integrator == EXPLICIT_EULER || core.control.integrator == SYMPLECTIC_EULER) {
        for (Index i = 0; i < n; ++i) solver.mass[i] = cloth.dry_mass[i] + buf.water[i];
        forces(cloth, phys, core.work, buf.pos, buf.vel, buf.water);
        const double largest = euler_update(n, buf.pos, buf.vel, core.work.force, cloth.dry_mass, buf.water,
                                            cloth.free, h, core.control.integrator == SYMPLECTIC_EULER,
                                            buf.trial_pos, buf.trial_vel);
        return {0.5 * h * largest, 1, true};  // |h (v+ - v)| / 2: first- against second-order update
    }
    // Backward Euler is BDF2's first step, without history, solved by descent: its steps never fail.
    const bool euler = core.control.integrator == IMPLICIT_EULER;
    double* clock = core.clock;
    const double h_prev = euler ? 0.0 : clock[LAST_STEP];
    double* step_water = buf.trial_water;
    copy(n, buf.water, step_water);
    if (absorbing(phys)) {
        double* predicted = solver.predicted;              // scratch: z
        double* predicted_speed = solver.predicted + n;    // and v_z
        const double w = h_prev > 0.0 ? h / h_prev : 0.0;
        const double* z = buf.pos + 2 * n;
        const double* vz = buf.vel + 2 * n;
        const double* z_prev = buf.prev_pos + 2 * n;
        const double* vz_prev = buf.prev_vel + 2 * n;
        for (Index i = 0; i < n; ++i) {
            predicted[i] = z[i] + h * vz[i] + w * w * (z_prev[i] - z[i] + h_prev * vz[i]);
            predicted_speed[i] = vz[i] + w * (vz[i] - vz_prev[i]);
        }
        uptake(n, z, predicted, vz, predicted_speed, surface(phys), cloth.dry_mass, phys.absorption_capacity,
               phys.absorption_rate, h, buf.water, step_water);
    }
    const NewtonMode mode = core.control.allowed > 0.0 ? NewtonMode::ADAPTIVE : NewtonMode::FIXED;
    const double base = euler ? DESCENT_CG_TOLERANCE : core.control.cg_tolerance;
    const double cg_tolerance = mode == NewtonMode::ADAPTIVE ? adaptive_cg_tolerance(base, core.control, h) : base;
    const StepEstimate step = bdf2_step(cloth, phys, core.work, solver, core.plane, buf.pos, buf.vel, buf.water,
                                        step_water, buf.prev_pos, buf.prev_vel, buf.prev_water, buf.acceleration, h,
                                        h_prev, core.control.newton_tolerance, cg_tolerance, mode, euler,
                                        clock + NEWTON_RATE,
                                        buf.trial_pos, buf.trial_vel, buf.held, grip.acts ? grip.rate : nullptr,
                                        core.reused);
    return {step.error, h_prev > 0.0 ? 2 : 1, step.converged};
}

//: Uptake where the cloth touches water, drying in air, wicking between neighbours; each skipped when its
//: rate is zero.  mass_used (kg) is what the step took as each particle's mass: the momentum it gave is
//: kept as the uptake changes that mass.  Returns whether any particle's water changed.
bool exchange_water(Core& core, const double* mass_used, double h) {
    const Cloth& cloth = core.cloth;
    const Physics& phys = core.phys;
    Buffers& buf = core.buf;
    const Index n = cloth.n;
    copy(n, buf.water, buf.trial_water);
    const bool absorbs = absorbing(phys);
    if (!(absorbs || phys.drying_rate > 0.0 || phys.wicking_rate > 0.0)) return false;
    const double level = surface(phys);
    Index exchanged = 0;
    const double* z_start = buf.pos + 2 * n;
    const double* z_end = buf.trial_pos + 2 * n;
    const double* vz_start = buf.vel + 2 * n;
    const double* vz_end = buf.trial_vel + 2 * n;
    if (absorbs) {
        exchanged += uptake(n, z_start, z_end, vz_start, vz_end, level, cloth.dry_mass, phys.absorption_capacity,
                            phys.absorption_rate, h, buf.water, buf.trial_water);
        keep_momentum(n, mass_used, cloth.dry_mass, buf.trial_water, buf.trial_vel);
    }
    if (phys.drying_rate > 0.0) {
        exchanged += dry(n, z_start, z_end, vz_start, vz_end, level, phys.drying_rate, h, buf.trial_water);
    }
    if (phys.wicking_rate > 0.0 && phys.absorption_capacity > 0.0) {
        const double substeps = std::max(1.0, std::ceil(h / (WICK_SUBSTEP_FRACTION * phys.wick_step_limit)));
        const double moved = wick(cloth, static_cast<Index>(substeps), h, buf.trial_water, buf.trial_vel,
                                  core.work.wick_buffer);
        for (Index c = 0; c < 3; ++c) {
            double* v = buf.trial_vel + c * n;
            for (Index i = 0; i < n; ++i) v[i] *= cloth.free[i];
        }
        exchanged += moved > 0.0;
    }
    return exchanged > 0;
}

//: Whether the water the cloth still takes up can only press it harder onto whatever holds it up, so that it
//: may sleep while it absorbs (docs/model.md section 7): the uptake is its only exchange (no wicking; drying
//: acts in air only), its stiffness does not depend on it, and every particle lies wholly under water (its
//: buoyancy then no longer depends on its height) and weighs more than the water it displaces.
bool sunk(const Core& core) {
    const Cloth& cloth = core.cloth;
    const Physics& phys = core.phys;
    if (phys.wicking_rate > 0.0 || phys.wet_factor != 0.0) return false;
    const Index n = cloth.n;
    const double* z = core.buf.pos + 2 * n;
    const double* water = core.buf.water;
    for (Index i = 0; i < n; ++i) {
        const bool under = phys.smooth ? z[i] <= phys.water_level - 0.5 * phys.thickness : z[i] < phys.water_level;
        if (!under || !(cloth.dry_mass[i] + water[i] > phys.water_density * cloth.volume[i])) return false;
    }
    return true;
}

//: Whether the fixed-step mode checks a step from pos to trial_pos for energy it made (docs/model.md section 7):
//: always but where, with the thesis's buoyancy, a particle is at or under the water's surface at either end (a step
//: at the surface: Newton has no slope to converge on there, and its steps gained energy at every halving, 55 steps
//: taken again a frame).
bool energy_checked(const Core& core) {
    const Physics& phys = core.phys;
    if (phys.smooth) return true;
    const Index n = core.cloth.n;
    const double* z0 = core.buf.pos + 2 * n;
    const double* z1 = core.buf.trial_pos + 2 * n;
    const double wet = surface(phys) + 0.5 * phys.thickness;  // (above it, a particle has no water)
    for (Index i = 0; i < n; ++i) {
        if (!(z0[i] > wet && z1[i] > wet)) return false;
    }
    return true;
}

//: The energy a step may not add (J): mechanical (energy.hpp's, with the step's water) and buoyancy's potential,
//: at pos, vel; and the sum of its terms' magnitudes into `magnitude` (J).
double checked_energy(const Core& core, const double* pos, const double* vel, double& magnitude) {
    const double buoyancy = buoyancy_energy(core.cloth, core.phys, pos);  // (its terms are >= 0)
    const double mechanical =
        mechanical_energy(core.cloth, core.phys.wet_factor, core.solver.mass, core.buf.trial_water, pos, vel, &magnitude);
    magnitude += buoyancy;
    return mechanical + buoyancy;
}

//: The particles a keyed collider that moves over the step may have acted on in the solve, 1 in (n) where so:
//: those held on it (or on a mesh collider's edges), sliding on it or in one of its support terms.  Read before
//: release_all (buf.held).
std::vector<double> on_moving_colliders(const Core& core) {
    const Physics& phys = core.phys;
    const Index n = core.cloth.n;
    std::vector<double> marks(static_cast<std::size_t>(n), 0.0);
    for (Index i = 0; i < n; ++i) {
        const double held = core.buf.held[i];
        const bool on_moving = held >= collider_held(0)
            ? collider_moving(phys, static_cast<Index>(held - collider_held(0)))
            : held == EDGE_HELD;  // (which mesh holds it is not kept)
        if (on_moving) marks[static_cast<std::size_t>(i)] = 1.0;
    }
    if (const Sliding* sliding = core.solver.sliding) {
        for (std::size_t s = 0; s < sliding->index.size(); ++s) {
            if (collider_moving(phys, sliding->collider[s])) marks[static_cast<std::size_t>(sliding->index[s])] = 1.0;
        }
    }
    if (const Supports* supports = core.solver.supports) {
        for (Index t = 0; t < supports->count(); ++t) {
            if (!collider_moving(phys, supports->collider[static_cast<std::size_t>(t)])) continue;
            for (int j = 0; j < SUPPORT_POINTS; ++j) {
                const Index i = supports->points[static_cast<std::size_t>(SUPPORT_POINTS * t + j)];
                if (i >= 0) marks[static_cast<std::size_t>(i)] = 1.0;
            }
        }
    }
    return marks;
}

//: How the energy check weighs a fixed step over which keyed colliders move (docs/model.md section 7).  Where those
//: that may reach the cloth (colliders_near) all move at one velocity without turning (`in_frame`), it weighs the
//: step in the frame moving at that velocity (`frame`, m/s; zero where none may reach it), where they stand still
//: (if that frame rises or sinks, only while the cloth is out of the water).  Else in the world's frame, with
//: their work: acted_on (n) marks the particles they acted on in the solve (on_moving_colliders), solved (6 n)
//: holds the step's end as the solve left it (positions, then velocities), and contact (J) bounds the work of what
//: contact did to that end before self-collision (contact_work).
struct MovingColliders {
    bool in_frame = false;
    double frame[3] = {0.0, 0.0, 0.0};
    std::vector<double> acted_on, solved;
    double contact = 0.0;
};

//: Whether a frame's velocity `frame` (3, m/s) is zero: the world's frame.
bool at_rest(const double* frame) { return frame[0] == 0.0 && frame[1] == 0.0 && frame[2] == 0.0; }

//: The most work (J) what drives the cloth may have done on it over a backward Euler step of h s from pos, vel to
//: end_pos, end_vel (with end_pos = pos + h end_vel), from that end, seen from a frame moving at `frame` (3, m/s)
//: (docs/model.md section 7): the flowing fluids' h fluid_drive there; over the particles held to a path (pinned
//: ones, which the grip or the frame moves, and those marked in `acted_on` (n, or empty), on which a moving keyed
//: collider acted in the solve) the work h R . (v+ - frame) of R = m (v+ - v) / h - F(x+, v+), the force that kept
//: them there; and h frame_z g M, the gravity the frame rises against (M the cloth's mass).  A solved step of a
//: cloth whose forces are conservative with a convex energy (gravity, tension-only springs, smooth buoyancy),
//: dissipative (damping) or drag ends at most this much above its start.  0 where nothing drives it.  work.force
//: is its scratch.
double drivers_work(Core& core, double h, const double* end_pos, const double* end_vel,
                    const std::vector<double>& acted_on, const double* frame) {
    const Cloth& cloth = core.cloth;
    const Physics& phys = core.phys;
    const Buffers& buf = core.buf;
    const Index n = cloth.n;
    const double* mass = core.solver.mass;
    double work = h * fluid_drive(cloth, phys, core.work, end_pos, end_vel, frame);
    const bool framed = !at_rest(frame);
    if (frame[2] != 0.0) work += h * frame[2] * GRAVITY * total(n, mass);
    std::vector<char> on_path(static_cast<std::size_t>(n), 0);  // held to a path
    bool any = false;
    for (Index i = 0; i < n; ++i) {
        bool moved = framed;  // a pinned particle the grip or the frame moves
        for (Index c = 0; c < 3; ++c) moved |= end_vel[c * n + i] != 0.0;
        const bool on_collider = !acted_on.empty() && acted_on[static_cast<std::size_t>(i)] != 0.0;
        on_path[static_cast<std::size_t>(i)] = (cloth.free[i] == 0.0 && moved) || on_collider;
        any |= on_path[static_cast<std::size_t>(i)] != 0;
    }
    if (!any) return work;
    forces(cloth, phys, core.work, end_pos, end_vel, buf.trial_water);
    for (Index c = 0; c < 3; ++c) {
        for (Index i = 0; i < n; ++i) {
            if (!on_path[static_cast<std::size_t>(i)]) continue;
            const Index k = c * n + i;
            work += (mass[i] * (end_vel[k] - buf.vel[k]) - h * core.work.force[k]) * (end_vel[k] - frame[c]);
        }
    }
    return work;
}

//: The most work (J) contact did on the cloth from the step's end as solved (solved: positions, then velocities,
//: (6 n)) to trial_pos, trial_vel (docs/model.md section 7): sum m u . (v2 - v0) over the particles within the
//: cloth's thickness of a collider that moves, u its surface's velocity there, v0 and v2 the particle's velocity
//: before and after.  Contact is inelastic relative to the surface and its friction opposes the slip, so relative
//: to the surface it only takes kinetic energy, m |v2 - u|^2 <= m |v0 - u|^2: the kinetic energy then rises by at
//: most m u . (v2 - v0).  Nothing is allowed for the floor, a still collider, or positions moved (a push that
//: stretches the springs makes energy).
double contact_work(const Core& core, const std::vector<double>& solved) {
    const Physics& phys = core.phys;
    const Index n = core.cloth.n;
    const double* pos = core.buf.trial_pos;
    const double* vel = core.buf.trial_vel;
    const double* before = solved.data() + 3 * n;
    double work = 0.0;
    for (Index i = 0; i < n; ++i) {
        const double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
        double nearest = phys.thickness, u[3] = {0.0, 0.0, 0.0}, normal[3];
        for (Index k = 0; k < phys.collider_count; ++k) {
            if (!collider_moving(phys, k)) continue;
            const double distance = collider_distance(phys, k, p, phys.thickness, normal);
            if (distance <= nearest) {
                nearest = distance;
                surface_velocity(phys, k, p, u);
            }
        }
        for (Index c = 0; c < 3; ++c) work += core.solver.mass[i] * u[c] * (vel[c * n + i] - before[c * n + i]);
    }
    return work;
}

//: Whether no particle is in the water at the step's start or end (pos, trial_pos): a frame that rises or sinks would
//: see the water's surface move, and buoyancy do work.
bool dry(Core& core) {
    const Index n = core.cloth.n;
    return submerged(core.phys, n, core.buf.pos + 2 * n, core.work.submerged) == 0.0 &&
           submerged(core.phys, n, core.buf.trial_pos + 2 * n, core.work.submerged) == 0.0;
}

//: checked_energy at pos and the velocities vel (3, n) less `frame` (3, m/s): seen from a frame moving at it.
double checked_energy_in(const Core& core, const double* pos, const double* vel, const double* frame,
                         double& magnitude) {
    if (at_rest(frame)) return checked_energy(core, pos, vel, magnitude);
    const Index n = core.cloth.n;
    std::vector<double> relative(vel, vel + 3 * n);
    for (Index c = 0; c < 3; ++c) {
        for (Index i = 0; i < n; ++i) relative[static_cast<std::size_t>(c * n + i)] -= frame[c];
    }
    return checked_energy(core, pos, relative.data(), magnitude);
}

//: Whether a step of h s from pos, vel to trial_pos, trial_vel gained energy beyond what drives the cloth and beyond
//: noise (ENERGY_NOISE).  What drives it: drivers_work at the step's end; where keyed colliders moved over it
//: (`moving`, else null), both seen from their frame, or drivers_work at its end as solved and what contact did
//: after the solve (contact_work).
bool gained_energy(Core& core, double h, const MovingColliders* moving) {
    const double still[3] = {0.0, 0.0, 0.0};
    const bool in_frame = moving != nullptr && moving->in_frame && (moving->frame[2] == 0.0 || dry(core));
    const double* frame = in_frame ? moving->frame : still;
    double start_size = 0.0, end_size = 0.0;
    const double start = checked_energy_in(core, core.buf.pos, core.buf.vel, frame, start_size);
    const double end = checked_energy_in(core, core.buf.trial_pos, core.buf.trial_vel, frame, end_size);
    const Index n = core.cloth.n;
    const double drive = moving == nullptr || in_frame
        ? drivers_work(core, h, core.buf.trial_pos, core.buf.trial_vel, {}, frame)
        : drivers_work(core, h, moving->solved.data(), moving->solved.data() + 3 * n, moving->acted_on, still) +
              moving->contact;
    return end - start - drive > ENERGY_NOISE * (start_size + end_size);
}

//: Fall asleep after sleep_after s still, with no water exchange and no grip moving (`exchanging`:
//: either, in this step; velocities then zero).  Stillness is checked every sleep_after / 20 s of
//: simulated time, not at every step.
void maybe_sleep(Core& core, double h, bool exchanging) {
    if (!core.phys.skip_idle) return;
    double* clock = core.clock;
    const Control& control = core.control;
    Buffers& buf = core.buf;
    const Index n = core.cloth.n;
    if (exchanging) clock[EXCHANGING] = 1.0;
    clock[UNCHECKED_TIME] += h;
    if (clock[UNCHECKED_TIME] < control.sleep_after / 20) return;
    if (clock[EXCHANGING] != 0.0 || largest_deviation(n, buf.pos, buf.anchor) > control.sleep_distance) {
        copy(3 * n, buf.pos, buf.anchor);
        clock[CALM_TIME] = 0.0;
    } else {
        clock[CALM_TIME] += clock[UNCHECKED_TIME];
    }
    clock[UNCHECKED_TIME] = 0.0;
    clock[EXCHANGING] = 0.0;
    if (clock[CALM_TIME] >= control.sleep_after) {
        clock[SLEEPING] = 1.0;
        std::fill(buf.vel, buf.vel + 3 * n, 0.0);
        clock[SPEED] = 0.0;
        clock[LAST_STEP] = 0.0;  // the velocities changed: BDF2 starts afresh
    }
}

//: collider_edge_contact over the step from x0 to x1 (velocities v1), the particles held during the step
//: (at rest on their support) not moved by still meshes (a moving one may come onto them).
int collider_edges(Core& core, const double* x0, double* x1, double* v1) {
    if (core.phys.meshes.count == 0 || core.contact.lists == nullptr) return UNTOUCHED;
    return collider_edge_contact(core.contact, *core.contact.lists, core.phys, core.cloth.n, core.solver.mass,
                                 core.contact.lists->collider_free.data(), core.cloth.free, x0, x1, v1);
}

//: Marks in pushed (n) the particles whose end of step (pos, vel: (3, n)) self-collision's pushes changed
//: from (before_pos, before_vel), 1 where changed, else 0.  Returns how many.
Index mark_pushed(Index n, const double* before_pos, const double* before_vel, const double* pos, const double* vel,
                  double* pushed) {
    Index count = 0;
    for (Index i = 0; i < n; ++i) {
        bool changed = false;
        for (Index c = 0; c < 3; ++c) {
            const Index k = c * n + i;
            changed = changed || pos[k] != before_pos[k] || vel[k] != before_vel[k];
        }
        pushed[i] = changed ? 1.0 : 0.0;
        count += changed;
    }
    return count;
}

//: The history (prev_pos, prev_vel) of the particles marked in pushed (n), h s before their pushed state
//: (pos, vel): a past of constant acceleration (the step's, m/s2) through it, so that BDF2's next step
//: continues their motion from where the push left them to second order, and its error estimate sees how
//: far their forces there depart from it.  The other particles keep their own history.
void carry_pushed_history(Index n, const double* pushed, const double* pos, const double* vel,
                          const double* acceleration, double h, double* prev_pos, double* prev_vel) {
    for (Index c = 0; c < 3; ++c) {
        for (Index i = 0; i < n; ++i) {
            if (pushed[i] == 0.0) continue;
            const Index k = c * n + i;
            prev_vel[k] = vel[k] - h * acceleration[k];
            prev_pos[k] = pos[k] - h * vel[k] + 0.5 * h * h * acceleration[k];
        }
    }
}

//: Note for self-collision's stage the colliders the cloth lies on through the step (ContactLists::supported_normal,
//: from the particles held on colliders and sliding on them, before their holds are released), if it lies `on` any:
//: the stage's pushes do not take those particles into them.
void note_collider_supports(Core& core, bool on) {
    if (!core.contact.enabled || core.contact.lists == nullptr) return;
    const Index n = core.cloth.n;
    std::vector<double>& normals = core.contact.lists->supported_normal;
    normals.assign(on ? 3 * static_cast<std::size_t>(n) : 0, 0.0);
    if (on && supported_normals(n, core.phys, core.buf.pos, core.buf.held, core.solver.sliding, normals.data()) == 0) {
        normals.clear();
    }
}

//: Take one accepted step of at most `span` s, `remaining` s before the end of the interval being advanced
//: (span is shorter when a collider's key comes first); `retried`: a fixed step taken again in halves (for
//: self-collision's impact zones or energy gained).  Returns DONE or BLOWN_UP.
Status step(Core& core, double remaining, double span, bool retried = false) {
    Cloth& cloth = core.cloth;
    const Physics& phys = core.phys;
    const Control& control = core.control;
    Buffers& buf = core.buf;
    double* clock = core.clock;
    const Index n = cloth.n;
    const bool adaptive = control.allowed > 0.0;
    const bool implicit = control.integrator == BDF2 || control.integrator == IMPLICIT_EULER;
    start_collider_motion(phys, clock[TIME]);
    // The fixed-step mode's energy check weighs a step over which keyed colliders move in their frame or with
    // their work (MovingColliders); for their work it keeps what they did.
    const bool weighs_colliders = !adaptive && control.integrator == IMPLICIT_EULER && colliders_move(phys);
    MovingColliders moving;
    if (weighs_colliders) {  // (those that cannot reach the cloth in the step do no work on it)
        moving.in_frame = common_frame(phys, colliders_near(phys, n, buf.pos, clock[SPEED], control.max_step),
                                       moving.frame);
    }
    const bool weighs_work = weighs_colliders && !(moving.in_frame && moving.frame[2] == 0.0);
    // Layers lying on layers where the cloth starts (a mesh folded in its file, a state set or restored without
    // a list) are seen from the first step: without a candidate list the stage builds one only after the step's
    // solve, which then had no layers' supports or holds (at frame steps a sheet lying on another slid through
    // its first frame as if frictionless: bench/layer_friction.py).
    if (core.contact.enabled && core.contact.lists != nullptr && core.contact.margin != nullptr &&
        core.contact.margin[0] == 0.0) {
        self_contact::rebuild_for_step(core.contact, n, phys.thickness, buf.pos, buf.pos);
    }
    // Particles at rest on the floor take no part in the step (a constraint of its solve) unless its forces
    // would move them; the model's free flags are theirs again before the step ends.
    const double touch_slack = implicit && !adaptive ? FRAME_TOUCH_SLACK * 0.5 * phys.thickness : 0.0;  // m
    Index held = hold_resting(n, phys.floor_z, buf.pos, buf.vel, cloth.free, buf.held);
    const Index held_on_colliders = hold_on_colliders(n, phys, buf.pos, buf.vel, cloth.free, buf.held,
                                                          clock[LAST_STEP], touch_slack);
    held += held_on_colliders;
    const Index held_on_edges = core.contact.lists != nullptr ? hold_on_collider_edges(core.contact, *core.contact.lists,
                                                                                       phys, n, buf.pos, buf.vel,
                                                                                       cloth.free, buf.held)
                                                              : 0;
    held += held_on_edges;
    const Index on_layers = hold_on_layers(core.contact, phys.thickness, n, buf.pos, buf.vel, cloth.free, buf.held);
    // At fixed steps those the forces in hand would slip on a still collider with friction slide on it from the
    // step's start (in
    // the sliding set below, friction a force of the solve): held through the step, a slip made at its end moves
    // each particle as if alone against its springs, and a sheet set at rest on a slope steeper than its friction
    // lost its first frame's slide (tests/test_colliders.py).  (On a moving collider add_released takes only those
    // exactly at its surface's velocity, a test the rounding of its motion decides: a box and its mesh under a sheet
    // parted by 1.5 um, tests/test_turning_colliders.py; they, and those on a frictionless one, slip at the step's
    // end, as before.)
    const bool slips_checked = implicit && !adaptive && held_on_colliders > 0;
    if (on_layers > 0 || slips_checked) forces(cloth, phys, core.work, buf.pos, buf.vel, buf.water);
    if (on_layers > 0) {  // whom the forces in hand would slide off their layer go free at once
        const Index slid = release_sliding(core.contact, n, core.work.force, cloth.free, buf.held);
        held += on_layers - slid;
        // and any of them another still element holds within friction is held on that one
        if (slid > 0) {
            held += hold_within_friction(core.contact, phys.thickness, n, buf.pos, buf.vel, core.work.force,
                                         cloth.free, buf.held);
        }
    }
    // Particles sliding on the floor or a collider stay on it through an implicit step, friction a force of it.
    if (implicit) gather_sliding(n, phys, buf.pos, buf.vel, cloth.free, core.sliding, touch_slack);
    if (slips_checked) {
        const Index slipping = release_from_colliders(n, phys, buf.pos, core.work.force, core.solver.mass, cloth.free,
                                                      buf.held, 1.0, true);
        held -= slipping;
        if (slipping > 0) add_released(n, phys, buf.pos, buf.vel, cloth.free, core.work.force, core.sliding, touch_slack);
    }
    const bool sliding = implicit && core.sliding.count() > 0;
    core.sliding.smoothed = !adaptive;
    core.solver.sliding = sliding ? &core.sliding : nullptr;
    core.solver.near_itself = core.contact.enabled && core.contact.lists != nullptr &&
                              self_contact::candidate_count(core.contact) > 0;
    // A moving mesh's vertices and edges near the cloth's triangles and edges: supports its solve sees; at
    // fixed steps a still mesh's too (its frame-long moves at a bucket's rim the edges' pass cannot show safe).
    const bool meshes_support = implicit && core.contact.lists != nullptr &&
                                (phys.collider_motion != nullptr || !adaptive) &&
                                gather_supports(core.contact, *core.contact.lists, phys, n, buf.pos, buf.vel,
                                                (SUPPORT_DISTANCE + 1.0) * 0.5 * phys.thickness,
                                                adaptive ? 0.0 : control.max_step, core.supports) > 0;
    // At fixed steps the analytic colliders and the floor too: the free particles a frame-long step may carry
    // onto one (again whenever particles leave the sliding set: those that lift off their surface fell through it
    // unsupported, and the tablecloth's springs were stretched by 38 % at 1/24 s steps).
    const bool analytic = implicit && !adaptive;
    const Index mesh_terms = meshes_support ? core.supports.count() : 0;
    // And the cloth's pairs with itself near at the step's start (self_contact/supports.hpp).
    const bool self_supports = analytic && core.solver.near_itself;
    const double support_distance = SUPPORT_DISTANCE * 0.5 * phys.thickness;  // m: where the penalties start
    const auto support = [&]() {
        bool any = mesh_terms > 0;
        if (analytic) {
            any = gather_analytic_supports(phys, n, buf.pos, buf.vel, cloth.free, core.solver.sliding,
                                           support_distance, control.max_step, mesh_terms, core.supports) > 0;
        }
        if (self_supports) {
            any = self_contact::gather_self_supports(core.contact, n, buf.pos, buf.vel, phys.thickness,
                                                     support_distance, control.max_step, core.supports) > 0;
        }
        if (any) {
            const double stiffest = stiffest_spring(cloth);
            core.supports.distance = support_distance;
            core.supports.stiffness = SUPPORT_STIFFNESS * stiffest;
            core.supports.self_stiffness = self_contact::SELF_SUPPORT_STIFFNESS * stiffest;
        }
        core.solver.supports = any ? &core.supports : nullptr;
    };
    support();
    // Slips and lift-offs made at the step's end move a particle at most this far (m); farther, the step is
    // taken again with it free.  Adaptive steps allow their error; fixed implicit steps, which have none to
    // allow, the contact's reach (taken again for every slip, the frame-long steps of a cloth draping over a
    // table went round 7 times each, and the cloth fell through the table); fixed explicit ones, none.
    const double end_move_limit = adaptive ? control.allowed : implicit ? 0.5 * phys.thickness : 0.0;
    double h = 0.0;
    Trial trial{};
    GripMove grip;
    int rejections = 0;  // by the controller (the floor's releases are bounded by the particles held)
    // The last try rejected for its error, at this step's start, with nothing changed since (no release or
    // lift-off): its step (s; 0 if none) and error ratio, to measure the order at which the error falls.
    double rejected_h = 0.0, rejected_ratio = 0.0;
    while (true) {
        if (rejections > MAX_REJECTIONS) {  // no step it accepts: a state it cannot go on from
            if (held > 0) release_all(n, cloth.free, buf.held);
            clock[FAILED_STEP] = h;
            return BLOWN_UP;
        }
        double planned = adaptive ? pymin(pymin(clock[NEXT_STEP], control.max_step), stable_step(control, clock[SPEED]))
                                  : pymin(clock[NEXT_STEP], control.max_step);  // fixed steps, as the user asked
        if (control.integrator == BDF2 && clock[LAST_STEP] > 0.0) {
            planned = pymin(planned, control.growth * clock[LAST_STEP]);  // zero-stable for ratios < 2.4
        }
        if (phys.collider_motion != nullptr) planned = pymin(planned, collider_step_limit(phys));
        // Equal steps to the end of the interval (or a collider's key) rather than a last sliver.
        h = span / pymax(1.0, std::ceil(span / planned - STEP_COUNT_SLACK));
        grip = grip_move(n, phys, cloth.free, buf.held, buf.pos, clock[TIME], h, remaining);
        trial = take_step(core, h, grip);
        if (weighs_work) {
            moving.solved.assign(buf.trial_pos, buf.trial_pos + 3 * n);
            moving.solved.insert(moving.solved.end(), buf.trial_vel, buf.trial_vel + 3 * n);
        }
        carry_held(n, phys, buf.held, buf.pos, h, buf.trial_pos, buf.trial_vel);  // on moving colliders
        if (core.solver.sliding != nullptr && trial.converged) {
            // Those the step's force lifts off their surface move off it at the step's end if that moves
            // none farther than end_move_limit (as slips do); else the step is taken again without them.
            const double lifted = lift_off(core.sliding, n, phys, core.work.force, core.solver.mass,
                                           core.work.diagonal_blocks, core.work.blocks, h, end_move_limit,
                                           buf.trial_pos, buf.trial_vel);
            if (lifted < 0.0) {
                drop_lifting(core.sliding, n, core.solver.mass, core.work.force);
                if (core.sliding.count() == 0) core.solver.sliding = nullptr;
                if (analytic) support();
                clock[REJECTED] += 1;
                rejected_h = 0.0;
                continue;
            }
            trial.error = pymax(trial.error, lifted);
        }
        if (held > 0 && trial.converged) {
            // Slips on the floor, a collider or a mesh collider's edges that move no particle farther than the
            // step's allowed error need no second try: they are made now (most are: a draping cloth releases a
            // few every step).  Layers' releases, longer slips and lift-offs from edges take the step again.
            Index released = release_unsupported(core.contact, n, cloth.free, buf.held);
            const double* diagonal_blocks = implicit ? core.work.diagonal_blocks : nullptr;
            double slipped = released == 0 && end_move_limit > 0.0
                ? slip_on_supports(n, phys, core.work.force, core.solver.mass, diagonal_blocks, core.work.blocks, h,
                                   end_move_limit, buf.held, buf.pos, buf.trial_pos, buf.trial_vel)
                : -1.0;
            if (slipped >= 0.0 && held_on_edges > 0) {
                const double on_edges = slip_on_collider_edges(*core.contact.lists, n, core.work.force, core.solver.mass,
                                                               diagonal_blocks, core.work.blocks, h, end_move_limit,
                                                               cloth.free, buf.held, buf.trial_pos, buf.trial_vel);
                slipped = on_edges >= 0.0 ? pymax(slipped, on_edges) : -1.0;
            }
            if (slipped >= 0.0) {
                trial.error = pymax(trial.error, slipped);
            } else {
                released += release_slipping(n, phys.floor_friction, core.work.force, cloth.free, buf.held) +
                            (held_on_colliders > 0
                                 ? release_from_colliders(n, phys, buf.pos, core.work.force, core.solver.mass, cloth.free, buf.held)
                                 : 0) +
                            (held_on_edges > 0 ? release_from_collider_edges(*core.contact.lists, n, core.work.force,
                                                                              cloth.free, buf.held)
                                               : 0);
            }
            if (released > 0) {  // redo the step with them free, and with them those near slipping too
                held -= released + release_slipping(n, RELEASE_ROUND_CONE * phys.floor_friction, core.work.force,
                                                    cloth.free, buf.held);
                if (held_on_colliders > 0) {
                    held -= release_from_colliders(n, phys, buf.pos, core.work.force, core.solver.mass, cloth.free, buf.held,
                                                   RELEASE_ROUND_CONE);
                }
                if (held_on_edges > 0) {
                    held -= release_from_collider_edges(*core.contact.lists, n, core.work.force, cloth.free, buf.held,
                                                        RELEASE_ROUND_CONE);
                }
                // Those released on the floor or a collider slide on it in the step taken again.
                if (implicit && add_released(n, phys, buf.pos, buf.vel, cloth.free, core.work.force, core.sliding,
                                             touch_slack) > 0) {
                    core.solver.sliding = &core.sliding;
                }
                clock[REJECTED] += 1;
                rejected_h = 0.0;
                continue;
            }
        }
        if (!trial.converged && h > control.smallest_step) {
            clock[NEXT_STEP] = pymax(control.smallest_step, 0.25 * h);
            clock[REJECTED] += 1;
            ++rejections;
            rejected_h = 0.0;
            continue;
        }
        if (!adaptive) {  // the blow-up guard watches
            // A step taken again in halves passes its size on; one taken whole doubles it, up to max_step.
            // Tried whole first every time, a flag bunched at its pole took 1880 steps again in 1.5 s instead
            // of 240 (bench/violent_frames.py).  Not after a failed solve (a quarter step): BDF2's frame steps
            // of the hanging sheet then took 221 steps and 60 again instead of 184 and 32.
            clock[NEXT_STEP] = retried ? planned : pymin(control.max_step, 2.0 * planned);
            break;
        }
        // Error relative to what is allowed: the position error, and the uptake's (a fraction of the wet
        // mass, held to the tolerance), whichever is larger, with its order.
        double ratio = trial.error / control.allowed;
        int order = trial.order;
        if (absorbing(phys)) {
            const double water_error = uptake_timing_error(
                n, buf.pos + 2 * n, buf.trial_pos + 2 * n, buf.vel + 2 * n, buf.trial_vel + 2 * n, surface(phys),
                cloth.dry_mass, phys.absorption_capacity, phys.absorption_rate, h, buf.water);
            const double water_ratio =
                water_error / (control.tolerance * (total(n, cloth.dry_mass) + total(n, buf.water)));
            if (water_ratio > ratio) {
                ratio = water_ratio;
                order = 1;
            }
        }
        const bool finite = std::isfinite(ratio);
        double factor = ratio > 0.0 ? STEP_SAFETY * std::pow(ratio, -1.0 / (order + 1)) : control.growth;
        if (ratio <= 1.0 || h <= control.smallest_step || !finite) {
            const double proposed = finite ? h * pymin(control.growth, pymax(control.shrink, factor)) : h;
            // A step cut short by the end of the interval says nothing against the planned one.
            clock[NEXT_STEP] = (h < planned && ratio <= 1.0) ? pymax(proposed, planned) : proposed;
            break;
        }
        // Rejected again: the error fell from the last try's more slowly than the order says (right after the
        // particles held on a collider changed, or an input jumped, the motion is not smooth on the step's scale:
        // a draping towel's errors fell as h^1.3-1.7), so the cut follows the order observed between the two.
        if (finite && rejected_h > h) {
            factor = STEP_SAFETY * std::pow(ratio, -1.0 / observed_order(rejected_h, rejected_ratio, h, ratio, order));
        }
        rejected_h = h;
        rejected_ratio = ratio;
        clock[NEXT_STEP] = pymax(control.smallest_step, h * pymax(control.shrink, factor));
        clock[REJECTED] += 1;
        ++rejections;
    }
    if (phys.meshes.count > 0 && core.contact.lists != nullptr) {
        core.contact.lists->collider_free.assign(cloth.free, cloth.free + n);
    }
    if (weighs_work) moving.acted_on = on_moving_colliders(core);
    note_collider_supports(core, held_on_colliders > 0 || (core.solver.sliding != nullptr && phys.collider_count > 0));
    if (held > 0) release_all(n, cloth.free, buf.held);
    if (std::isfinite(trial.error)) clock[LARGEST_ERROR] = pymax(clock[LARGEST_ERROR], trial.error);
    if (!(h > 0.0 && clock[TIME] + h > clock[TIME])) {  // a step that would not advance the time
        clock[FAILED_STEP] = h;
        return BLOWN_UP;
    }
    end_collider_motion(phys, clock[TIME] + h);  // the colliders where the step ends
    place_grip(n, phys, grip, cloth.free, buf.held, buf.trial_pos, buf.trial_vel);
    const bool on_floor = floor_contact(n, phys.floor_z, phys.floor_friction, buf.trial_pos, buf.trial_vel) > 0 ||
                          held > 0 || core.solver.sliding != nullptr;
    double kick = 0.0;  // m/s: the largest change of a velocity along a moving collider's surface
    bool on_collider = (phys.collider_count > 0 &&
                        collider_contact(n, phys, buf.pos, buf.trial_pos, buf.trial_vel, &kick) > 0) ||
                       held_on_colliders > 0 || (core.solver.sliding != nullptr && phys.collider_count > 0);
    // The cloth's edges and triangles against mesh colliders' edges and vertices, before self-collision and
    // again after it if it moved the cloth.
    int edged = collider_edges(core, buf.pos, buf.trial_pos, buf.trial_vel);
    if (weighs_work) moving.contact = contact_work(core, moving.solved);
    // Self-collision's pushes: with BDF2 the pushed particles' history is carried through their pushed state
    // (carry_pushed_history); a step whose motion it froze, or that mesh colliders' edges changed, restarts it.
    const bool carries = control.integrator == BDF2 && core.contact.enabled;
    double* unpushed_pos = core.solver.p;  // scratch (the linear solves' directions, free between steps)
    double* unpushed_vel = core.solver.ap;
    double* pushed = core.solver.z;
    const Index freezes = core.contact.enabled ? core.contact.counters[FREEZES] : 0;
    const Index zone_rounds = core.contact.enabled ? core.contact.counters[ZONE_ROUNDS] : 0;
    if (carries) {
        copy(3 * n, buf.trial_pos, unpushed_pos);
        copy(3 * n, buf.trial_vel, unpushed_vel);
    }
    core.contact.layers_solved = self_supports;  // the solve held the layers: the stage leaves what it balanced
    bool kinked = resolve(core.contact, phys.thickness, phys.floor_z, control.blow_up_speed, n, core.solver.mass,
                          cloth.free, buf.pos, buf.trial_pos, buf.trial_vel, h);
    // A fixed step whose self-collision needed rigid impact zones or undid its motion (a frame-long step's
    // folds meeting: the zones' rigid motion stretched the springs at their edges by up to 139 %), down to
    // SUBSTEP_LEAST of max_step, or that gained energy, down to GAIN_SUBSTEP_LEAST, is taken again in halves.  In
    // the fixed-step mode nothing may add to the cloth's energy beyond the work of what drives it, but a solve
    // stopped short of converging (what its unsolved residual does: a sheet swinging onto the floor, a towel whose
    // grip stops) and self-collision's pushes after it (a sheet hung by a corner folding onto itself) may
    // (bench/frame_step_energy.py, bench/self_contact_energy.py, tests/test_driven_energy.py).
    const bool zoned = !adaptive && h > SUBSTEP_LEAST * control.max_step && core.contact.enabled &&
                       (core.contact.counters[ZONE_ROUNDS] > zone_rounds || core.contact.counters[FREEZES] > freezes);
    const bool gained = !adaptive && h > GAIN_SUBSTEP_LEAST * control.max_step && !zoned &&
                        control.integrator == IMPLICIT_EULER && energy_checked(core) &&
                        gained_energy(core, h, weighs_colliders ? &moving : nullptr);
    if (zoned || gained) {
        start_collider_motion(phys, clock[TIME]);
        clock[NEXT_STEP] = 0.5 * h;
        clock[REJECTED] += 1;
        return step(core, remaining, span, true);
    }
    const bool carried = kinked && carries && core.contact.counters[FREEZES] == freezes &&
                         mark_pushed(n, unpushed_pos, unpushed_vel, buf.trial_pos, buf.trial_vel, pushed) > 0;
    if (kinked) {  // self-collision's pushes do not see the colliders: those it pushed into one go back out
        edged |= collider_edges(core, buf.pos, buf.trial_pos, buf.trial_vel);
        if (phys.collider_count > 0 && collider_contact(n, phys, buf.pos, buf.trial_pos, buf.trial_vel, &kick) > 0) {
            on_collider = true;
        }
    }
    // A moving collider's friction that changed a velocity along it by more than the step's allowed error
    // in a step breaks the history BDF2 extrapolates: BDF2 starts afresh (a sheet on a box accelerating at
    // 2 mu g under it then slides mu g t^2 / 2 within 0.0003 %, 0.2 % without).
    kinked = (kinked && !carried) || (edged & STOPPED) != 0 || kick * h > control.allowed;
    const bool exchanging = exchange_water(core, core.solver.mass, h);
    place_grip(n, phys, grip, cloth.free, buf.held, nullptr, buf.trial_vel);  // (the uptake rescaled velocities)
    const SpeedCheck check = speed_and_finiteness(n, buf.trial_pos, buf.trial_vel, buf.trial_water);
    if (!(check.finite && check.speed < control.blow_up_speed)) {
        clock[FAILED_STEP] = h;
        return BLOWN_UP;
    }
    clock[SPEED] = check.speed;
    copy(3 * n, buf.pos, buf.prev_pos);
    copy(3 * n, buf.vel, buf.prev_vel);
    copy(n, buf.water, buf.prev_water);
    copy(3 * n, buf.trial_pos, buf.pos);
    copy(3 * n, buf.trial_vel, buf.vel);
    copy(n, buf.trial_water, buf.water);
    if (control.integrator == BDF2) copy(3 * n, core.solver.step_acceleration, buf.acceleration);
    if (carried) carry_pushed_history(n, pushed, buf.pos, buf.vel, buf.acceleration, h, buf.prev_pos, buf.prev_vel);
    if (on_floor) agree_history(n, phys.floor_z, buf.pos, buf.vel, buf.prev_pos, buf.prev_vel, h);
    if (on_collider) {  // (those that slid along a curved collider keep their own history)
        std::vector<char> on_path;
        const bool curved = core.solver.sliding != nullptr && mark_curved_paths(core.sliding, n, on_path) > 0;
        collider_history(n, phys, curved ? on_path.data() : nullptr, buf.pos, buf.vel, buf.prev_pos, buf.prev_vel, h);
    }
    if (edged & PUSHED) collider_edge_history(*core.contact.lists, n, buf.pos, buf.vel, buf.prev_pos, buf.prev_vel, h);
    if (core.solver.supports != nullptr) support_history(core.supports, n, buf.pos, buf.vel, buf.prev_pos, buf.prev_vel, h);
    clock[LAST_STEP] = kinked ? 0.0 : h;  // a frozen step, a mesh collider's edges: BDF2 starts afresh
    clock[TIME] += h;
    clock[STEPS] += 1;
    maybe_sleep(core, h, (exchanging && !sunk(core)) || grip.moving ||
                             (phys.collider_motion != nullptr && colliders_ahead(phys, clock[TIME])));
    return DONE;
}

}  // namespace

namespace {

std::string g(double value) {  // Python's format(value, "g")
    char text[32];
    std::snprintf(text, sizeof text, "%g", value);
    return text;
}

//: The clock's slots as Simulation.snapshot() names them.
const char* const SLOT_NAMES[CLOCK_SIZE] = {
    "state.time", "next_step", "last_step", "speed", "calm_time", "unchecked_time", "exchanging", "sleeping",
    "steps", "rejected_steps", "failed_step", "newton_rate", "rate_correction", "first_guess",
    "last_solve_iterations", "largest_error"};

//: The first value of values[0 .. count) outside [lo, hi] (or not finite), as "<name> holds <value><unit> at
//: particle <i> (<x|y|z>)" (rows of n, when n > 0) or "... at <index>", else empty.
std::string outside(const char* name, const double* values, Index count, double lo, double hi, const char* unit,
                    Index n = 0) {
    for (Index k = 0; k < count; ++k) {
        const double v = values[k];
        if (!(v >= lo && v <= hi)) {
            std::string where = n > 0 ? "particle " + std::to_string(k % n) : "index " + std::to_string(k);
            if (n > 0 && count == 3 * n) where += std::string(" (") + "xyz"[k / n] + ")";
            return std::string(name) + " holds " + g(v) + unit + " at " + where;
        }
    }
    return "";
}

}  // namespace

std::string state_problem(const Cloth& cloth, const Physics& phys, const Control& control, const StateView& s) {
    const Index n = cloth.n;
    const double* clock = s.clock;
    std::string what;
    // Every value finite.
    for (Index k = 0; k < CLOCK_SIZE; ++k) {
        if (!std::isfinite(clock[k])) return std::string(SLOT_NAMES[k]) + " is " + g(clock[k]) + ": not a finite number";
    }
    if (!std::isfinite(s.contact_margin)) return "contact_margin is not finite";
    const double big = std::numeric_limits<double>::max();  // within +-big: finite
    if (!(what = outside("acceleration", s.acceleration, 3 * n, -big, big, " m/s2", n)).empty()) {
        return what + ": not a finite number";
    }
    if (!(what = outside("the preconditioner", s.others, s.other_count, -big, big, "")).empty()) {
        return what + ": not a finite number";
    }
    // Time and the step control.
    if (!(clock[TIME] >= 0.0 && clock[TIME] <= MAX_TIME)) {
        return "state.time is " + g(clock[TIME]) + " s: a state's time is 0 (its start) to " + g(MAX_TIME) + " s";
    }
    if (!(clock[NEXT_STEP] > 0.0)) return "next_step is " + g(clock[NEXT_STEP]) + " s: it must be > 0 s";
    if (!(clock[LAST_STEP] >= 0.0 && clock[LAST_STEP] <= 2.0 * control.max_step)) {
        return "last_step is " + g(clock[LAST_STEP]) + " s: it is 0 (none) to twice max_step";
    }
    for (const ClockSlot slot : {CALM_TIME, UNCHECKED_TIME}) {
        if (!(clock[slot] >= 0.0 && clock[slot] <= MAX_TIME)) {
            return std::string(slot == CALM_TIME ? "calm_time" : "unchecked_time") + " is " + g(clock[slot]) +
                   " s: it is 0 to " + g(MAX_TIME) + " s";
        }
    }
    for (const ClockSlot slot : {STEPS, REJECTED}) {
        if (!(clock[slot] >= 0.0 && clock[slot] == std::floor(clock[slot]))) {
            return std::string(slot == STEPS ? "steps" : "rejected_steps") + " is " + g(clock[slot]) +
                   ": a count is a whole number >= 0";
        }
    }
    for (const ClockSlot slot : {EXCHANGING, SLEEPING}) {
        if (clock[slot] != 0.0 && clock[slot] != 1.0) {
            return std::string(slot == EXCHANGING ? "exchanging" : "sleeping") + " is " + g(clock[slot]) +
                   ": a flag is 0 or 1";
        }
    }
    if (!(clock[SPEED] >= 0.0 && clock[SPEED] < control.blow_up_speed)) {
        return "speed is " + g(clock[SPEED]) + " m/s: it is 0 to below " + g(control.blow_up_speed) + " m/s";
    }
    if (!(s.contact_margin >= 0.0)) return "contact_margin is " + g(s.contact_margin) + " m: it must be >= 0 m";
    // Positions: finite, bounded, above the floor.
    const double c = MAX_COORDINATE;
    const char* const position_names[] = {"state.pos", "prev_pos", "anchor", "contact_reference"};
    const double* const positions[] = {s.pos, s.prev_pos, s.anchor, s.contact_reference};
    for (int a = 0; a < 4; ++a) {
        if (!(what = outside(position_names[a], positions[a], 3 * n, -c, c, " m", n)).empty()) {
            return what + ": coordinates are finite, within " + g(c) + " m of the origin";
        }
    }
    const double lowest = phys.floor_z - phys.thickness;
    if (!(what = outside("state.pos", s.pos + 2 * n, n, lowest, c, " m", n)).empty()) {
        return what + ": the floor holds every particle at z >= " + g(phys.floor_z) + " m";
    }
    // Velocities: below the blow-up speed; the pinned particles' all one, the grip's (place_grip), and every
    // particle's zero while asleep.
    const char* const velocity_names[] = {"state.vel", "prev_vel"};
    const double* const velocities[] = {s.vel, s.prev_vel};
    Index first_pinned = 0;
    while (first_pinned < n && cloth.free[first_pinned] != 0.0) ++first_pinned;
    for (int a = 0; a < 2; ++a) {
        const double* v = velocities[a];
        for (Index i = 0; i < n; ++i) {
            const double x = v[i], y = v[n + i], z = v[2 * n + i];
            const double speed = std::sqrt(x * x + y * y + z * z);
            if (!(speed < control.blow_up_speed)) {
                return std::string(velocity_names[a]) + " holds a speed of " + g(speed) + " m/s at particle " +
                       std::to_string(i) + ": speeds are finite and below " + g(control.blow_up_speed) + " m/s";
            }
            if (a == 0 && cloth.free[i] == 0.0) {
                const Index r = first_pinned;
                if (x != v[r] || y != v[n + r] || z != v[2 * n + r]) {
                    return "state.vel holds (" + g(x) + ", " + g(y) + ", " + g(z) + ") m/s at particle " +
                           std::to_string(i) + ", which is pinned, but (" + g(v[r]) + ", " + g(v[n + r]) + ", " +
                           g(v[2 * n + r]) + ") m/s at pinned particle " + std::to_string(r) +
                           ": the grip moves the pinned particles together";
                }
            }
            if (a == 0 && (x != 0.0 || y != 0.0 || z != 0.0)) {
                if (clock[SLEEPING] != 0.0) {
                    return "the state is asleep but moves (" + g(speed) + " m/s at particle " + std::to_string(i) +
                           "): a cloth sleeps only at rest";
                }
            }
        }
    }
    if (clock[SLEEPING] != 0.0 && clock[SPEED] != 0.0) {
        return "the state is asleep but its speed is " + g(clock[SPEED]) + " m/s: a cloth sleeps only at rest";
    }
    // Water: 0 to the most a particle can hold.
    const char* const water_names[] = {"state.water", "prev_water"};
    const double* const waters[] = {s.water, s.prev_water};
    for (int a = 0; a < 2; ++a) {
        for (Index i = 0; i < n; ++i) {
            const double w = waters[a][i], most = MAX_WATER_RATIO * cloth.dry_mass[i];
            if (!(w >= 0.0 && w <= most)) {
                return std::string(water_names[a]) + " holds " + g(w) + " kg at particle " + std::to_string(i) +
                       ": a particle holds 0 to " + g(most) + " kg of water (" + g(MAX_WATER_RATIO) +
                       " times its dry mass)";
            }
        }
    }
    return "";
}

double stable_step(const Control& control, double speed) {
    const double gamma = control.damping_rate + control.drag_rate_offset + control.drag_rate_slope * speed;
    if (control.integrator == EXPLICIT_EULER) {
        double limit = control.spring_limit;
        if (gamma > 0.0) limit = pymin(limit, 2.0 / gamma);
        return STABILITY_SAFETY * limit;
    }
    if (control.integrator == SYMPLECTIC_EULER) {
        // For x'' = -w^2 x - g x' the scheme is stable iff h < 4 / (g + sqrt(g^2 + 4 w^2)).
        const double omega2 = control.omega_squared + control.buoyancy_omega_squared;
        return STABILITY_SAFETY * 4.0 / (gamma + std::sqrt(gamma * gamma + 4.0 * omega2));
    }
    return std::numeric_limits<double>::infinity();
}

namespace {

using WallClock = std::chrono::steady_clock;

WallClock::time_point deadline_after(double seconds) {
    const double capped = pymin(pymax(seconds, 0.0), 1e6);  // NaN: at once
    return WallClock::now() + std::chrono::duration_cast<WallClock::duration>(std::chrono::duration<double>(capped));
}

//: Time (s, from now) at which the uptake of a sleeping cloth has made a particle SLEEP_WEIGHT_GROWTH
//: heavier than at the last step it took (prev_water), or infinity.  Each particle under the surface holds
//: q(t) = Q - (Q - q) exp(-R t / C) (the uptake is exact over any time).
double wake_time(const Core& core) {
    const Cloth& cloth = core.cloth;
    const Physics& phys = core.phys;
    const Buffers& buf = core.buf;
    const Index n = cloth.n;
    const double level = surface(phys);
    double soonest = std::numeric_limits<double>::infinity();
    if (!absorbing(phys)) return soonest;
    for (Index i = 0; i < n; ++i) {
        if (!(buf.pos[2 * n + i] < level)) continue;
        const double full = phys.absorption_capacity * cloth.dry_mass[i];
        const double limit = (1.0 + SLEEP_WEIGHT_GROWTH) * (cloth.dry_mass[i] + buf.prev_water[i]) - cloth.dry_mass[i];
        if (buf.water[i] >= limit) return 0.0;
        if (limit >= full) continue;  // it fills up first
        soonest = pymin(soonest, phys.absorption_capacity / phys.absorption_rate *
                                     std::log((full - buf.water[i]) / (full - limit)));
    }
    return soonest;
}

//: Let a sleeping cloth's time pass towards target (s): what it takes up meanwhile (exactly: it does not
//: move), until target or until its weight has grown enough to wake it (wake_time).  Returns whether it woke.
bool sleep_until(Core& core, double target) {
    double* clock = core.clock;
    Buffers& buf = core.buf;
    const Index n = core.cloth.n;
    const double wake = wake_time(core);
    const double remaining = target - clock[TIME];
    const bool wakes = wake < remaining;
    const double h = wakes ? wake : remaining;
    if (absorbing(core.phys) && h > 0.0) {
        const double* z = buf.pos + 2 * n;
        const double* vz = buf.vel + 2 * n;  // zero: asleep
        uptake(n, z, z, vz, vz, surface(core.phys), core.cloth.dry_mass, core.phys.absorption_capacity,
               core.phys.absorption_rate, h, buf.water, buf.trial_water);
        copy(n, buf.trial_water, buf.water);
    }
    if (!wakes) return false;
    clock[TIME] += h;
    clock[SLEEPING] = 0.0;
    clock[CALM_TIME] = 0.0;
    clock[UNCHECKED_TIME] = 0.0;
    clock[EXCHANGING] = 0.0;
    copy(3 * n, buf.pos, buf.anchor);
    return true;
}

//: advance up to a wall-clock deadline.  The clock is read every `stride` steps, a few microseconds of
//: work apart at least (a step costs some tens of nanoseconds per particle), and after the first step:
//: a call always makes progress.
Status advance_until(Core& core, double target, Index max_steps, WallClock::time_point deadline) {
    double* clock = core.clock;
    const Index stride = std::max<Index>(1, 1024 / std::max<Index>(1, core.cloth.n));
    Index taken = 0;
    while (target - clock[TIME] > 1e-12 * pymax(1.0, std::fabs(target))) {
        if (clock[SLEEPING] != 0.0 && !sleep_until(core, target)) break;
        if (taken >= max_steps) return PAUSED;
        if (taken > 0 && taken % stride == 0 && WallClock::now() >= deadline) return PAUSED;
        const double key = core.phys.collider_motion != nullptr ? next_collider_key(core.phys, clock[TIME]) : target;
        if (step(core, target - clock[TIME], pymin(target, key) - clock[TIME]) != DONE) return BLOWN_UP;
        ++taken;
    }
    clock[TIME] = pymax(clock[TIME], target);
    return DONE;
}

}  // namespace

Status advance(Core& core, double target, Index max_steps, double pause_after) {
    return advance_until(core, target, max_steps, deadline_after(pause_after));
}

void record_outputs(Index n, const double* dry_mass, double water_level, const double* pos, const double* water,
                    double* row) {
    double wet_mass = 0.0, water_mass = 0.0, moment_x = 0.0, moment_y = 0.0, moment_z = 0.0;
    const double* x = pos;
    const double* y = pos + n;
    const double* z = pos + 2 * n;
    for (Index i = 0; i < n; ++i) {
        const double mass = dry_mass[i] + water[i];
        wet_mass += mass;
        water_mass += water[i];
        moment_x += mass * x[i];
        moment_y += mass * y[i];
        moment_z += mass * z[i];
    }
    row[0] = moment_x / wet_mass;
    row[1] = moment_y / wet_mass;
    row[2] = moment_z / wet_mass;
    row[3] = water_level - row[2];
    row[4] = wet_mass;
    row[5] = water_mass;
}

SamplingResult advance_sampling(Core& core, const double* times, Index count, double* outputs, double* errors,
                                Index first, Index max_steps, double pause_after) {
    const WallClock::time_point deadline = deadline_after(pause_after);
    const double budget_end = core.clock[STEPS] + static_cast<double>(max_steps);
    double* clock = core.clock;
    for (Index k = first; k < count; ++k) {
        const Index budget = static_cast<Index>(budget_end - clock[STEPS]);
        if (budget <= 0 || (k > first && WallClock::now() >= deadline)) return {PAUSED, k};
        // The interval's own largest error, kept in errors[k] across paused calls; the clock keeps the
        // largest of them all.
        const double running = clock[LARGEST_ERROR];
        clock[LARGEST_ERROR] = errors[k];
        const Status status = advance_until(core, times[k], budget, deadline);
        errors[k] = clock[LARGEST_ERROR];
        clock[LARGEST_ERROR] = pymax(running, errors[k]);
        if (status != DONE) return {status, k};
        record_outputs(core.cloth.n, core.cloth.dry_mass, core.phys.water_level, core.buf.pos, core.buf.water,
                       outputs + k * OUTPUT_COUNT);
    }
    return {DONE, count};
}

}  // namespace wc
