// Implicit steps: BDF2 and backward Euler, both by Newton iterations (BDF2 a port of
// bf41571:fmu_src/wetcloth/kernels/implicit.py).
//
// Both solve systems with the matrix A = M - h' dF/dv - h'^2 dF/dx (h' the step times the scheme's
// coefficient), which forces_and_blocks (assembly.hpp) leaves as per-particle and per-spring blocks;
// compressed springs contribute no negative stiffness, so A is symmetric positive definite.
#pragma once
#include <cmath>

#include "wetcloth/core.hpp"

namespace wc {

//: BDF2: at most this many Newton iterations, each a conjugate-gradient solve until the error left in
//: the correction is estimated below CG_TOLERANCE of the correction, or below CG_FLOOR of the Newton
//: tolerance (at most NEWTON_CG_ITERATIONS iterations).  The floor keeps tiny corrections from being
//: solved to round-off; it must stay small, since an error left in every step's velocity is not random
//: and adds up over the run.
inline constexpr Index NEWTON_ITERATIONS_MAX = 8;
//: Newton stops when the velocity correction is below NEWTON_RELATIVE of the fastest particle's speed
//: and velocity change (or below the position tolerance over NEWTON_VELOCITY_TIME s) and moves
//: positions by less than the position tolerance.
inline constexpr double NEWTON_RELATIVE = 1e-3;
inline constexpr double NEWTON_VELOCITY_TIME = 1.0;
//: After its first iteration Newton has no convergence rate of its own yet.  It borrows the rate last
//: observed (in an earlier step), scaled up by how much larger its correction is than the one that
//: rate followed (Newton's rate grows in proportion to the correction: Deuflhard's affine-invariant
//: model), and stops if the corrections still to come at that rate are within FIRST_ITERATION_TRUST of
//: the tolerance (a borrowed rate is a guess, hence the margin).  Measured (docs/benchmarks.md): on a
//: floating 9 x 9 cloth's 2 ms steps, 40 % fewer Newton and CG iterations; at 1.0, or without the
//: scaling, the sinking reference scene's wet mass erred by 1.2e-3 or 9.5e-4 (6.3e-4 before).  Only
//: with the banded preconditioner: with the multigrid cycle's inexact solves the floating 64 x 64
//: towel's accepted first iterates made its later steps fail their error test.
inline constexpr double FIRST_ITERATION_TRUST = 0.3;
//: Newton converges only linearly (its Jacobian is approximate: drag lumped, tension-only springs
//: clamped; each iteration cut the correction 2.5-3x on a sinking 9 x 9 cloth at 0.05 s steps), so
//: solving each correction much more closely than that rate is wasted: 1e-1 took 10-13 % less time
//: than 1e-2 on sink_map at the same accuracy; at 2e-1 the landing scene's centroid erred 0.72 mm
//: instead of 0.19-0.24 (bench/work_precision.py).  With fixed steps no error estimate watches the
//: steps: their solves go to FIXED_STEP_CG_TOLERANCE (at 1e-1 the 4 s sinking reference at 0.25 ms
//: steps and the same at half the step differed by 0.17 mm in centroid, at 1e-2 by 0.03 mm).
inline constexpr double CG_TOLERANCE = 1e-1;
inline constexpr double FIXED_STEP_CG_TOLERANCE = 1e-2;
inline constexpr double CG_FLOOR = 1e-2;
inline constexpr Index NEWTON_CG_ITERATIONS = 300;
//: How adaptive_cg_tolerance tightens with the overdamping D.  The hanging sheet swung 1 s at the default
//: tolerance against one 100 times tighter, at damping 100 to 1e5 N s/m: with the base tolerance the
//: 21 x 21 sheet erred 1.3-839 mm (at 1e5 it rose 0.8 m over the other's path) and the 11 x 11 0.8-55 mm;
//: with D^1 0.2-0.5 mm and 0.5-5.0 mm; with D^1.5 0.2-0.5 mm both (bench/overdamped.py).
inline constexpr double OVERDAMPED_EXPONENT = 1.5;

//: The relative tolerance of an adaptive step's linear solves: `base` divided by the step's overdamping
//: D = h gamma / (1 + h^2 omega^2) (Control's damping_rate gamma and omega_squared) to the power
//: OVERDAMPED_EXPONENT, where D exceeds 1.  Over h, D peaks at gamma / (2 omega), the damping ratio of
//: the stiffest springs' mode, so only overdamped springs tighten it (every preset's ratio is at most
//: 1.02).  There the damped stretch dominates the step's matrix and the residual's first value, and a
//: solve stopped at a tenth of that leaves the slow motion (the cloth swinging on its pins) unsolved,
//: unseen by Newton's corrections and the error estimate (docs/model.md section 7).  Fixed steps keep
//: theirs: their preconditioner, from the Jacobian, holds the damping.
inline double adaptive_cg_tolerance(double base, const Control& control, double h) {
    const double overdamping = h * control.damping_rate / (1.0 + h * h * control.omega_squared);
    return overdamping > 1.0 ? base / std::pow(overdamping, OVERDAMPED_EXPONENT) : base;
}

//: How bdf2_step builds its preconditioner.  ADAPTIVE (an error estimate watches the steps, tolerance
//: > 0): the rest-stiffness factors, reused across steps and refreshed from the Jacobian when solves
//: grow long (banded grids); with a ReusedPlane (multigrid grids) the solves use its in-plane systems
//: from the Jacobian instead, the error estimate still the rest-stiffness factors'.  FIXED (tolerance 0, steps possibly a frame long): from the Jacobian at every Newton
//: iteration.
enum class NewtonMode : int { ADAPTIVE = 0, FIXED = 1 };

//: With `descent` (backward Euler, integrator implicit_euler) Newton descends the step's incremental
//: potential: a line search along each correction, at most DESCENT_NEWTON_ITERATIONS iterations, and
//: the last iterate is taken whether converged or not (what is left unsolved goes into the error
//: estimate): its steps never fail.
//: Frame-long steps start far from their solution, where the tension-only springs' Jacobian misleads
//: Newton: a slack spring has no stiffness in it, so the first correction of a sheet released
//: horizontal is free fall, which the pinned edge's springs then hold back with their whole stiffness,
//: and full corrections oscillate without converging.  Descent with fixed steps counts every tension-only
//: spring in its Newton matrix as at least DESCENT_SLACK_SLOPE taut along itself (a majorant of the
//: Jacobian; with adaptive steps, which start close to their solution, it would only slow the last
//: iterations: a hanging cloth kept 1.3e-5 m/s of that noise after 3 s), and each
//: correction is cut by a line search on the incremental potential: false position on its slope along
//: the correction, at most LINE_SEARCH_EVALUATIONS residuals, stopping within LINE_SEARCH_SLOPE of the
//: first slope.  Measured on the hanging sheet at 1/30 s (bench/hanging_sheet.py; docs/benchmarks.md):
//: with 4 iterations the mechanical energy fell in every frame (41 x 41, 3 s; 81 x 81, 1 s), with 3 or 2
//: it rose by up to 0.33 and 0.49 J in a frame; building the preconditioner once per step instead of
//: at every iteration took 38 CG iterations per Newton iteration instead of 15, and 1.8x the time.
inline constexpr double DESCENT_SLACK_SLOPE = 1.0;
inline constexpr Index LINE_SEARCH_EVALUATIONS = 4;
inline constexpr double LINE_SEARCH_SLOPE = 0.1;
//: A false-position guess within this fraction of the bracket's width from either end is replaced by the
//: bracket's middle (line_search).
inline constexpr double LINE_SEARCH_GUARD = 0.1;
inline constexpr Index DESCENT_NEWTON_ITERATIONS = 4;
//: With fixed steps, descent stops before DESCENT_NEWTON_ITERATIONS once the step's energy has settled:
//: backward Euler's kinetic energy changes by v+ . M (v+ - v^) - 1/2 |v+ - v^|_M^2, of which the first
//: term is the work of the forces over the step plus that of the residual left unsolved, and the second
//: the scheme's own damping.  When the residual's work is at most this fraction of that damping, the
//: step cannot gain energy through it, however far Newton is from converged; what is left unsolved goes
//: into the error estimate as before.  Measured on the hanging sheet at 1/30 s (bench/hanging_sheet.py,
//: 81 x 81, 3 s): 2.3 Newton iterations a step instead of 4, 42 ms a frame instead of 70, the energy
//: still falling in every frame and the centroid 0.6 mm from where 4 iterations leave it.  (0.05: 2.6
//: iterations; 0.2: no fewer than at 0.1.)
inline constexpr double DESCENT_ENERGY_FRACTION = 0.1;
//: With fixed steps in contact (supports in the solve), at most this many fresh starts of descent from the
//: lowest point between rest and a solve that ended above the energy its step started with (bdf2_step).
inline constexpr Index DESCENT_RESTARTS = 3;
//: Descent's linear solves go to this tolerance (relative, as CG_TOLERANCE): with BDF2's 1e-1 a towel at
//: 1e6 N/m floating at 1/30 s steps gained energy from its unconverged steps and climbed 9 cm out of the
//: water in 2 s (8 Newton iterations did not help); at 3e-2 it floats (1.8 mm from its depth, 0.04 m/s
//: after 2 s).  The 81 x 81 hanging sheet's frames cost more (first 0.5 s: 17.3 CG per Newton iteration
//: instead of 14.3, 54 against 51 ms; over 3 s 28.6 against 20.3, 75 against 57 ms) and come far closer
//: to the converged motion (the centroid at 3 s 0.4 mm from the default's along y instead of 12 mm).
inline constexpr double DESCENT_CG_TOLERANCE = 3e-2;
//: With fixed steps on a grid (its coarse space in the preconditioner), descent's Newton iterations after the
//: first stop their linear solve after at most this many CG iterations while the cloth moves freely (a
//: truncated Newton step: CG's iterates from zero descend the step's quadratic model, and the line search takes
//: them only as far as the potential falls).  The first solve, which carries the step, still goes to
//: DESCENT_CG_TOLERANCE.  Where Newton needs more than two iterations (a swinging sheet's edge whipping), the
//: later residuals are what the preconditioner handles worst: the hanging 81 x 81 sheet spent 10-22 CG
//: iterations on each, for corrections that moved its end no better than 8 do.  In contact the later solves
//: carry the contact's response: truncated, a tablecloth on its table gained 0.016 J in a frame, the floating
//: towel ended 55 mm from the adaptive run instead of 46; on a mesh (algebraic multigrid, no coarse space) a
//: 2.5k-vertex disc hanging from its cap gained 0.19 J in a frame (0.05 untruncated) and swung over its pins.
inline constexpr Index DESCENT_LATER_CG_ITERATIONS = 8;

//: Kinds of Newton's first guess (memory[2]): the line through v_prev and v; the parabola through them
//: with the slope the last step implied at v.
inline constexpr double LINE = 0.0;
inline constexpr double PARABOLA = 1.0;

struct StepEstimate {
    double error;    // m, local position error estimate
    bool converged;  // whether Newton converged
};

//: One step of the variable-step BDF2 (backward Euler when h_prev == 0), preconditioned as mode says, by
//: descent or not; see implicit.cpp.
//: memory (4) carries over from step to step (clock slots NEWTON_RATE..LAST_SOLVE).  With grip_rate (3,
//: m/s), the pinned particles (free 0 and held 0 in held (n)) move at that velocity during the step
//: (grip.hpp); without, they stay where they are.  `reused` (adaptive steps only): reused_plane.hpp.
StepEstimate bdf2_step(const Cloth& cloth, const Physics& phys, Work& work, Solver& solver, Plane& plane,
                       const double* pos, const double* vel, const double* water, const double* step_water,
                       const double* prev_pos, const double* prev_vel, const double* prev_water,
                       const double* acceleration, double h, double h_prev, double newton_tolerance,
                       double cg_tolerance, NewtonMode mode, bool descent, double* memory, double* out_pos,
                       double* out_vel, const double* held = nullptr, const double* grip_rate = nullptr,
                       ReusedPlane* reused = nullptr);

}  // namespace wc
