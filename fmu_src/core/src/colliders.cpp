// Colliders (colliders.hpp; docs/model.md section 6.3): the floor's rule (floor.cpp) against a plane, an
// axis-aligned box, a sphere, a capped cylinder with a vertical axis or a triangle mesh (collider_mesh.cpp).
//
// Contact is resolved after the step, as floor_contact does: a particle that ends the step closer than
// gap (thickness / 2) to a collider is moved out along the outward normal, loses its velocity into the
// collider, and its sliding speed drops by friction times that loss.  A particle at rest on a collider is
// then held during the next step, as on the floor (hold_on_colliders), as long as the step's force keeps
// it within the friction cone (release_from_colliders).  A horizontal plane collider acts as the floor
// (tests/test_colliders.py compares the two).  (Limiting the step's tangential motion by friction times the depth as
// well, tried, took four times the steps for a cloth landing on a plane: the error estimate does not see
// it; the holding keeps a particle at rest on a slope still without it.)
#include "wetcloth/colliders.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "wetcloth/collider_mesh.hpp"
#include "wetcloth/collider_motion.hpp"
#include "wetcloth/floor.hpp"

namespace wc {

namespace {

//: A particle moves with a turning collider's surface if its velocity is within this fraction of the
//: surface's (rounding, as the step's end recomputes the collider's motion from its keys) beyond the
//: change of the surface's velocity over the last step's travel (hold_on_colliders).
constexpr double HOLD_SLACK = 1e-9;

//: A cylinder's normal within this of square to its axis (rounding of a turned one) lies on its side.
constexpr double SIDE_ROUNDING = 1e-9;

//: Particle i of pos (3, n) as a point.
std::array<double, 3> buf_point(Index n, Index i, const double* pos) { return {pos[i], pos[n + i], pos[2 * n + i]}; }

//: Distance to an axis-aligned box of half sizes half (3) centred at the origin, from offset d (3).
double box_distance(const double* d, const double* half, double* normal) {
    double q[3], outside2 = 0.0;
    Index widest = 0;
    for (Index c = 0; c < 3; ++c) {
        q[c] = std::abs(d[c]) - half[c];
        if (q[c] > q[widest]) widest = c;
        if (q[c] > 0.0) outside2 += q[c] * q[c];
    }
    if (outside2 > 0.0) {
        const double dist = std::sqrt(outside2);
        for (Index c = 0; c < 3; ++c) normal[c] = q[c] > 0.0 ? std::copysign(q[c], d[c]) / dist : 0.0;
        return dist;
    }
    for (Index c = 0; c < 3; ++c) normal[c] = 0.0;
    normal[widest] = d[widest] < 0.0 ? -1.0 : 1.0;
    return q[widest];
}

//: The collider's axis-aligned bounding box (lo, hi (3)) where its row puts it; false for a plane (unbounded).
bool bounds(const Physics& phys, const double* row, double* lo, double* hi) {
    double half[3];
    switch (static_cast<Index>(row[C_SHAPE])) {
        case MESH: {
            const double* header = phys.meshes.headers + static_cast<Index>(row[C_RADIUS]) * MESH_COLUMNS;
            for (Index c = 0; c < 3; ++c) lo[c] = header[M_LO_X + c], hi[c] = header[M_HI_X + c];
            return true;
        }
        case SPHERE: half[0] = half[1] = half[2] = row[C_RADIUS]; break;
        case CYLINDER: half[0] = half[1] = row[C_RADIUS]; half[2] = 0.5 * row[C_HEIGHT]; break;
        case BOX: half[0] = 0.5 * row[C_SIZE_X]; half[1] = 0.5 * row[C_SIZE_Y]; half[2] = 0.5 * row[C_SIZE_Z]; break;
        default: return false;
    }
    for (Index c = 0; c < 3; ++c) {
        lo[c] = row[C_X + c] - half[c];
        hi[c] = row[C_X + c] + half[c];
    }
    return true;
}

//: The distance (m) from a collider's centre to its farthest point (its row's box's farthest corner).
double turning_bound(const Physics& phys, const double* row) {
    double lo[3], hi[3], far2 = 0.0;
    bounds(phys, row, lo, hi);
    for (Index c = 0; c < 3; ++c) {
        const double extent = std::max(std::abs(lo[c] - row[C_X + c]), std::abs(hi[c] - row[C_X + c]));
        far2 += extent * extent;
    }
    return std::sqrt(far2);
}

//: Whether any point of the box [lo, hi] can be closer than gap to the collider, where it is now or was at
//: the step's start (shift: its row of Physics::collider_motion, or null: it stands where its row puts it).
bool reachable(const Physics& phys, const double* row, const double* shift, const double* lo, const double* hi,
               double gap) {
    double clo[3], chi[3];
    if (turns(shift) && static_cast<Index>(row[C_SHAPE]) != PLANE) {  // the sphere about its centre that holds it
        const double far = turning_bound(phys, row);
        for (Index c = 0; c < 3; ++c) {
            const double now = shift[MOTION_NOW + c], start = shift[MOTION_START + c];
            if (hi[c] < row[C_X + c] + std::min(now, start) - far - gap ||
                lo[c] > row[C_X + c] + std::max(now, start) + far + gap) {
                return false;
            }
        }
        return true;
    }
    if (bounds(phys, row, clo, chi)) {
        for (Index c = 0; c < 3; ++c) {
            if (shift != nullptr) {
                const double now = shift[MOTION_NOW + c], start = shift[MOTION_START + c];
                clo[c] += std::min(now, start);
                chi[c] += std::max(now, start);
            }
            if (hi[c] < clo[c] - gap || lo[c] > chi[c] + gap) return false;
        }
        return true;
    }
    // A plane: the box's corner deepest along -normal (the plane where it is now).
    double depth = 0.0, normal[3] = {row[C_NORMAL_X], row[C_NORMAL_Y], row[C_NORMAL_Z]};
    world_direction(shift, normal);
    for (Index c = 0; c < 3; ++c) {
        const double nc = normal[c];
        const double point = row[C_X + c] + (shift != nullptr ? shift[MOTION_NOW + c] : 0.0);
        depth += nc * ((nc >= 0.0 ? lo[c] : hi[c]) - point);
    }
    return depth < gap;
}

//: The force (3, N) the support of particle i (at pos (3, n), of mass (n) kg) held on collider k must
//: balance: f less its mass times its surface's acceleration omega x (omega x r) when the collider turns
//: (r from its centre), in place.
void carried_force(const Physics& phys, Index k, Index n, Index i, const double* pos, const double* mass, double* f) {
    const double* shift = collider_shift(phys, k);
    if (!turns(shift)) return;
    const double* centre = phys.colliders + k * COLLIDER_COLUMNS + C_X;
    const double* w = shift + MOTION_SPIN;
    double r[3], u[3], a[3];
    for (Index c = 0; c < 3; ++c) r[c] = pos[c * n + i] - centre[c] - shift[MOTION_NOW + c];
    cross(w, r, u);
    cross(w, u, a);
    for (Index c = 0; c < 3; ++c) f[c] -= mass[i] * a[c];
}

}  // namespace

double collider_distance(const Physics& phys, Index k, const double* at, double reach, double* normal) {
    const double* row = phys.colliders + k * COLLIDER_COLUMNS;
    const double* shift = collider_shift(phys, k);  // a moving collider: p in the frame where it stands still
    if (turns(shift)) {  // its table point, and the normal there turned back to the world
        double q[3];
        table_point(shift, row + C_X, at, false, q);
        const double dist = table_distance(phys, row, q, reach, normal);
        world_direction(shift, normal);
        return dist;
    }
    double p[3];
    table_point(shift, row + C_X, at, false, p);
    return table_distance(phys, row, p, reach, normal);
}

PinnedPressed pinned_pressed(const Physics& phys, Index n, const double* free, const double* pos) {
    PinnedPressed nearest;
    nearest.distance = 0.5 * phys.thickness * (1.0 + 1e-6);  // (contact leaves a particle it pushed at thickness / 2)
    for (Index i = 0; i < n; ++i) {
        if (free[i] != 0.0) continue;
        const double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
        for (Index k = 0; k < phys.collider_count; ++k) {
            double normal[3];
            const double distance = collider_distance(phys, k, p, 1.0, normal);  // (a mesh's looked for within 1 m)
            if (distance < nearest.distance) nearest = {i, k, distance};
        }
    }
    return nearest;
}

double table_distance(const Physics& phys, const double* row, const double* p, double reach, double* normal) {
    const double d[3] = {p[0] - row[C_X], p[1] - row[C_Y], p[2] - row[C_Z]};
    switch (static_cast<Index>(row[C_SHAPE])) {
        case MESH: return mesh_distance(phys.meshes, static_cast<Index>(row[C_RADIUS]), p, reach, normal);
        case SPHERE: {
            const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (r > 0.0) {
                for (Index c = 0; c < 3; ++c) normal[c] = d[c] / r;
            } else {
                normal[0] = normal[1] = 0.0;
                normal[2] = 1.0;
            }
            return r - row[C_RADIUS];
        }
        case CYLINDER: {
            const double rho = std::sqrt(d[0] * d[0] + d[1] * d[1]);
            const double radial = rho - row[C_RADIUS];
            const double axial = std::abs(d[2]) - 0.5 * row[C_HEIGHT];
            const double ex = rho > 0.0 ? d[0] / rho : 1.0, ey = rho > 0.0 ? d[1] / rho : 0.0;
            const double ez = d[2] < 0.0 ? -1.0 : 1.0;
            if (radial > 0.0 && axial > 0.0) {  // beyond the rim
                const double dist = std::sqrt(radial * radial + axial * axial);
                normal[0] = ex * radial / dist;
                normal[1] = ey * radial / dist;
                normal[2] = ez * axial / dist;
                return dist;
            }
            if (radial > axial) {
                normal[0] = ex;
                normal[1] = ey;
                normal[2] = 0.0;
                return radial;
            }
            normal[0] = normal[1] = 0.0;
            normal[2] = ez;
            return axial;
        }
        case BOX: {
            const double half[3] = {0.5 * row[C_SIZE_X], 0.5 * row[C_SIZE_Y], 0.5 * row[C_SIZE_Z]};
            return box_distance(d, half, normal);
        }
        default: {  // PLANE
            double dist = 0.0;
            for (Index c = 0; c < 3; ++c) {
                normal[c] = row[C_NORMAL_X + c];
                dist += normal[c] * d[c];
            }
            return dist;
        }
    }
}

namespace {

//: The box (lo, hi (3)) of the particles' paths from start to pos (both (3, n)).
void path_box(Index n, const double* start, const double* pos, double* lo, double* hi) {
    for (Index c = 0; c < 3; ++c) {
        const auto [a, b] = std::minmax_element(pos + c * n, pos + (c + 1) * n);
        const auto [e, f] = std::minmax_element(start + c * n, start + (c + 1) * n);
        lo[c] = std::min(*a, *e);
        hi[c] = std::max(*b, *f);
    }
}

//: Where particle i's path from a to p crossed mesh collider `row`'s surface: p goes back to the side it
//: came from, gap off the crossed triangle (normal: that side's).  Returns whether it crossed.  A moving
//: mesh (shift: its row of Physics::collider_motion) is looked at in its own frame: the path from a less its
//: displacement at the step's start to p less its displacement now.
bool undo_crossing(const Physics& phys, const double* row, const double* shift, const double* a, double gap, double* p,
                   double* normal) {
    double hit[3];
    if (shift == nullptr) {
        if (!mesh_crossing(phys.meshes, static_cast<Index>(row[C_RADIUS]), a, p, hit, normal)) return false;
        for (Index c = 0; c < 3; ++c) p[c] = hit[c] + gap * normal[c];
        return true;
    }
    double from[3], to[3];
    table_point(shift, row + C_X, a, true, from);
    table_point(shift, row + C_X, p, false, to);
    if (!mesh_crossing(phys.meshes, static_cast<Index>(row[C_RADIUS]), from, to, hit, normal)) return false;
    for (Index c = 0; c < 3; ++c) hit[c] = hit[c] + gap * normal[c];
    world_point(shift, row + C_X, hit, p);
    world_direction(shift, normal);
    return true;
}

//: Where particle i's path entered a box or a cylinder (shift: its row of Physics::collider_motion, or null for
//: a still one), in the collider's frame (from a (3) less its displacement at the step's start to p (3) less its
//: displacement now), as a mesh's crossing (undo_crossing): p goes back gap off the face it entered through,
//: where the collider is now (normal: that face's).  Returns whether the path entered the solid from outside.
//: (The nearest face at the step's end would let a particle whose support the box's top carried away in the
//: step fall past its edge, or push one that a frame-long step took in through the top near the edge out
//: through the side face, across the cloth.)
bool undo_solid_crossing(const double* row, const double* shift, const double* a, double gap, double* p,
                         double* normal) {
    const bool cylinder = static_cast<Index>(row[C_SHAPE]) == CYLINDER;
    const double half[3] = {0.5 * row[C_SIZE_X], 0.5 * row[C_SIZE_Y], 0.5 * row[C_SIZE_Z]};
    double s[3], e[3];
    double enter = -std::numeric_limits<double>::infinity(), leave = std::numeric_limits<double>::infinity();
    Index axis = -1;  // the face entered through: an axis's slab, or 3 for a cylinder's side
    double from[3], to[3];
    table_point(shift, row + C_X, a, true, from);
    table_point(shift, row + C_X, p, false, to);
    for (Index c = 0; c < 3; ++c) {
        s[c] = from[c] - row[C_X + c];
        e[c] = to[c] - row[C_X + c];
    }
    // The slabs |x_c| <= half_c: a box's three, a cylinder's axial one.
    for (Index c = cylinder ? 2 : 0; c < 3; ++c) {
        const double extent = cylinder ? 0.5 * row[C_HEIGHT] : half[c];
        if (s[c] == e[c]) {
            if (std::abs(s[c]) > extent) return false;  // beside the slab all along
            continue;
        }
        const double t0 = (-extent - s[c]) / (e[c] - s[c]), t1 = (extent - s[c]) / (e[c] - s[c]);
        const double lo = std::min(t0, t1), hi = std::max(t0, t1);
        if (lo > enter) enter = lo, axis = c;
        leave = std::min(leave, hi);
    }
    if (cylinder) {  // and within its radius: |s + t (e - s)| <= r across the axis
        const double dx = e[0] - s[0], dy = e[1] - s[1], r = row[C_RADIUS];
        const double qa = dx * dx + dy * dy, qb = s[0] * dx + s[1] * dy, qc = s[0] * s[0] + s[1] * s[1] - r * r;
        if (qa == 0.0) {
            if (qc > 0.0) return false;  // beside the side all along
        } else {
            const double disc = qb * qb - qa * qc;
            if (!(disc >= 0.0)) return false;  // the line misses the side
            const double root = std::sqrt(disc);
            const double lo = (-qb - root) / qa, hi = (-qb + root) / qa;
            if (lo > enter) enter = lo, axis = 3;
            leave = std::min(leave, hi);
        }
    }
    if (axis < 0 || !(enter > 0.0 && enter <= 1.0 && enter <= leave)) return false;  // inside at the start, or missed
    double q[3];
    for (Index c = 0; c < 3; ++c) q[c] = s[c] + enter * (e[c] - s[c]);
    for (Index c = 0; c < 3; ++c) normal[c] = 0.0;
    if (axis < 3) {
        normal[axis] = s[axis] > 0.0 ? 1.0 : -1.0;
    } else {
        const double rho = std::hypot(q[0], q[1]);
        normal[0] = q[0] / rho;
        normal[1] = q[1] / rho;
    }
    for (Index c = 0; c < 3; ++c) q[c] += gap * normal[c] + row[C_X + c];
    world_point(shift, row + C_X, q, p);
    world_direction(shift, normal);
    return true;
}

}  // namespace

Index collider_contact(Index n, const Physics& phys, const double* start, double* pos, double* vel, double* kick) {
    if (phys.collider_count == 0 || n == 0) return 0;
    const double gap = 0.5 * phys.thickness;
    double lo[3], hi[3];
    path_box(n, start, pos, lo, hi);
    Index touching = 0;
    for (Index k = 0; k < phys.collider_count; ++k) {
        const double* row = phys.colliders + k * COLLIDER_COLUMNS;
        const double* shift = collider_shift(phys, k);
        if (!reachable(phys, row, shift, lo, hi, gap)) continue;
        const bool mesh = static_cast<Index>(row[C_SHAPE]) == MESH;
        const bool solid = static_cast<Index>(row[C_SHAPE]) == BOX || static_cast<Index>(row[C_SHAPE]) == CYLINDER;
        const double friction = row[C_FRICTION];
        for (Index i = 0; i < n; ++i) {
            double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
            const double a[3] = {start[i], start[n + i], start[2 * n + i]};
            double nrm[3];
            const bool crossed = mesh ? undo_crossing(phys, row, shift, a, gap, p, nrm)
                                 : solid && undo_solid_crossing(row, shift, a, gap, p, nrm);
            if (!crossed) {
                const double dist = collider_distance(phys, k, p, gap, nrm);
                if (!(dist < gap)) continue;
                // Position: out along the normal, to the contact distance.
                const double depth = gap - dist;
                for (Index c = 0; c < 3; ++c) p[c] += depth * nrm[c];
            }
            touching += 1;
            // Velocity: the part into the collider removed, sliding reduced by friction times that (relative
            // to a moving collider's velocity).
            double v[3] = {vel[i], vel[n + i], vel[2 * n + i]};
            if (shift == nullptr) {
                coulomb_stop(v, nrm, friction);
            } else {
                double u[3];
                surface_velocity(phys, k, p, u);
                for (Index c = 0; c < 3; ++c) v[c] -= u[c];
                double before[3] = {v[0], v[1], v[2]};
                coulomb_stop(v, nrm, friction);
                double along = 0.0, across = 0.0;
                for (Index c = 0; c < 3; ++c) {
                    before[c] = v[c] - before[c];
                    across += before[c] * nrm[c];
                    v[c] += u[c];
                }
                for (Index c = 0; c < 3; ++c) along += (before[c] - across * nrm[c]) * (before[c] - across * nrm[c]);
                const bool moves = u[0] != 0.0 || u[1] != 0.0 || u[2] != 0.0;
                if (kick != nullptr && moves) *kick = std::max(*kick, std::sqrt(along));
            }
            for (Index c = 0; c < 3; ++c) {
                pos[c * n + i] = p[c];
                vel[c * n + i] = v[c];
            }
        }
    }
    return touching;
}

bool normal_turning(const Physics& phys, Index k, const double* nrm, const double* v, double* turning) {
    const double* row = phys.colliders + k * COLLIDER_COLUMNS;
    const Index shape = static_cast<Index>(row[C_SHAPE]);
    turning[0] = turning[1] = turning[2] = 0.0;
    if (shape != SPHERE && shape != CYLINDER) return false;
    double axis[3] = {0.0, 0.0, 0.0};  // a sphere's normal turns along every direction
    if (shape == CYLINDER) {
        axis[2] = 1.0;
        world_direction(collider_shift(phys, k), axis);
        if (std::abs(nrm[0] * axis[0] + nrm[1] * axis[1] + nrm[2] * axis[2]) > SIDE_ROUNDING) return false;  // cap, rim
    }
    const double along = v[0] * axis[0] + v[1] * axis[1] + v[2] * axis[2];
    const double radius = row[C_RADIUS] + 0.5 * phys.thickness;
    for (int c = 0; c < 3; ++c) turning[c] = (v[c] - along * axis[c]) / radius;
    return turning[0] != 0.0 || turning[1] != 0.0 || turning[2] != 0.0;
}

Index touched_collider(const Physics& phys, Index n, Index i, const double* pos, double* nrm, double slack) {
    const double reach = 0.5 * phys.thickness * (1.0 + 1e-9);
    const double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
    for (Index k = 0; k < phys.collider_count; ++k) {
        // (the slack where analytic supports hold the cloth, and friction acts: still colliders of analytic shapes
        // with friction)
        const double* row = phys.colliders + k * COLLIDER_COLUMNS;
        const bool slack_here = slack > 0.0 && !collider_moves(phys, k) && static_cast<Index>(row[C_SHAPE]) != MESH &&
                                row[C_FRICTION] > 0.0;
        const double within = slack_here ? reach + slack : reach;
        if (collider_distance(phys, k, p, 2.0 * within, nrm) <= within) return k;
    }
    return -1;
}

Index hold_on_colliders(Index n, const Physics& phys, const double* pos, const double* vel, double* free, double* held,
                        double last_step, double slack) {
    Index holding = 0;
    if (phys.collider_count == 0) return 0;
    const double still[3] = {0.0, 0.0, 0.0};
    for (Index i = 0; i < n; ++i) {
        if (free[i] == 0.0) continue;
        if (phys.collider_motion == nullptr && (vel[i] != 0.0 || vel[n + i] != 0.0 || vel[2 * n + i] != 0.0)) continue;
        double nrm[3];
        const Index k = touched_collider(phys, n, i, pos, nrm, slack);
        if (k < 0) continue;
        const double* shift = collider_shift(phys, k);
        double u[3] = {still[0], still[1], still[2]};  // at rest on it: moving with it
        if (shift != nullptr) surface_velocity(phys, k, buf_point(n, i, pos).data(), u);
        if (turns(shift)) {  // (a step leaves it at the surface's velocity where it started or ends the step)
            const double* w = shift + MOTION_SPIN;
            const double carried = std::hypot(u[0] - shift[MOTION_VELOCITY], u[1] - shift[MOTION_VELOCITY + 1],
                                              u[2] - shift[MOTION_VELOCITY + 2]);
            const double off = std::hypot(vel[i] - u[0], vel[n + i] - u[1], vel[2 * n + i] - u[2]);
            const double slack = std::hypot(w[0], w[1], w[2]) * carried * last_step;
            if (off > slack + HOLD_SLACK * std::hypot(u[0], u[1], u[2])) continue;
        } else if (vel[i] != u[0] || vel[n + i] != u[1] || vel[2 * n + i] != u[2]) {
            continue;
        }
        free[i] = 0.0;
        held[i] = collider_held(k);
        holding += 1;
    }
    return holding;
}

Index release_from_colliders(Index n, const Physics& phys, const double* pos, const double* force, const double* mass,
                             double* free, double* held, double cone, bool still_only) {
    Index released = 0;
    const double reach = phys.thickness;  // a held particle sits at thickness / 2
    for (Index i = 0; i < n; ++i) {
        if (held[i] < collider_held(0)) continue;  // not on a collider (floor 1, layer 2, free 0)
        const Index k = static_cast<Index>(held[i] - collider_held(0));
        if (still_only && (collider_moves(phys, k) || !(phys.colliders[k * COLLIDER_COLUMNS + C_FRICTION] > 0.0))) continue;
        const double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
        double nrm[3];
        const bool on = collider_distance(phys, k, p, reach, nrm) < reach;  // a mesh's is not looked for farther
        double f[3] = {force[i], force[n + i], force[2 * n + i]};
        carried_force(phys, k, n, i, pos, mass, f);
        if (!on || slips(f, nrm, cone * phys.colliders[k * COLLIDER_COLUMNS + C_FRICTION])) {
            held[i] = 0.0;
            free[i] = 1.0;
            released += 1;
        }
    }
    return released;
}

Index supported_normals(Index n, const Physics& phys, const double* pos, const double* held, const Sliding* sliding,
                        double* out) {
    Index supported = 0;
    for (Index i = 0; i < n; ++i) {
        if (held[i] < collider_held(0)) continue;  // not on a collider (floor 1, layer 2, free 0)
        const double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
        double nrm[3];
        collider_distance(phys, static_cast<Index>(held[i] - collider_held(0)), p, phys.thickness, nrm);
        for (Index c = 0; c < 3; ++c) out[c * n + i] = nrm[c];
        supported += 1;
    }
    for (Index s = 0; sliding != nullptr && s < sliding->count(); ++s) {
        if (sliding->collider[s] < 0) continue;  // on the floor: the stage's own rule
        const Index i = sliding->index[s];
        for (Index c = 0; c < 3; ++c) out[c * n + i] = sliding->normal[3 * s + c];
        supported += 1;
    }
    return supported;
}

double onto_surface(const Physics& phys, Index k, Index n, Index i, double reach, double h, double* pos, double* vel) {
    const double* shift = collider_shift(phys, k);
    const bool sphere = phys.colliders[k * COLLIDER_COLUMNS + C_SHAPE] == SPHERE;  // the same shape, turned
    if (turns(shift) && !sphere) return 0.0;  // (left where the solve put it)
    // The collider is where the step started (end_collider_motion comes after): p as seen from there.
    const double* moved = shift != nullptr ? shift + MOTION_VELOCITY : nullptr;
    double p[3];
    for (int c = 0; c < 3; ++c) p[c] = pos[c * n + i] - (moved != nullptr ? h * moved[c] : 0.0);
    double nrm[3], u[3];
    const double off = reach - collider_distance(phys, k, p, 2.0 * reach, nrm);
    const double q[3] = {pos[i] + off * nrm[0], pos[n + i] + off * nrm[1], pos[2 * n + i] + off * nrm[2]};
    surface_velocity(phys, k, p, u);
    double v[3], across = 0.0, speed2 = 0.0, along2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        v[c] = vel[c * n + i] - u[c];
        across += v[c] * nrm[c];
        speed2 += v[c] * v[c];
    }
    for (int c = 0; c < 3; ++c) {
        v[c] -= across * nrm[c];
        along2 += v[c] * v[c];
    }
    const double keep = along2 > 0.0 ? std::sqrt(speed2 / along2) : 1.0;  // its speed
    for (int c = 0; c < 3; ++c) {
        pos[c * n + i] = q[c];
        vel[c * n + i] = u[c] + keep * v[c];
    }
    return std::abs(off);
}

