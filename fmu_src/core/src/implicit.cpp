// Implicit steps: BDF2 and backward Euler, both by Newton iterations (BDF2 a port of
// bf41571:fmu_src/wetcloth/kernels/implicit.py).
#include "wetcloth/implicit.hpp"

#include <cmath>

#include "wetcloth/assembly.hpp"
#include "wetcloth/coarse_space.hpp"
#include "wetcloth/collider_motion.hpp"
#include "wetcloth/collider_supports.hpp"
#include "wetcloth/integration.hpp"
#include "wetcloth/lanes.hpp"
#include "wetcloth/plane.hpp"
#include "wetcloth/reused_plane.hpp"
#include "wetcloth/sliding.hpp"

namespace wc {

namespace {

//: Python's max(a, b) and min(a, b): a unless b compares greater (smaller); a NaN b is never taken.
inline double py_max(double a, double b) { return b > a ? b : a; }
inline double py_min(double a, double b) { return b < a ? b : a; }

//: Maxima of |values| over (3, n) arrays are kept in MAX_LANES running maxima side by side (in_lanes), which
//: do not wait on each other as one running maximum does: the same value as one pass
//: in order, whatever the order (py_max never takes a NaN).
constexpr Index MAX_LANES = 8;

//: The largest of MAX_LANES running maxima.
double largest_lane(const double* largest) {
    double result = 0.0;
    for (Index l = 0; l < MAX_LANES; ++l) result = py_max(result, largest[l]);
    return result;
}

//: Largest |a| over a (3, n) array.
double largest_of(Index n, const double* a) {
    double largest[MAX_LANES] = {};
    in_lanes<MAX_LANES>(3 * n, [&](Index l, Index k) { largest[l] = py_max(largest[l], std::fabs(a[k])); });
    return largest_lane(largest);
}

struct DotAndLargest {
    double dot, largest;
};

//: dot(n, r, z) and largest_of(n, z) in one pass (the same sums and comparisons, in the same order).
DotAndLargest dot_and_largest(Index n, const double* r, const double* z) {
    static_assert(DOT_LANES == MAX_LANES, "one pass keeps the sums and the maxima in the same lanes");
    double sums[DOT_LANES] = {};
    double largest[MAX_LANES] = {};
    in_lanes<DOT_LANES>(3 * n, [&](Index l, Index k) {
        sums[l] += r[k] * z[k];
        largest[l] = py_max(largest[l], std::fabs(z[k]));
    });
    return {sum_of_lanes<DOT_LANES>(sums), largest_lane(largest)};
}

struct Corrections {
    double largest;    // m/s, the largest |length dv|
    double increment;  // m/s, the largest |v+ - v| or |v+|
};

//: Newton's convergence measures over (3, n) arrays, in MAX_LANES lanes.
Corrections corrections(Index n, double length, const double* dv, const double* out_vel, const double* vel) {
    double largest[MAX_LANES] = {};
    double increment[MAX_LANES] = {};
    in_lanes<MAX_LANES>(3 * n, [&](Index l, Index k) {
        largest[l] = py_max(largest[l], std::fabs(length * dv[k]));
        increment[l] = py_max(py_max(increment[l], std::fabs(out_vel[k] - vel[k])), std::fabs(out_vel[k]));
    });
    return {largest_lane(largest), largest_lane(increment)};
}

struct PlaneSolve {
    Index iterations;
    bool solved;
};

//: Solve A x = b (x = 0 first) by conjugate gradients preconditioned by the plane preconditioner, until
//: the preconditioned residual P^-1 r, which estimates the error left in x, is at most rtol times its
//: first value or `floor` (m/s) in every component.  With a `coarse` space, its correction is added to
//: the plane preconditioner's (two-level additive).  Its products read the springs' blocks rounded to
//: single precision (a relative change of about 1e-7 in A, far below rtol); Newton's residual stays exact.
PlaneSolve plane_pcg(const Cloth& cloth, const Work& work, Solver& solver, Plane& plane, const double* b, double* x,
                     double rtol, double floor, Index max_iterations, CoarseSpace* coarse) {
    const Index n = cloth.n;
    const double* mass = solver.mass;
    double* r = solver.r;
    double* z = solver.z;
    double* p = solver.p;
    double* ap = solver.ap;
    for (Index k = 0; k < 3 * n; ++k) x[k] = 0.0;
    copy(3 * n, b, r);
    apply(plane, n, cloth.free, r, z);
    if (coarse != nullptr) add_coarse_correction(*coarse, cloth, r, z);
    if (solver.sliding != nullptr) project_sliding(*solver.sliding, n, z);
    copy(3 * n, z, p);
    DotAndLargest rz_z = dot_and_largest(n, r, z);  // r . z and the largest |z|
    double rz = rz_z.dot;
    const double accuracy = py_max(rtol * rz_z.largest, floor);
    Index iterations = 0;
    while (rz_z.largest > accuracy && iterations < max_iterations) {
        system_matvec(cloth, work, mass, p, ap, Precision::SINGLE);
        if (solver.supports != nullptr) add_support_product(*solver.supports, n, cloth.free, p, ap);
        if (solver.sliding != nullptr) project_sliding(*solver.sliding, n, ap);
        const double p_ap = dot(n, p, ap);
        if (!(p_ap > 0.0)) break;
        conjugate_gradient_step(n, rz / p_ap, p, ap, x, r);
        iterations += 1;
        apply(plane, n, cloth.free, r, z);
        if (coarse != nullptr) add_coarse_correction(*coarse, cloth, r, z);
        if (solver.sliding != nullptr) project_sliding(*solver.sliding, n, z);
        rz_z = dot_and_largest(n, r, z);
        next_search_direction(n, rz_z.dot / rz, z, p);
        rz = rz_z.dot;
    }
    return {iterations, rz_z.largest <= accuracy};
}

//: Newton's first guess (m/s) of a velocity component h s ahead, extrapolated from v (now, with `slope`
//: m/s^2) and v_prev (h_prev s ago).  The PARABOLA errs by third order in h where the solution is smooth
//: on the step's scale (a floating cloth's bobbing at 2 ms steps: first corrections a third of the
//: LINE's), the LINE by second order; on stiff modes at long steps (a floating cloth at 1/30 s) the
//: implied slope is noise and the LINE does better.
inline double first_guess(double kind, double v, double v_prev, double slope, double h, double h_prev) {
    const double w = h / h_prev;
    if (kind == PARABOLA) return v + h * slope + w * w * (v_prev - v + h_prev * slope);
    return v + w * (v - v_prev);
}

//: Which first_guess kind came closer to this step's solution (3, n): the next step's.
double better_guess(Index n, const double* vel, const double* prev_vel, const double* acceleration,
                    const double* free, double h, double h_prev, const double* solution) {
    double line = 0.0;
    double parabola = 0.0;
    for (Index c = 0; c < 3; ++c) {
        for (Index i = 0; i < n; ++i) {
            if (free[i] != 0.0) {
                const Index k = c * n + i;
                const double v = vel[k], v_prev = prev_vel[k], slope = acceleration[k], end = solution[k];
                line = py_max(line, std::fabs(first_guess(LINE, v, v_prev, slope, h, h_prev) - end));
                parabola = py_max(parabola, std::fabs(first_guess(PARABOLA, v, v_prev, slope, h, h_prev) - end));
            }
        }
    }
    return parabola < line ? PARABOLA : LINE;
}

//: Newton's residual into solver.rhs from the force (3, n) in work.force at velocities out_vel (3, n).
void residual_of_force(const Cloth& cloth, const Work& work, Solver& solver, const double* hat_vel,
                       const double* out_vel, double bh) {
    const Index n = cloth.n;
    const double* free = cloth.free;
    const double* mass = solver.mass;
    for (Index c = 0; c < 3; ++c) {
        const double* __restrict f = work.force + c * n;
        const double* __restrict ov = out_vel + c * n;
        const double* __restrict hv = hat_vel + c * n;
        double* __restrict rc = solver.rhs + c * n;
        for (Index i = 0; i < n; ++i) rc[i] = free[i] * (bh * f[i] - mass[i] * (ov[i] - hv[i]));
    }
    if (solver.sliding != nullptr) project_sliding(*solver.sliding, n, solver.rhs);
}

//: Forces and Jacobian pieces at (out_pos, out_vel), and Newton's residual into solver.rhs:
//: free (b h F - M (v - v^)), minus the gradient of the step's incremental potential in v.  The particles
//: sliding on a surface (solver.sliding) feel kinetic friction in F, and their residual has no part along
//: the surface's normal (their velocity across it is prescribed).
void newton_residual(const Cloth& cloth, const Physics& phys, Work& work, Solver& solver, const double* hat_vel,
                     const double* step_water, const double* out_pos, const double* out_vel, double bh,
                     double slack_slope) {
    const Index n = cloth.n;
    forces_and_blocks(cloth, phys, work, out_pos, out_vel, step_water, bh, slack_slope);
    if (solver.supports != nullptr) add_support_forces(*solver.supports, n, out_pos, out_vel, work.force, work.blocks);
    if (solver.sliding != nullptr) {
        add_sliding_friction(*solver.sliding, n, solver.mass, out_vel, bh, work.force, work.blocks);
    }
    residual_of_force(cloth, work, solver, hat_vel, out_vel, bh);
}

//: Whether a support presses in `at` (its terms' pressing flags) that does not in `before`.
bool met_within(const std::vector<char>& before, const std::vector<char>& at) {
    for (std::size_t t = 0; t < at.size(); ++t) {
        if (at[t] && !before[t]) return true;
    }
    return false;
}

//: Descent's line search along the correction dv from the velocities out_vel, whose residual (minus
//: the gradient of the step's incremental potential) is in solver.rhs: the step length a in (0, 1] where
//: the potential stops falling along dv, the root of the slope dv . r(v + a dv) by false position
//: (Illinois), or 1 where it still falls.  At most LINE_SEARCH_EVALUATIONS residuals; the last is
//: where it leaves out_vel, out_pos and solver.rhs (so the next Newton iteration starts from it).
//: base (3, n) is scratch.
//: A support met within the bracket (a penalty the Newton matrix did not have) makes the slope at its far
//: end far steeper than at its near end, and false position then creeps from the near end: a guess within
//: LINE_SEARCH_GUARD of the bracket's width from either end is replaced by its middle.  If the evaluations
//: still run out short of the slope's root, the search ends where the potential still falls (the bracket's
//: near end; past the root, a mesh ball spinning through a towel pressed its supports too deep, and 67 steps
//: were taken again instead of 7), and the supports pressing at the full step are anticipated (stiff in the
//: matrix for the rest of the step), so that the next correction sees the wall.  (A sheet swinging onto the
//: floor at 1/24 s stopped at 0.0015 of its correction four times in a row and gained 0.012 J in the step; at
//: 1/20 s the tablecloth hovered 8.3 mm above its table: bench/frame_step_energy.py, tests/test_analytic_supports.py.)
//: Without such a support the guesses are left as they are: bisecting a smoothed friction's steep stick too slid
//: a pushed sheet 0.4 % past Coulomb's distance.
double line_search(const Cloth& cloth, const Physics& phys, Work& work, Solver& solver, const double* hat_pos,
                   const double* hat_vel, const double* step_water, double bh, double slack_slope, const double* dv,
                   double* base, double* out_pos, double* out_vel) {
    const Index n = cloth.n;
    const double first = dot(n, dv, solver.rhs);
    copy(3 * n, out_vel, base);
    Supports* supports = solver.supports;
    std::vector<char> low_pressing, high_pressing, full_step_pressing;  // the supports' at the bracket's ends
    if (supports != nullptr) low_pressing = supports->pressing;  // (the residual in hand is the start's)
    const auto slope_at = [&](double a) {
        for (Index k = 0; k < 3 * n; ++k) {
            out_vel[k] = base[k] + a * dv[k];
            out_pos[k] = hat_pos[k] + bh * out_vel[k];
        }
        newton_residual(cloth, phys, work, solver, hat_vel, step_water, out_pos, out_vel, bh, slack_slope);
        return dot(n, dv, solver.rhs);
    };
    double high = 1.0;
    double high_slope = slope_at(high);
    if (!(first > 0.0 && high_slope < 0.0)) return high;  // still falling at the full step
    if (supports != nullptr) high_pressing = full_step_pressing = supports->pressing;
    double low = 0.0;
    double low_slope = first;
    double a = high;
    int side = 0;  // which end the last two guesses moved (Illinois halves the other end's slope)
    for (Index evaluation = 1; evaluation < LINE_SEARCH_EVALUATIONS; ++evaluation) {
        a = high - high_slope * (high - low) / (high_slope - low_slope);
        const double guard = LINE_SEARCH_GUARD * (high - low);
        const bool near_an_end = !(a > low + guard && a < high - guard);
        // (The first guess, at the full step's end, always: a wall anywhere within the step.)
        if (near_an_end && (evaluation == 1 || met_within(low_pressing, high_pressing))) a = 0.5 * (low + high);
        const double slope = slope_at(a);
        if (std::fabs(slope) <= LINE_SEARCH_SLOPE * first) return a;
        if (slope > 0.0) {
            low = a;
            low_slope = slope;
            if (side > 0) high_slope *= 0.5;
            side = 1;
            if (supports != nullptr) low_pressing = supports->pressing;
        } else {
            high = a;
            high_slope = slope;
            if (side < 0) low_slope *= 0.5;
            side = -1;
            if (supports != nullptr) high_pressing = supports->pressing;
        }
    }
    if (supports != nullptr) {
        for (std::size_t t = 0; t < full_step_pressing.size(); ++t) supports->anticipated[t] |= full_step_pressing[t];
    }
    if (a == high && low > 0.0) {  // ended past the slope's root: back to where the potential still fell
        slope_at(low);
        return low;
    }
    return a;
}

//: Whether a backward Euler step at velocities v+ = out_vel, whose residual (minus the gradient of the
//: incremental potential) is in rhs, has settled its energy: the work the unsolved residual would do
//: over the step, |v+ . rhs| (J), is at most DESCENT_ENERGY_FRACTION of the kinetic energy the scheme's
//: own damping removes, 1/2 sum m |v+ - v^|^2 (J).
bool energy_settled(Index n, const double* mass, const double* free, const double* out_vel, const double* hat_vel,
                    const double* rhs) {
    double work = 0.0;
    double damped = 0.0;
    for (Index c = 0; c < 3; ++c) {
        for (Index i = 0; i < n; ++i) {
            const Index k = c * n + i;
            const double change = out_vel[k] - hat_vel[k];
            work += out_vel[k] * rhs[k];
            damped += 0.5 * free[i] * mass[i] * change * change;
        }
    }
    return std::fabs(work) <= DESCENT_ENERGY_FRACTION * damped;
}

//: Whether the cloth moves freely at the iterate whose forces work holds: no particle on a surface or held by
//: a support in the step's solve, none in the water, no layers near each other (DESCENT_LATER_CG_ITERATIONS).
bool moves_freely(const Cloth& cloth, const Work& work, const Solver& solver) {
    if (solver.near_itself) return false;
    if (solver.sliding != nullptr && solver.sliding->count() > 0) return false;
    if (solver.supports != nullptr && solver.supports->count() > 0) return false;
    for (Index i = 0; i < cloth.n; ++i) {
        if (work.submerged[i] > 0.0) return false;
    }
    return true;
}

//: The velocities v+ at which a backward Euler step would leave its free particles where they start
//: (x+ = x): 0 for them, out_vel's prescribed ones for the pinned, gripped and held, and the sliding
//: particles' speed across their surface as the step prescribes it.  The step's incremental potential
//: there is the energy (kinetic, potential) the step started with.
void velocities_at_rest(const Cloth& cloth, Solver& solver, Index n, const double* pos, const double* hat_pos,
                        double h, double bh, const double* out_vel, double* rest) {
    for (Index c = 0; c < 3; ++c) {
        for (Index i = 0; i < n; ++i) rest[c * n + i] = cloth.free[i] != 0.0 ? 0.0 : out_vel[c * n + i];
    }
    if (solver.sliding != nullptr) prescribe_normal_speed(*solver.sliding, n, pos, hat_pos, h, bh, rest);
}

//: How far (J) the step's incremental potential at out_vel lies above its value at the velocities rest:
//: Simpson's rule over its slope along the segment between them, at five points, the last at out_vel,
//: so that the residual (solver.rhs) and the supports' state are left as they are there.  toward (3, n)
//: receives out_vel - rest; solver.z and solver.ap are scratch.
double potential_rise(const Cloth& cloth, const Physics& phys, Work& work, Solver& solver, const double* hat_pos,
                      const double* hat_vel, const double* step_water, double bh, double slack_slope,
                      const double* rest, const double* out_pos, const double* out_vel, double* toward) {
    const Index n = cloth.n;
    for (Index k = 0; k < 3 * n; ++k) toward[k] = out_vel[k] - rest[k];
    constexpr double simpson[5] = {1.0, 4.0, 2.0, 4.0, 1.0};  // times a quarter of the segment / 3
    double rise = 0.0;
    for (int j = 0; j < 5; ++j) {
        const double* at_vel = out_vel;
        const double* at_pos = out_pos;
        if (j < 4) {
            for (Index k = 0; k < 3 * n; ++k) {
                solver.z[k] = rest[k] + 0.25 * j * toward[k];
                solver.ap[k] = hat_pos[k] + bh * solver.z[k];
            }
            at_vel = solver.z;
            at_pos = solver.ap;
        }
        newton_residual(cloth, phys, work, solver, hat_vel, step_water, at_pos, at_vel, bh, slack_slope);
        rise -= simpson[j] / 12.0 * dot(n, toward, solver.rhs);  // the residual is minus the potential's slope
    }
    return rise;
}

}  // namespace

//: With w = h / h_prev, y+ = y^ + b h f(y+) for y = (x, p), where y^ = ((1 + w)^2 y - w^2 y_prev) / (1 + 2w)
//: and b = (1 + w) / (1 + 2w).  The momentum p = m v is the history's variable, not the velocity:
//: absorbed water arrives at rest, so uptake between steps leaves p unchanged (and slows v); a history
//: of velocities would carry that slowing forward and count it twice.  Forces and inertia are those of
//: step_water, the water (kg) the particles will hold at the end of the step; water is what they hold
//: now.  Newton iterations in the velocity, x+ = x^ + b h v+, each solving
//: A dv = b h F(x+, v+) - M (v+ - v^) (see CG_TOLERANCE), until the correction, or what the observed
//: convergence rate leaves to come, is within tolerance: newton_tolerance (m) in position, and see
//: NEWTON_RELATIVE for the velocity.
//:
//: memory (4) carries over from step to step: the last convergence rate observed and the correction
//: (m/s) it was observed after (FIRST_ITERATION_TRUST), which kind of first guess to start from (with
//: the acceleration (3, n) m/s^2 the last step implied), and the CG iterations of the last linear solve
//: (jacobian_refresh_pays).  Leaves in solver.step_acceleration the acceleration the step implies at
//: its end, (v+ - v^) / (b h), and in memory[2] the kind of guess that would have come closer to it.
//:
//: The error estimate is the corrector's distance from the quadratic extrapolation through x_prev, x, v
//: (Milne's device): BDF2 errs by -(1+w)^2/(6w(1+2w)) h^3 x''', the extrapolation by (1+w)/(6w) h^3 x''',
//: so the BDF2 error is (1+w)/(2+3w) times their difference.  Without history: h |v+ - v| / 2.  Pinned
//: particles' positions are not estimated (they stay, or the grip moves them).
StepEstimate bdf2_step(const Cloth& cloth, const Physics& phys, Work& work, Solver& solver, Plane& plane,
                       const double* pos, const double* vel, const double* water, const double* step_water,
                       const double* prev_pos, const double* prev_vel, const double* prev_water,
                       const double* acceleration, double h, double h_prev, double newton_tolerance,
                       double cg_tolerance, NewtonMode mode, bool descent, double* memory, double* out_pos,
                       double* out_vel, const double* held, const double* grip_rate, ReusedPlane* reused) {
    const Index n = cloth.n;
    double* mass = solver.mass;
    double* hat_pos = solver.hat_pos;
    double* hat_vel = solver.hat_vel;
    double* predicted = solver.predicted;
    double* dv = solver.dv;
    double* rhs = solver.rhs;
    const double* free = cloth.free;
    const double* dry_mass = cloth.dry_mass;
    for (Index i = 0; i < n; ++i) mass[i] = dry_mass[i] + step_water[i];
    const bool history = h_prev > 0.0;
    const double w = history ? h / h_prev : 0.0;
    const double beta = (1.0 + w) / (1.0 + 2.0 * w);
    const double a = (1.0 + w) * (1.0 + w) / (1.0 + 2.0 * w);
    const double b = w * w / (1.0 + 2.0 * w);
    const double kind = memory[2];
    for (Index c = 0; c < 3; ++c) {
        for (Index i = 0; i < n; ++i) {
            const Index k = c * n + i;
            double guess;
            if (history && free[i] != 0.0) {  // (a pinned particle stays exactly where it is)
                hat_pos[k] = a * pos[k] - b * prev_pos[k];
                const double momentum = (dry_mass[i] + water[i]) * vel[k];
                const double previous_momentum = (dry_mass[i] + prev_water[i]) * prev_vel[k];
                hat_vel[k] = (a * momentum - b * previous_momentum) / mass[i];
                predicted[k] = pos[k] + h * vel[k] + w * w * (prev_pos[k] - pos[k] + h_prev * vel[k]);
                guess = first_guess(kind, vel[k], prev_vel[k], acceleration[k], h, h_prev);
            } else {
                hat_pos[k] = pos[k];
                hat_vel[k] = (dry_mass[i] + water[i]) * vel[k] / mass[i];
                predicted[k] = pos[k];
                guess = hat_vel[k];
            }
            out_vel[k] = guess * free[i];
            // The grip or a moving collider that holds it moves it: v+ prescribed.
            double carried[3];
            const double* rate = free[i] != 0.0 || held == nullptr ? nullptr
                                 : held[i] == 0.0                   ? grip_rate
                                 : held_rate(phys, held[i], n, i, pos, h, carried) ? carried : nullptr;
            if (rate != nullptr) {
                out_vel[k] = rate[c];
                hat_vel[k] = rate[c];
                hat_pos[k] = pos[k] + (h - beta * h) * rate[c];  // so that x+ = x + h v+
            }
        }
    }
    const double bh = beta * h;
    if (solver.supports != nullptr) place_supports(*solver.supports, phys, n, pos, h, bh);
    if (solver.sliding != nullptr && solver.sliding->smoothed) {  // friction's normal force, held for the step
        forces(cloth, phys, work, pos, vel, water);
        lag_normal_force(*solver.sliding, n, mass, work.force);  // the start's
        if (history) {  // the one the history predicts at the step's end, where that is near the start's
            double* ahead = solver.p;  // scratch: the velocities extrapolated to the step's end
            for (Index k = 0; k < 3 * n; ++k) ahead[k] = vel[k] + w * (vel[k] - prev_vel[k]);
            forces(cloth, phys, work, predicted, ahead, step_water);
            lag_predicted_normal_force(*solver.sliding, n, phys, mass, work.force, ahead, h);
        }
    }
    if (solver.sliding != nullptr) prescribe_normal_speed(*solver.sliding, n, pos, hat_pos, h, bh, out_vel);
    for (Index k = 0; k < 3 * n; ++k) out_pos[k] = hat_pos[k] + bh * out_vel[k];
    const bool adaptive = mode == NewtonMode::ADAPTIVE;
    Index factored = 0;
    if (adaptive) {  // (fixed steps build every system from the Jacobian)
        factored = refresh(plane, cloth, mass, bh * bh);
        solver.counters[FACTORISATIONS] += factored > 0;
    }
    if (adaptive) follow_cloth(plane, cloth, pos);
    if (!adaptive) reused = nullptr;
    Plane* solving = &plane;  // the linear solves' preconditioner
    // Descent's fixed steps on grids add a coarse space to it.  (BDF2's fixed steps, halved where Newton
    // fails, took 13.6 CG iterations per Newton iteration with it instead of 14.9, but 226 steps instead
    // of 219 and 10 % more time on the hanging sheet.)
    CoarseSpace coarse_space;
    CoarseSpace* coarse = nullptr;
    if (!adaptive && descent && has_coarse_space(cloth)) {
        shape_coarse_space(coarse_space, cloth, COARSE_SIDE);
        coarse = &coarse_space;
    }
    const double slack_slope = descent && !adaptive ? DESCENT_SLACK_SLOPE : 0.0;
    const Index iterations = descent ? DESCENT_NEWTON_ITERATIONS : NEWTON_ITERATIONS_MAX;
    bool converged = false;
    bool residual_ready = false;  // the line search leaves the residual at its end in rhs
    double previous = 0.0;
    double correction = 0.0;  // m/s, the last iteration's
    // A support met within a fixed step has no normal force at its start, so no friction: its particle landed
    // frictionless (a sheet released onto an incline kept the whole step's slide along it).  Its normal force
    // is lagged from the first Newton iterate at which it presses instead (IPC's lag), held from then on unless
    // a converged solve ends with it apart (drop_departed).
    const bool lags_arrivals = !adaptive && solver.supports != nullptr && solver.supports->any_friction;
    //: Whether supports met at the iterate got their normal force (the potential changed, and the solve goes on;
    //: a residual in hand, the line search's, takes their friction).
    const auto lagged = [&]() {
        if (!(lags_arrivals && lag_arriving_normal_force(*solver.supports, n, mass, vel, out_pos, out_vel, h,
                                                         work.force, work.blocks) > 0)) {
            return false;
        }
        if (residual_ready) residual_of_force(cloth, work, solver, hat_vel, out_vel, bh);
        previous = 0.0;
        return true;
    };
    //: The supports' friction changed at the iterate: its residual anew, from which the solve goes on.
    const auto friction_changed = [&]() {
        newton_residual(cloth, phys, work, solver, hat_vel, step_water, out_pos, out_vel, bh, slack_slope);
        residual_ready = true;
        previous = 0.0;
        return true;
    };
    //: Whether supports lagged within the step that the iterate leaves not pressing lost their friction.  Only
    //: where the solve converged: an iterate its energy test let stand is no solution to judge the contact by
    //: (after a restart from rest, the tablecloth_sphere's solve at frame steps dropped 83 of the ball's terms
    //: there, and its frame's estimated error rose from 16 to 72 mm, bench/frame_steps.py).
    const auto departed = [&]() {
        return lags_arrivals && drop_departed(*solver.supports, n, out_pos) > 0 && friction_changed();
    };
    //: Whether the layers' normal forces at the iterate the solve would stop at are taken again
    //: (relag_self_normal_force).
    const auto relagged = [&]() {
        return !adaptive && solver.supports != nullptr && relag_self_normal_force(*solver.supports, n, out_pos) &&
               friction_changed();
    };
    const auto iterate = [&]() {
        for (Index iteration = 0; iteration < iterations; ++iteration) {
            lagged();
            if (!residual_ready) {
                newton_residual(cloth, phys, work, solver, hat_vel, step_water, out_pos, out_vel, bh, slack_slope);
            }
            if (!adaptive) {  // the frame where the step ends (a frame-long step turns the cloth)
                follow_cloth(plane, cloth, out_pos);
                set_systems_from_jacobian(plane, cloth, mass, work);
                if (coarse != nullptr && iteration < COARSE_BUILDS) {  // (turns about the centres there)
                    build_coarse_space(*coarse, cloth, mass, work, out_pos);
                }
                solver.counters[FACTORISATIONS] += 1;
            } else {
                if (jacobian_refresh_pays(plane, memory[3]) || buckling_mesh_refresh_pays(plane, cloth, memory[3])) {
                    factored = refresh_from_jacobian(plane, cloth, mass, is_mesh(cloth) ? work.pair_along : work.along);
                    if (factored < 0) factored = refresh(plane, cloth, mass, bh * bh);  // back to the rest stiffness
                    solver.counters[FACTORISATIONS] += factored > 0;
                }
                set_normal_diagonal(plane, n, mass, work.diagonal_blocks, work.blocks);
                if (reused != nullptr) {
                    if (reuse_expired(*reused, bh * bh, memory[3])) {
                        if (long_solve(memory[3])) {
                            build_reused(*reused, cloth, mass, work, out_pos, bh * bh);
                            solver.counters[FACTORISATIONS] += 1;
                        } else {
                            drop_reused(*reused);
                        }
                    }
                    solving = in_use(*reused) ? &reused->plane : &plane;
                }
            }
            const double floor = CG_FLOOR * py_min(newton_tolerance / bh, newton_tolerance / NEWTON_VELOCITY_TIME);
            const bool truncated = descent && !adaptive && iteration > 0 && coarse != nullptr &&
                                   moves_freely(cloth, work, solver);
            const Index cg_limit = truncated ? DESCENT_LATER_CG_ITERATIONS : NEWTON_CG_ITERATIONS;
            const PlaneSolve solve = plane_pcg(cloth, work, solver, *solving, rhs, dv, cg_tolerance, floor, cg_limit,
                                               coarse);
            memory[3] = static_cast<double>(solve.iterations);
            if (reused != nullptr && in_use(*reused)) count_reused_solve(*reused, solve.iterations);
            solver.counters[NEWTON_ITERATIONS] += 1;
            solver.counters[CG_ITERATIONS] += solve.iterations;
            solver.counters[UNCONVERGED] += !solve.solved;
            double length = 1.0;  // of the step along dv
            if (descent) {
                length = line_search(cloth, phys, work, solver, hat_pos, hat_vel, step_water, bh,
                                     slack_slope, dv, solver.step_acceleration, out_pos, out_vel);
                residual_ready = true;
            } else {
                for (Index k = 0; k < 3 * n; ++k) {
                    out_vel[k] += dv[k];
                    out_pos[k] = hat_pos[k] + bh * out_vel[k];
                }
            }
            const Corrections measured = corrections(n, length, dv, out_vel, vel);
            const double largest = measured.largest;
            const double increment = measured.increment;
            correction = largest;
            if (!std::isfinite(largest)) break;
            if (descent && !adaptive && energy_settled(n, mass, free, out_vel, hat_vel, rhs) &&
                !(iteration + 1 < iterations && (lagged() || relagged()))) {
                break;
            }
            // The velocity's tolerance: an error left in every step's velocity is not random and adds up, so
            // it is held to a fraction of the velocity and of its change over the step, or to what moves a
            // particle by the position tolerance in NEWTON_VELOCITY_TIME.
            const double velocity_tolerance =
                py_max(NEWTON_RELATIVE * increment, newton_tolerance / NEWTON_VELOCITY_TIME);
            const double tolerance = py_min(newton_tolerance / bh, velocity_tolerance);
            // Converged when the correction, or the corrections still to come at the observed rate (a
            // geometric series), are within the tolerance.
            double rate, trust;
            if (previous > 0.0) {
                rate = largest / previous;
                trust = 1.0;
                memory[0] = rate;
                memory[1] = previous;
            } else {  // first iteration: the rate last observed, scaled to this correction, with a margin
                rate = memory[1] > 0.0 ? memory[0] * py_max(1.0, largest / memory[1]) : 0.0;
                trust = banded(plane) ? FIRST_ITERATION_TRUST : 0.0;
            }
            if (largest <= tolerance || (0.0 < rate && rate < 1.0 && rate / (1.0 - rate) * largest <= trust * tolerance)) {
                if (iteration + 1 < iterations && (lagged() || departed() || relagged())) continue;
                converged = true;
                break;
            }
            previous = largest;
        }
    };
    iterate();
    // A frame-long step in contact may converge to a worse local minimum of its (non-convex) incremental
    // potential, one above the energy the step started with: a sheet landing on a box within a 1/24 s step
    // ended with its overhang in free fall and the corners' springs stretched, 0.078 J gained.  Where the
    // potential at the solve's end lies above its value at rest (x+ = x), the solve starts again from the
    // lowest point on the segment between them.
    if (descent && !adaptive && solver.supports != nullptr && solver.supports->count() > 0) {
        double* rest = solver.p;
        double* toward = solver.r;
        for (Index restart = 0; restart < DESCENT_RESTARTS && std::isfinite(correction); ++restart) {
            velocities_at_rest(cloth, solver, n, pos, hat_pos, h, bh, out_vel, rest);
            if (potential_rise(cloth, phys, work, solver, hat_pos, hat_vel, step_water, bh, slack_slope, rest, out_pos,
                               out_vel, toward) <= 0.0) {
                break;
            }
            solver.counters[RESTARTS] += 1;
            for (Index k = 0; k < 3 * n; ++k) {
                out_vel[k] = rest[k];
                out_pos[k] = hat_pos[k] + bh * out_vel[k];
            }
            newton_residual(cloth, phys, work, solver, hat_vel, step_water, out_pos, out_vel, bh, slack_slope);
            // Rising from rest toward the solve's end, rest is that lowest point (the line search, which takes
            // the full step where its first slope does not fall, would go back to the end).
            if (dot(n, toward, solver.rhs) > 0.0) {
                line_search(cloth, phys, work, solver, hat_pos, hat_vel, step_water, bh, slack_slope, toward,
                            solver.step_acceleration, out_pos, out_vel);
            }
            residual_ready = true;
            converged = false;
            previous = 0.0;
            iterate();
        }
    }
    if (solver.sliding != nullptr) stop_reversed(*solver.sliding, n, hat_pos, bh, out_pos, out_vel);
    for (Index k = 0; k < 3 * n; ++k) solver.step_acceleration[k] = (out_vel[k] - hat_vel[k]) / bh;
    // Descent never fails: a solve stopped short of its tolerance is taken, what it left unsolved added to
    // the estimate, so that the user sees what it cost: the corrections still to come (m) at the rate its
    // last two observed (the convergence test's geometric series), or the last correction itself without
    // a rate below 1.  (The last correction alone overstated the hanging sheet's frame error up to 12-fold.)
    double unsolved = 0.0;
    if (!converged) {
        const double rate = previous > 0.0 ? correction / previous : 1.0;
        unsolved = bh * correction * (rate < 1.0 ? rate / (1.0 - rate) : 1.0);
    }
    if (descent && std::isfinite(correction)) converged = true;
    if (history) {
        memory[2] = better_guess(n, vel, prev_vel, acceleration, free, h, h_prev, out_vel);
    } else {
        double error = 0.0;
        for (Index k = 0; k < 3 * n; ++k) error = py_max(error, std::fabs(out_vel[k] - vel[k]));
        return {0.5 * h * error + unsolved, converged};
    }
    // The difference, filtered through (approximately) A^-1 M, as Shampine filters the error estimates
    // of stiff solvers: stiff modes (in-plane vibration, a floating cloth's heave), which the scheme
    // damps anyway, would otherwise dominate the estimate and hold the step far below what the smooth
    // motion needs.  Through the rest-stiffness systems (`plane`), never the reused Jacobian ones: a
    // filter that changed with each rebuild of those would move the steps.
    double* difference = solver.r;
    for (Index c = 0; c < 3; ++c) {
        for (Index i = 0; i < n; ++i) {
            const Index k = c * n + i;
            difference[k] = free[i] * mass[i] * (out_pos[k] - predicted[k]);
        }
    }
    // A pressing support sets its particles' motion along its normal, which the estimate leaves out (as the
    // floor's): without, the sweep's mesh ball (advanced a second at a time, the supports at e/2) took 6916
    // steps and 1895 retaken, with 5522 and 1175.
    if (solver.supports != nullptr) project_supported(*solver.supports, n, difference);
    apply(plane, n, free, difference, solver.z);
    return {(1.0 + w) / (2.0 + 3.0 * w) * largest_of(n, solver.z) + unsolved, converged};
}

}  // namespace wc
