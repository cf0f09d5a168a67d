// The self-collision stage of a step (docs/model.md section 6.2; port of
// bf41571:fmu_src/wetcloth/kernels/self_contact/response.py): after the integrator and the floor have moved the cloth from
// x0 to x1 (velocities v1), make the motion free of self-intersection and push layers apart to the
// thickness.
//
// Each candidate pair is examined along the step's straight-line motion.  A pair whose motion may bring it
// closer than a safe minimum distance (time_of_contact) is treated in the configuration just before that
// contact, where its normal says which side each element is on; a pair that ends the step closer than the
// thickness without such a contact is treated in its end configuration.  Treating it moves the end
// positions apart along that normal to the thickness (in proportion to the inverse masses and the closest
// points' weights; a particle on the floor is not pushed into it; a pair treated in its end configuration
// that started the step closer than the thickness only back to its start distance, kept_distance; after a
// solve that held the pairs, Contact::layers_solved, only pairs it left closer than KEPT_FRACTION of it), removes
// the pair's approaching velocity
// (an inelastic impulse) and reduces its sliding velocity by `friction` times the normal velocity removed
// (Coulomb).  A few passes settle stacked layers.  Pairs whose motion is still not shown safe then form
// rigid impact zones: each zone moves with its own linear and angular momentum, zones that still meet
// merge; a zone holding pinned particles moves with the grip, and one that the grip leaves still, or that would
// enter the floor, stays where it was.
#include "wetcloth/self_contact/response.hpp"

#include <cmath>

#include "wetcloth/grip.hpp"
#include "wetcloth/integration.hpp"
#include "wetcloth/self_contact.hpp"
#include "wetcloth/self_contact/broad_phase.hpp"
#include "wetcloth/self_contact/geometry.hpp"