double slip_on_supports(Index n, const Physics& phys, const double* force, const double* mass,
                        const double* diagonal_blocks, const double* blocks, double h, double limit,
                        const double* held, const double* start, double* pos, double* vel) {
    const double up[3] = {0.0, 0.0, 1.0};
    double farthest = 0.0;
    for (int pass = 0; pass < 2; ++pass) {  // first: how far each would move; second: move them
        for (Index i = 0; i < n; ++i) {
            const bool on_floor = held[i] == 1.0;
            if (!on_floor && held[i] < collider_held(0)) continue;  // free, or on a layer
            double nrm[3] = {up[0], up[1], up[2]};
            double friction = phys.floor_friction;
            const Index k = on_floor ? -1 : static_cast<Index>(held[i] - collider_held(0));
            if (!on_floor) {
                double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
                const double* shift = collider_shift(phys, k);
                if (turns(shift)) {  // where a moving collider held it, at the step's start
                    for (int c = 0; c < 3; ++c) p[c] = start[c * n + i];
                } else if (shift != nullptr) {
                    for (int c = 0; c < 3; ++c) p[c] -= h * shift[MOTION_VELOCITY + c];
                }
                if (collider_distance(phys, k, p, phys.thickness, nrm) >= phys.thickness) return -1.0;  // off it
                friction = phys.colliders[k * COLLIDER_COLUMNS + C_FRICTION];
            }
            double f[3] = {force[i], force[n + i], force[2 * n + i]};
            if (!on_floor) carried_force(phys, k, n, i, start, mass, f);
            if (!slips(f, nrm, friction)) continue;
            const Slide slide = slide_of(n, i, f, nrm, friction, mass, diagonal_blocks, blocks);
            if (pass == 0) {
                if (!slide.fits(h, limit, farthest)) return -1.0;
                continue;
            }
            slide.apply(n, i, h, pos, vel);
            // Pressed onto a curved collider, that straight move ends move^2 / 2R off it, moving away: back onto it.
            const bool pressed = f[0] * nrm[0] + f[1] * nrm[1] + f[2] * nrm[2] < 0.0;
            double turning[3];
            if (!on_floor && pressed && normal_turning(phys, k, nrm, slide.direction, turning)) {
                farthest = std::max(farthest, onto_surface(phys, k, n, i, 0.5 * phys.thickness, h, pos, vel));
            }
        }
    }
    return farthest;
}

Index collider_history(Index n, const Physics& phys, const char* on_path, const double* pos, const double* vel,
                       double* prev_pos, double* prev_vel, double h) {
    Index agreed = 0;
    for (Index i = 0; i < n; ++i) {
        if (on_path != nullptr && on_path[i] != 0) continue;
        double nrm[3];
        if (touched_collider(phys, n, i, pos, nrm) < 0) continue;
        agreed += 1;
        normal_history(n, i, nrm, pos, vel, prev_pos, prev_vel, h);
    }
    return agreed;
}

}  // namespace wc
