// The self-collision stage's response (port of bf41571:fmu_src/wetcloth/kernels/self_contact/response.py): settling passes
// that push layers apart to the thickness with friction, then rigid impact zones (Bridson, Fedkiw and
// Anderson 2002).  The entry point, resolve(), is declared in wetcloth/self_contact.hpp.
#pragma once

#include "wetcloth/core.hpp"
#include "wetcloth/self_contact/geometry.hpp"

namespace wc::self_contact {

//: Settling passes over the candidates per step (each pass treats every pair that needs it).
inline constexpr int PASSES_MAX = 8;
//: A pair whose end distance is within this fraction below the thickness is left alone (with adaptive steps;
//: at fixed steps, whose solve holds the pairs, within 1 - KEPT_FRACTION: see Contact::layers_solved).
inline constexpr double SLACK = 0.01;
//: The safe minimum distance of a pair along the step: this fraction of the thickness, or half the pair's
//: distance at the start of the step if that is less.
inline constexpr double SAFE_FRACTION = 0.1;
//: The least distance, as a fraction of the thickness, to which kept_distance pushes a pair back.  At 0.5 the
//: `bucket` towel bunched against the wall by an 8.25 m/s current (bench/violent_frames.py) took 1.5 times the
//: time (14M pushes in 0.5 s, the settling passes at their limit in every step, against 0.6M): layers left that
//: close lie within each other's reach, and the current presses them in every step.  At 0.9 its adaptive run takes
//: about the time it took with every push to the thickness (5.6M pushes but 24k steps instead of 31k), its run at
//: frame steps 1.2 times.  At fixed steps, whose solve held the listed pairs with its penalty (self_contact/
//: supports.hpp), a pair it left at least this fraction of the thickness apart is not pushed at all: the solve
//: found it in balance there, and pushing it back to where it started undid each step's settling.  The crumpled
//: pile of bench/self_collision.py (--pile-only) then gained energy in its pushes in a third to half of its
//: steps for ever (taken again in halves, 90-300 tries a simulated second on the floor); now it comes to rest at
//: one step a frame.
inline constexpr double KEPT_FRACTION = 0.9;
//: How far apart (m) a push sets a pair that ends the step closer than (1 - SLACK) `thickness` without meeting on
//: the way: the thickness, unless the pair started the step closer; then back to its distance at the start (at
//: least KEPT_FRACTION of the thickness).  Lifting layers that lie closer than the thickness apart is work no
//: force did: at fixed frame steps, where a step that gains energy is taken again in halves, a crumpled pile's
//: pushes to the thickness gained energy at nearly every step (docs/model.md 6.2).  (A slack below this distance
//: too would let resting layers creep closer by up to SLACK of it in every step, as many times as the steps
//: are short: the towel folded by a current then ended 2.5 mm from its run at 1/100 the tolerance, 0.26 mm now.)
inline double kept_distance(double start_distance, double thickness) {
    return py_min(thickness, py_max(start_distance, KEPT_FRACTION * thickness));
}
//: A particle within this fraction of the thickness above the floor is on it (see push_apart).
inline constexpr double ON_FLOOR = 0.01;
//: Candidate lists rebuilt (when the treatment moved particles beyond the list's margin) at most this many
//: times per step; after that the step's motion is undone (counted: seen only in hostile trials, e.g. 23 times in
//: 3.1 s where a turning cylinder drags a pinned towel at frame steps; stepping.cpp then takes a fixed step longer
//: than SUBSTEP_LEAST of max_step again in halves).
inline constexpr int ATTEMPTS = 6;

//: Rows of Contact::zone_sums per zone root: mass; mass-weighted start position (3) and motion (3);
//: whether held; angular momentum (3); inertia (xx, yy, zz, xy, xz, yz); rotation over the step (3); the
//: motion of its pinned particles (3) and whether it has any; members.
enum ZoneRow : Index {
    MASS = 0, POS = 1, MOVE = 4, HELD = 7, MOMENT = 8, INERTIA = 11, SPIN = 17, CARRY = 20, PINNED = 23, MEMBERS = 24
};
static_assert(MEMBERS + 1 == ZONE_ROWS, "Contact::zone_sums rows");

//: The inverse masses (1/kg) of a pair's four particles (0: pinned, held or immovable).
struct Inverse {
    double m[4];
    double sum() const { return m[0] + m[1] + m[2] + m[3]; }
};

//: When along the step a pair must be treated (a fraction of it), or CLEAR; and whether it can come
//: within its distance at all.
struct ContactTime {
    double when;
    bool near;
};

//: Whether a pair `start` (m) apart whose points move by p[0..3] surely stays `gap` (m) apart, as contact_time's
//: motion bound shows, without its square roots: that bound is at most twice the largest motion from the
//: mean (the same mean, to the bit).  (With a relative margin of 1e-6, and only where start - gap is not lost
//: in start's rounding, so that the bound would show it too.)
inline bool surely_apart(const Vec3 p[4], double start, double gap) {
    const double room = start - gap;
    if (!(room > 1e-9 * start)) return false;
    const Vec3 mean = mean_motion(p[0], p[1], p[2], p[3]);
    double largest = 0.0;  // (NaN once a motion is: then not surely apart)
    for (int k = 0; k < 4; ++k) {
        const double squared = dot(sub(p[k], mean), sub(p[k], mean));
        largest = squared > largest || squared != squared ? squared : largest;
    }
    return 4.0 * (1.0 + 1e-6) * largest < room * room;
}

//: The ContactTime of a pair of kind `kind` whose points x[0..3] move by p[0..3] over the step, `start`
//: (m) apart at its start, to be kept `gap` (m) apart: near unless its motion bound cannot take it within
//: gap; when from time_of_contact (within_step passed on), down to SAFE_FRACTION of gap (or half of
//: start, if less).
inline ContactTime contact_time(int kind, const Vec3 x[4], const Vec3 p[4], double start, double gap,
                                bool within_step = false) {
    if (surely_apart(p, start, gap) || start - motion_bound(kind, p[0], p[1], p[2], p[3]) >= gap) return {CLEAR, false};
    const double minimum = py_min(SAFE_FRACTION * gap, 0.5 * start);
    return {time_of_contact(kind, x[0], x[1], x[2], x[3], p[0], p[1], p[2], p[3], start, minimum, within_step),
            true};
}

//: Move the end positions x1 (3, n) of the pair's particles idx so that its separation along `normal`
//: (closest-point weights kept) is `target` (m); then remove its approaching velocity (v1 (3, n), m/s) and
//: apply Coulomb friction.  A particle on the floor (or that the push would take below floor_z) takes no
//: share of a push downwards, nor one lying on a collider (supported (3, n): its outward normal, zero if none;
//: null: none) of a push into it.  (Where the collider's particles moved, a sheet sliding frictionless on a
//: layer that a plane held took 3-8 times the pushes of a pinned one, each carrying the layer into the plane and
//: back, and slid 0.78x as far: bench/layer_friction.py.)
void push_apart(const Index idx[4], const Weights& weights, const Vec3& normal, double target,
                const Inverse& inverse, double friction, double floor_z, Index n, double* x1, double* v1,
                const double* supported = nullptr);

//: Whether the step's blow-up guard will refuse it: a value not finite, or a particle at blow_up_speed
//: (m/s) or faster.
bool refused(Index n, const double* x1, const double* v1, double blow_up_speed);

}  // namespace wc::self_contact