namespace wc::self_contact {

namespace {

//: Candidate j of the whole list (point-triangle pairs first, then edge-edge): its kind and four particles.
struct Candidate {
    int kind;
    Index idx[4];
};

inline Candidate candidate(const Contact& contact, Index j) {
    const ContactLists& lists = *contact.lists;
    const Index pt = lists.point_triangle_count();
    if (j < pt) {
        const Index t = lists.point_triangle[pt + j];
        return {POINT_TRIANGLE,
                {lists.point_triangle[j], contact.triangles[3 * t], contact.triangles[3 * t + 1],
                 contact.triangles[3 * t + 2]}};
    }
    const Index ee = lists.edge_edge_count();
    const Index a = lists.edge_edge[j - pt], b = lists.edge_edge[ee + j - pt];
    return {EDGE_EDGE, {contact.edges[2 * a], contact.edges[2 * a + 1], contact.edges[2 * b], contact.edges[2 * b + 1]}};
}

inline Inverse inverse_masses(const Index idx[4], const double* mass, const double* free) {
    return {{free[idx[0]] / mass[idx[0]], free[idx[1]] / mass[idx[1]], free[idx[2]] / mass[idx[2]],
             free[idx[3]] / mass[idx[3]]}};
}

inline Vec3 motion(const double* x0, const double* x1, Index n, Index i) {
    return {x1[i] - x0[i], x1[n + i] - x0[n + i], x1[2 * n + i] - x0[2 * n + i]};
}

//: Each candidate's distance (m) at the start of the step (in the order of candidate()).
void start_distances(const Contact& contact, Index n, const double* x0, Index count, double* out) {
    for (Index j = 0; j < count; ++j) {
        const Candidate p = candidate(contact, j);
        out[j] = distance(p.kind, point(x0, n, p.idx[0]), point(x0, n, p.idx[1]), point(x0, n, p.idx[2]),
                          point(x0, n, p.idx[3]));
    }
}

//: The ContactTime of candidate particles idx, start_distance (m) apart at the step's start, to be kept
//: `thickness` apart over the step from x0 to x1.
inline ContactTime contact_time(int kind, const Index idx[4], double start_distance, double thickness, Index n,
                                const double* x0, const double* x1) {
    Vec3 x[4], p[4];
    for (int k = 0; k < 4; ++k) {
        x[k] = point(x0, n, idx[k]);
        p[k] = motion(x0, x1, n, idx[k]);
    }
    return contact_time(kind, x, p, start_distance, thickness);
}

//: Particle k's inverse mass in a push, 0 if it is held (bit k of `held`).
inline double share(const Inverse& inverse, int held, int k) { return (held >> k) & 1 ? 0.0 : inverse.m[k]; }

}  // namespace

void push_apart(const Index idx[4], const Weights& weights, const Vec3& normal, double target,
                const Inverse& inverse, double friction, double floor_z, Index n, double* x1, double* v1,
                const double* supported) {
    const double w[4] = {weights.w0, weights.w1, weights.w2, weights.w3};
    const double nx = normal.x, ny = normal.y, nz = normal.z;
    double* x1x = x1;
    double* x1y = x1 + n;
    double* x1z = x1 + 2 * n;
    int held = 0;  // bit k: particle k is on the floor and the push would take it down
    for (int k = 0; k < 4; ++k) {
        if (w[k] * nz < 0.0 && x1z[idx[k]] <= floor_z + ON_FLOOR * target) held |= 1 << k;
        if (supported != nullptr) {
            const Index i = idx[k];
            if (w[k] * (nx * supported[i] + ny * supported[n + i] + nz * supported[2 * n + i]) < 0.0) held |= 1 << k;
        }
    }
    double separation = 0.0;
    for (int k = 0; k < 4; ++k) {
        const Index i = idx[k];
        separation += w[k] * (x1x[i] * nx + x1y[i] * ny + x1z[i] * nz);
    }
    if (separation < target) {
        for (int attempt = 0; attempt < 4; ++attempt) {
            double weight = 0.0;
            for (int k = 0; k < 4; ++k) weight += w[k] * w[k] * share(inverse, held, k);
            if (weight <= 0.0) break;
            const double lam = (target - separation) / weight;
            int floored = held;
            for (int k = 0; k < 4; ++k) {
                const double dz = lam * w[k] * share(inverse, held, k) * nz;
                if (dz < 0.0 && x1z[idx[k]] + dz < floor_z) floored |= 1 << k;
            }
            if (floored == held) {
                for (int k = 0; k < 4; ++k) {
                    const Index i = idx[k];
                    const double s = lam * w[k] * share(inverse, held, k);
                    x1x[i] += s * nx;
                    x1y[i] += s * ny;
                    x1z[i] += s * nz;
                }
                break;
            }
            held = floored;
        }
    }
    double* v1x = v1;
    double* v1y = v1 + n;
    double* v1z = v1 + 2 * n;
    double weight = 0.0;
    double rx = 0.0, ry = 0.0, rz = 0.0;
    for (int k = 0; k < 4; ++k) {
        weight += w[k] * w[k] * share(inverse, held, k);
        const Index i = idx[k];
        rx += w[k] * v1x[i];
        ry += w[k] * v1y[i];
        rz += w[k] * v1z[i];
    }
    const double approach = rx * nx + ry * ny + rz * nz;
    if (approach >= 0.0 || weight <= 0.0) return;
    // Inelastic: the relative normal velocity becomes zero; friction takes up to `friction` times that
    // change off the relative sliding velocity, never reversing it.
    const double tx = rx - approach * nx, ty = ry - approach * ny, tz = rz - approach * nz;
    const double slide = std::sqrt(tx * tx + ty * ty + tz * tz);
    const double keep = slide > 0.0 ? py_min(1.0, friction * -approach / slide) : 0.0;
    for (int k = 0; k < 4; ++k) {
        const Index i = idx[k];
        const double s = w[k] * share(inverse, held, k) / weight;
        v1x[i] -= s * (approach * nx + keep * tx);
        v1y[i] -= s * (approach * ny + keep * ty);
        v1z[i] -= s * (approach * nz + keep * tz);
    }
}

namespace {

//: What settle_pair did with a pair: nothing (it needs nothing), pushed it apart, or left it to the impact
//: zones (its motion is not shown safe, but it has no side to be pushed to).
enum Settled { NOTHING = 0, PUSHED = 1, LEFT = 2 };

//: Treat one pair if it needs it (see the file's head).
Settled settle_pair(const Candidate& p, double start_distance, const Contact& contact, double thickness,
                    double floor_z, Index n, const double* mass, const double* free, const double* x0, double* x1,
                    double* v1) {
    const Index* idx = p.idx;
    const Inverse inverse = inverse_masses(idx, mass, free);
    if (inverse.sum() == 0.0) return NOTHING;
    const ContactTime ct = contact_time(p.kind, idx, start_distance, thickness, n, x0, x1);
    if (!ct.near) return NOTHING;
    const double when = ct.when;
    Vec3 a, b, c, d;
    if (when == CLEAR) {
        a = point(x1, n, idx[0]), b = point(x1, n, idx[1]), c = point(x1, n, idx[2]), d = point(x1, n, idx[3]);
    } else {
        a = along(point(x0, n, idx[0]), when, motion(x0, x1, n, idx[0]));
        b = along(point(x0, n, idx[1]), when, motion(x0, x1, n, idx[1]));
        c = along(point(x0, n, idx[2]), when, motion(x0, x1, n, idx[2]));
        d = along(point(x0, n, idx[3]), when, motion(x0, x1, n, idx[3]));
    }
    const Weights w = closest(p.kind, a, b, c, d);
    const Vec3 gap = combine(w, a, b, c, d);
    const double length = std::sqrt(gap.x * gap.x + gap.y * gap.y + gap.z * gap.z);
    const double left_alone = contact.layers_solved ? KEPT_FRACTION : 1.0 - SLACK;  // of the thickness
    if (when == CLEAR && length >= left_alone * thickness) return NOTHING;
    const double target = when == CLEAR ? kept_distance(start_distance, thickness) : thickness;
    if (when == CLEAR && length >= target) return NOTHING;
    if (!(length > 0.0)) return when == CLEAR ? NOTHING : LEFT;  // no side to push to
    const Vec3 normal = {gap.x / length, gap.y / length, gap.z / length};
    const std::vector<double>& supported = contact.lists->supported_normal;
    push_apart(idx, w, normal, target, inverse, contact.friction, floor_z, n, x1, v1,
               supported.empty() ? nullptr : supported.data());
    return PUSHED;
}

//: Passes over the candidates until none needs treatment (at most PASSES_MAX); `start` holds their
//: distances at the start of the step (start_distances).  Returns whether every pair's motion is shown safe
//: (a pass pushed none and left none to the impact zones).
//:
//: After the first pass a pair is checked again only if a push has moved one of its particles since its
//: last check: what a pair needs depends on its particles' end positions alone, so the others would find
//: what they found then, and the pushes are the same, in the same order, as when every pair is checked in
//: every pass.  (The crumpled towel of bench/self_collision.py: 6 passes a step over its 1300 pairs.)
bool settle(Contact& contact, double thickness, double floor_z, Index n, const double* mass, const double* free,
            const double* x0, double* x1, double* v1, Index count, const double* start) {
    std::vector<Index>& moved = contact.lists->settle_moved;      // (see ContactLists)
    std::vector<Index>& checked = contact.lists->settle_checked;
    moved.assign(static_cast<std::size_t>(n), 0);
    checked.assign(static_cast<std::size_t>(count), 0);
    Index clock = 0;  // pushes so far
    Index left = 0;   // pairs whose last check left them to the impact zones
    for (int pass = 0; pass < PASSES_MAX; ++pass) {
        contact.counters[PASSES] += 1;
        Index treated = 0;
        for (Index j = 0; j < count; ++j) {
            const Candidate p = candidate(contact, j);
            const Index* idx = p.idx;
            const Index last = checked[j] / 2;
            if (pass > 0 && moved[idx[0]] <= last && moved[idx[1]] <= last && moved[idx[2]] <= last &&
                moved[idx[3]] <= last) {
                continue;
            }
            left -= checked[j] % 2;
            const Settled done = settle_pair(p, start[j], contact, thickness, floor_z, n, mass, free, x0, x1, v1);
            checked[j] = 2 * clock + (done == LEFT);
            left += done == LEFT;
            if (done == PUSHED) {
                treated += 1;
                clock += 1;
                for (int k = 0; k < 4; ++k) moved[idx[k]] = clock;
            }
        }
        contact.counters[RESPONSES] += treated;
        if (treated == 0) return left == 0;
    }
    return false;
}

inline Index root(Index* parent, Index i) {
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

//: The zone's rotation over the step (h times its angular velocity) from root r's inertia and the angular
//: momentum of its members' displacements; a tiny multiple of the trace regularises zones that are nearly
//: a line.
inline Vec3 solve_inertia(const double* s, Index n, Index r) {
    double xx = s[INERTIA * n + r], yy = s[(INERTIA + 1) * n + r], zz = s[(INERTIA + 2) * n + r];
    const double xy = s[(INERTIA + 3) * n + r], xz = s[(INERTIA + 4) * n + r], yz = s[(INERTIA + 5) * n + r];
    const double eps = 1e-9 * (xx + yy + zz);
    xx += eps;
    yy += eps;
    zz += eps;
    const Adjugate a = symmetric_adjugate(xx, yy, zz, xy, xz, yz);
    const double lx = s[MOMENT * n + r], ly = s[(MOMENT + 1) * n + r], lz = s[(MOMENT + 2) * n + r];
    if (!(a.det > 0.0)) return {0.0, 0.0, 0.0};
    return {(a.c11 * lx + a.c12 * ly + a.c13 * lz) / a.det, (a.c12 * lx + a.c22 * ly + a.c23 * lz) / a.det,
            (a.c13 * lx + a.c23 * ly + a.c33 * lz) / a.det};
}

//: Give every zone (a root with members) the rigid motion of its members' linear and angular momentum over
//: the step: motion h (v + w x r) about the centre of mass, which never brings two points of a zone closer
//: along the straight-line path.  A zone holding pinned particles that the grip moves together moves with
//: them (the grip carries what it presses on; the pinned particles' velocities stay the grip's).  A zone
//: holding pinned particles that stay, or move apart (one the grip had left behind), or whose motion would
//: take a member below the floor, stays where it started (velocities zero).
void move_zones(Contact& contact, double floor_z, Index n, const double* mass, const double* free, const double* x0,
                double* x1, double* v1, double h) {
    Index* parent = contact.zone;
    double* s = contact.zone_sums;
    auto S = [s, n](Index row, Index i) -> double& { return s[row * n + i]; };
    for (Index i = 0; i < n; ++i)
        for (Index row = 0; row < ZONE_ROWS; ++row) S(row, i) = 0.0;
    for (Index i = 0; i < n; ++i) {
        const Index r = root(parent, i);
        const double m = mass[i];
        S(MEMBERS, r) += 1.0;
        S(MASS, r) += m;
        for (Index c = 0; c < 3; ++c) {
            S(POS + c, r) += m * x0[c * n + i];
            S(MOVE + c, r) += m * (x1[c * n + i] - x0[c * n + i]);
        }
        if (free[i] == 0.0) {  // pinned (the floor's and colliders' holds are released before the stage)
            for (Index c = 0; c < 3; ++c) {
                const double move = x1[c * n + i] - x0[c * n + i];
                if (S(PINNED, r) == 0.0) {
                    S(CARRY + c, r) = move;
                } else if (std::fabs(move - S(CARRY + c, r)) > GRIP_RESOLUTION) {
                    S(HELD, r) = 1.0;
                }
            }
            S(PINNED, r) = 1.0;
        }
    }
    for (Index i = 0; i < n; ++i) {
        if (parent[i] != i) continue;
        for (Index c = 0; c < 3; ++c) {
            S(POS + c, i) /= S(MASS, i);
            S(MOVE + c, i) /= S(MASS, i);
        }
    }
    for (Index i = 0; i < n; ++i) {
        const Index r = root(parent, i);
        const double m = mass[i];
        const double rx = x0[i] - S(POS, r), ry = x0[n + i] - S(POS + 1, r), rz = x0[2 * n + i] - S(POS + 2, r);
        const double ux = x1[i] - x0[i] - S(MOVE, r);
        const double uy = x1[n + i] - x0[n + i] - S(MOVE + 1, r);
        const double uz = x1[2 * n + i] - x0[2 * n + i] - S(MOVE + 2, r);
        S(MOMENT, r) += m * (ry * uz - rz * uy);
        S(MOMENT + 1, r) += m * (rz * ux - rx * uz);
        S(MOMENT + 2, r) += m * (rx * uy - ry * ux);
        S(INERTIA, r) += m * (ry * ry + rz * rz);
        S(INERTIA + 1, r) += m * (rx * rx + rz * rz);
        S(INERTIA + 2, r) += m * (rx * rx + ry * ry);
        S(INERTIA + 3, r) -= m * rx * ry;
        S(INERTIA + 4, r) -= m * rx * rz;
        S(INERTIA + 5, r) -= m * ry * rz;
    }
    for (Index i = 0; i < n; ++i) {
        if (parent[i] == i) {
            const Vec3 spin = solve_inertia(s, n, i);  // from displacements: h times the angular velocity
            S(SPIN, i) = spin.x, S(SPIN + 1, i) = spin.y, S(SPIN + 2, i) = spin.z;
            const bool carried = S(CARRY, i) != 0.0 || S(CARRY + 1, i) != 0.0 || S(CARRY + 2, i) != 0.0;
            if (S(PINNED, i) != 0.0 && !carried) S(HELD, i) = 1.0;  // a still grip holds its zone where it was
        }
    }
    for (Index i = 0; i < n; ++i) {
        const Index r = root(parent, i);
        if (S(MEMBERS, r) == 1.0) continue;  // a particle in no zone
        const double rx = x0[i] - S(POS, r), ry = x0[n + i] - S(POS + 1, r);
        const double dz =
            S(PINNED, r) != 0.0 ? S(CARRY + 2, r) : S(MOVE + 2, r) + S(SPIN, r) * ry - S(SPIN + 1, r) * rx;
        if (x0[2 * n + i] + dz < floor_z) S(HELD, r) = 1.0;
    }
    for (Index i = 0; i < n; ++i) {
        const Index r = root(parent, i);
        if (S(MEMBERS, r) == 1.0) continue;
        if (S(HELD, r) != 0.0) {
            for (Index c = 0; c < 3; ++c) {
                x1[c * n + i] = x0[c * n + i];
                v1[c * n + i] = 0.0;
            }
            continue;
        }
        const double rx = x0[i] - S(POS, r), ry = x0[n + i] - S(POS + 1, r), rz = x0[2 * n + i] - S(POS + 2, r);
        const bool carried = S(PINNED, r) != 0.0;  // moved with its pinned particles, without turning
        const double wx = carried ? 0.0 : S(SPIN, r), wy = carried ? 0.0 : S(SPIN + 1, r),
                     wz = carried ? 0.0 : S(SPIN + 2, r);
        const double* shift = carried ? &S(CARRY, r) : &S(MOVE, r);
        const double move[3] = {shift[0 * n] + wy * rz - wz * ry, shift[1 * n] + wz * rx - wx * rz,
                                shift[2 * n] + wx * ry - wy * rx};
        for (Index c = 0; c < 3; ++c) {
            v1[c * n + i] += (move[c] - (x1[c * n + i] - x0[c * n + i])) / h;
            x1[c * n + i] = x0[c * n + i] + move[c];
        }
    }
}

//: Merge the particles of every pair whose motion is not shown safe into rigid zones until none is left
//: (each round merges at least two zones, so this ends).
void impact_zones(Contact& contact, double thickness, double floor_z, Index n, const double* mass,
                  const double* free, const double* x0, double* x1, double* v1, double h, Index count,
                  const double* start) {
    Index* parent = contact.zone;
    for (Index i = 0; i < n; ++i) parent[i] = i;
    for (Index round = 0; round < n; ++round) {
        Index unsafe = 0;
        for (Index j = 0; j < count; ++j) {
            const Candidate p = candidate(contact, j);
            const Index* idx = p.idx;
            const Index r = root(parent, idx[0]);
            if (r == root(parent, idx[1]) && r == root(parent, idx[2]) && r == root(parent, idx[3]))
                continue;  // inside one zone: its rigid motion keeps it apart
            if (inverse_masses(idx, mass, free).sum() == 0.0) continue;
            if (contact_time(p.kind, idx, start[j], thickness, n, x0, x1).when == CLEAR) continue;
            unsafe += 1;
            for (int other = 1; other < 4; ++other) {
                const Index a = root(parent, idx[0]), b = root(parent, idx[other]);
                if (a != b) parent[a > b ? a : b] = a < b ? a : b;
            }
        }
        if (unsafe == 0) return;
        contact.counters[ZONE_ROUNDS] += 1;
        move_zones(contact, floor_z, n, mass, free, x0, x1, v1, h);
    }
}

}  // namespace

//: The stage leaves a refused step alone, so that neither its rigid zones nor its last resort hide a
//: blow-up from the guard.
bool refused(Index n, const double* x1, const double* v1, double blow_up_speed) {
    const double limit = blow_up_speed * blow_up_speed;
    for (Index i = 0; i < n; ++i) {
        const double v2 = v1[i] * v1[i] + v1[n + i] * v1[n + i] + v1[2 * n + i] * v1[2 * n + i];
        if (!(v2 < limit && std::isfinite(x1[i] + x1[n + i] + x1[2 * n + i]))) return true;
    }
    return false;
}

}  // namespace wc::self_contact

namespace wc {

//: Nothing to do, and two passes over the positions (more while the cloth turns), while no pair is near.
//: A step that the blow-up guard will refuse (checked only where there is work) is left alone.  Returns
//: whether it changed x1 or v1: the step's motion then has a kink that a multistep integrator must not
//: extrapolate.
bool resolve(Contact& contact, double thickness, double floor_z, double blow_up_speed, Index n, const double* mass,
             const double* free, const double* x0, double* x1, double* v1, double h) {
    using namespace self_contact;
    if (!contact.enabled) return false;
    const Index treated = contact.counters[RESPONSES] + contact.counters[ZONE_ROUNDS];
    for (int attempt = 0; attempt < ATTEMPTS; ++attempt) {
        if (expired(contact, n, x0, x1)) {
            if (refused(n, x1, v1, blow_up_speed) || !rebuild_for_step(contact, n, thickness, x0, x1)) return false;
        }
        const Index candidates = candidate_count(contact);
        if (candidates == 0) return contact.counters[RESPONSES] + contact.counters[ZONE_ROUNDS] != treated;
        if (refused(n, x1, v1, blow_up_speed)) return false;
        contact.counters[BUSY_STEPS] += 1;
        std::vector<double>& scratch = contact.lists->scratch;
        if (static_cast<Index>(scratch.size()) < candidates) scratch.resize(static_cast<std::size_t>(candidates));
        double* start = scratch.data();
        start_distances(contact, n, x0, candidates, start);
        // (Where settling showed every pair safe, the impact zones' first round would find none unsafe.)
        if (!settle(contact, thickness, floor_z, n, mass, free, x0, x1, v1, candidates, start)) {
            impact_zones(contact, thickness, floor_z, n, mass, free, x0, x1, v1, h, candidates, start);
        }
        if (covers(contact, n, x0, x1)) return contact.counters[RESPONSES] + contact.counters[ZONE_ROUNDS] != treated;
    }
    // The treatment kept moving particles beyond every list built for it: undo the step's motion.
    contact.counters[FREEZES] += 1;
    for (Index k = 0; k < 3 * n; ++k) {
        x1[k] = x0[k];
        v1[k] = 0.0;
    }
    return true;
}

}  // namespace wc
