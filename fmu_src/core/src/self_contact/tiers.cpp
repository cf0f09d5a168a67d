// The rest sheet's tiers of windows and the cloth's deviation from a rigid motion in each (see
// wetcloth/self_contact/tiers.hpp).
#include "wetcloth/self_contact/tiers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "wetcloth/self_contact/geometry.hpp"

namespace wc::self_contact {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();
constexpr Index HEADER = 2;  // a tier's cells along x and y, before its arrays

//: Per cell sums of a deviation: count; rest position (2); reference (3); ends x0, x1 (3 each); reference
//: and each end times the rest position (3 x 2 each, row by row).
enum Sum : Index {
    COUNT = 0, REST = 1, REF = 3, END0 = 6, END1 = 9, REF_REST = 12, END0_REST = 18, END1_REST = 24, SUMS = 30
};

//: The cells along one axis of tier s: cell side `side` (m) from `origin`, over rest coordinates up to `top`.
inline Index cells_along(double origin, double side, double top) {
    return static_cast<Index>(std::floor((top - origin) / side)) + 1;
}

//: The last tier (the whole sheet) is one cell.
inline bool whole(int s) { return s == TIERS - 1; }

//: The orthonormal frame (columns e1, e2, e1 x e2, row-major 3 x 3) of the 3 x 2 matrix `f` (row-major) by
//: Gram-Schmidt on its columns; false if they are (nearly) parallel or zero.
bool frame(const double f[6], double e[9]) {
    const Vec3 a = {f[0], f[2], f[4]}, b = {f[1], f[3], f[5]};
    const double la = norm(a);
    if (!(la > 0.0)) return false;
    const Vec3 e1 = {a.x / la, a.y / la, a.z / la};
    const double along = dot(b, e1);
    const Vec3 u = {b.x - along * e1.x, b.y - along * e1.y, b.z - along * e1.z};
    const double lu = norm(u);
    if (!(lu > 1e-9 * norm(b))) return false;
    const Vec3 e2 = {u.x / lu, u.y / lu, u.z / lu};
    const Vec3 e3 = {e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x};
    const double cols[3][3] = {{e1.x, e2.x, e3.x}, {e1.y, e2.y, e3.y}, {e1.z, e2.z, e3.z}};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) e[3 * r + c] = cols[r][c];
    return true;
}

//: The frame of the positions whose sums start at `at` (REF, END0 or END1; their products with the rest
//: position at `times`) in window sums w: of their gradient along the rest sheet's axes (least squares).
bool frame_of(const double* w, Index at, Index times, double e[9]) {
    double f[6];
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 2; ++k) f[2 * c + k] = w[times + 2 * c + k] - w[at + c] * w[REST + k] / w[COUNT];
    return frame(f, e);
}

//: The window's rotation from the reference to the positions of frame `e` (this frame times the transposed
//: reference frame); `fallback` when either frame is degenerate (any rotation gives a valid bound).
void rotation(bool ref_ok, const double e_ref[9], bool ok, const double e[9], const double fallback[9], double r[9]) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r[3 * i + j] = ref_ok && ok ? e[3 * i] * e_ref[3 * j] + e[3 * i + 1] * e_ref[3 * j + 1] +
                                              e[3 * i + 2] * e_ref[3 * j + 2]
                                        : fallback[3 * i + j];
}

//: The larger of `worst` and `v`, NaN once either is.
inline double worse(double worst, double v) { return (v > worst || v != v) ? v : worst; }

//: The grid spacing (m) along the rest sheet's x and y: the largest extent of an edge along each.
struct Spacing {
    double x, y;
};

Spacing spacing_of(const Contact& contact, Index n) {
    Spacing h{0.0, 0.0};
    const double* rx = contact.rest;
    const double* ry = contact.rest + n;
    for (Index k = 0; k < contact.edge_count; ++k) {
        const Index a = contact.edges[2 * k], b = contact.edges[2 * k + 1];
        h.x = py_max(h.x, std::fabs(rx[a] - rx[b]));
        h.y = py_max(h.y, std::fabs(ry[a] - ry[b]));
    }
    return h;
}

//: The median length (m) of the edges in the rest sheet (0 if none).
double median_edge(const Contact& contact, Index n) {
    std::vector<double> lengths(static_cast<std::size_t>(contact.edge_count));
    for (Index k = 0; k < contact.edge_count; ++k) {
        const Index a = contact.edges[2 * k], b = contact.edges[2 * k + 1];
        lengths[k] = std::hypot(contact.rest[a] - contact.rest[b], contact.rest[n + a] - contact.rest[n + b]);
    }
    if (lengths.empty()) return 0.0;
    const auto middle = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
    std::nth_element(lengths.begin(), middle, lengths.end());
    return *middle;
}

//: The cell (0 to count - 1) of rest coordinate v: cells of `side` (m) from `origin`.
inline Index cell_along(double v, double origin, double side, Index count) {
    const double c = std::floor((v - origin) / side);
    return c < 0.0 ? 0 : (c > count - 1.0 ? count - 1 : static_cast<Index>(c));
}

}  // namespace

void prepare_tiers(Contact& contact, Index n) {
    const double* rx = contact.rest;
    const double* ry = contact.rest + n;
    double lo_x = INF, lo_y = INF, hi_x = -INF, hi_y = -INF;
    for (Index i = 0; i < n; ++i) {
        lo_x = py_min(lo_x, rx[i]), hi_x = py_max(hi_x, rx[i]);
        lo_y = py_min(lo_y, ry[i]), hi_y = py_max(hi_y, ry[i]);
    }
    const Spacing longest = spacing_of(contact, n);
    const double median = median_edge(contact, n);
    std::vector<Index>& out = contact.lists->tiers;
    out.clear();
    for (int s = 0; s <= FINE_TIER; ++s) {
        const Spacing h = s == FINE_TIER ? Spacing{median, median} : longest;
        const double side_x = (s == FINE_TIER ? FINE_CELLS : whole(s) ? 0 : TIER_CELLS[s]) * h.x;
        const double side_y = (s == FINE_TIER ? FINE_CELLS : whole(s) ? 0 : TIER_CELLS[s]) * h.y;
        // Cells start half a spacing before the sheet, so that no particle of a grid lies on a cell's side.
        const double origin_x = lo_x - 0.5 * h.x, origin_y = lo_y - 0.5 * h.y;
        Index nx = 1, ny = 1;
        if (!whole(s) && h.x > 0.0 && h.y > 0.0) {
            nx = cells_along(origin_x, side_x, hi_x);
            ny = cells_along(origin_y, side_y, hi_y);
        }
        const Index cells = nx * ny;
        const std::size_t base = out.size();
        out.resize(base + HEADER + n + (cells + 1) + n);
        Index* t = out.data() + base;
        t[0] = nx, t[1] = ny;
        Index* cell = t + HEADER;
        Index* start = cell + n;
        Index* members = start + cells + 1;
        for (Index i = 0; i < n; ++i) {
            const Index cx = nx > 1 ? cell_along(rx[i], origin_x, side_x, nx) : 0;
            const Index cy = ny > 1 ? cell_along(ry[i], origin_y, side_y, ny) : 0;
            cell[i] = cx + nx * cy;
        }
        // The particles by cell, ascending within each (a counting sort).
        for (Index c = 0; c <= cells; ++c) start[c] = 0;
        for (Index i = 0; i < n; ++i) start[cell[i] + 1] += 1;
        for (Index c = 0; c < cells; ++c) start[c + 1] += start[c];
        std::vector<Index>& cursor = contact.lists->index_scratch;
        cursor.assign(start, start + cells);
        for (Index i = 0; i < n; ++i) members[cursor[cell[i]]++] = i;
    }
}

Tier tier_in(const std::vector<Index>& tiers, Index n, int s) {
    const Index* t = tiers.data();
    for (int k = 0; k < s; ++k) t += HEADER + n + (t[0] * t[1] + 1) + n;
    Tier tier;
    tier.nx = t[0], tier.ny = t[1];
    tier.cell = t + HEADER;
    tier.start = tier.cell + n;
    tier.members = tier.start + tier.nx * tier.ny + 1;
    return tier;
}

double rest_distance_beyond(const Contact& contact, Index n, int s) {
    const Tier t = tier_of(contact, n, s);
    const Spacing h = spacing_of(contact, n);
    double beyond = INF;
    if (t.nx > WINDOW) beyond = py_min(beyond, ((WINDOW - 1) * TIER_CELLS[s] - 1) * h.x);
    if (t.ny > WINDOW) beyond = py_min(beyond, ((WINDOW - 1) * TIER_CELLS[s] - 1) * h.y);
    return beyond;
}

namespace {

//: Each window of tier s, moving from x0 to x1 away from a rigid motion of `ref` (all (3, n)): for each of its
//: particles i, particle(i, d2, a2, blend) with d2 the larger squared distance, at the two ends, from where
//: the window's rigid motion takes it, a2 its squared distance from the window's centroid at `ref` and
//: blend how far, per metre of that, the straight lines between the two rotations fall short of a rotation;
//: then window(blend).  Either returning false stops the scan (and it returns false).
template <class Particle, class Window>
bool scan_windows(const Contact& contact, Index n, int s, const double* ref, const double* x0, const double* x1,
                  Particle particle, Window window) {
    const Tier t = tier_of(contact, n, s);
    const Index cells = t.nx * t.ny;
    std::vector<double>& sums = contact.lists->tier_scratch;
    sums.assign(static_cast<std::size_t>((cells + 1) * SUMS), 0.0);
    const double* rest = contact.rest;
    for (Index i = 0; i < n; ++i) {
        double* c = sums.data() + t.cell[i] * SUMS;
        const double r[2] = {rest[i], rest[n + i]};
        c[COUNT] += 1.0;
        for (int k = 0; k < 2; ++k) c[REST + k] += r[k];
        for (int d = 0; d < 3; ++d) {
            const double y = ref[d * n + i], a = x0[d * n + i], b = x1[d * n + i];
            c[REF + d] += y;
            c[END0 + d] += a;
            c[END1 + d] += b;
            for (int k = 0; k < 2; ++k) {
                c[REF_REST + 2 * d + k] += y * r[k];
                c[END0_REST + 2 * d + k] += a * r[k];
                c[END1_REST + 2 * d + k] += b * r[k];
            }
        }
    }
    double* w = sums.data() + cells * SUMS;  // the window's sums
    // The whole sheet's rotation at each end (identity if degenerate): that of a window whose particles lie
    // on a line in the rest sheet (a few on the rim of a mesh), rather than none.
    double sheet0[9], sheet1[9];
    {
        const double identity[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
        for (Index k = 0; k < SUMS; ++k) w[k] = 0.0;
        for (Index c = 0; c < cells; ++c)
            for (Index k = 0; k < SUMS; ++k) w[k] += sums[c * SUMS + k];
        double e_ref[9], e0[9], e1[9];
        const bool ref_ok = frame_of(w, REF, REF_REST, e_ref);
        rotation(ref_ok, e_ref, frame_of(w, END0, END0_REST, e0), e0, identity, sheet0);
        rotation(ref_ok, e_ref, frame_of(w, END1, END1_REST, e1), e1, identity, sheet1);
    }
    const Index wide_x = py_min(WINDOW, t.nx), wide_y = py_min(WINDOW, t.ny);
    for (Index wy = 0; wy + wide_y <= t.ny; ++wy) {
        for (Index wx = 0; wx + wide_x <= t.nx; ++wx) {
            for (Index k = 0; k < SUMS; ++k) w[k] = 0.0;
            for (Index cy = wy; cy < wy + wide_y; ++cy)
                for (Index cx = wx; cx < wx + wide_x; ++cx) {
                    const double* c = sums.data() + (cx + t.nx * cy) * SUMS;
                    for (Index k = 0; k < SUMS; ++k) w[k] += c[k];
                }
            if (w[COUNT] == 0.0) continue;
            // A rotation for each end, and a translation: the window's centroid to the end's.
            double e_ref[9], e0[9], e1[9], r0[9], r1[9];
            const bool ref_ok = frame_of(w, REF, REF_REST, e_ref);
            rotation(ref_ok, e_ref, frame_of(w, END0, END0_REST, e0), e0, sheet0, r0);
            rotation(ref_ok, e_ref, frame_of(w, END1, END1_REST, e1), e1, sheet1, r1);
            const double inv = 1.0 / w[COUNT];
            const double ry[3] = {w[REF] * inv, w[REF + 1] * inv, w[REF + 2] * inv};
            const double m0[3] = {w[END0] * inv, w[END0 + 1] * inv, w[END0 + 2] * inv};
            const double m1[3] = {w[END1] * inv, w[END1 + 1] * inv, w[END1 + 2] * inv};
            // Along the motion the window's linear blend of the two rotations is within (1 - cos(angle / 2))
            // of a rotation at every point, at most (1 - cos(angle)) / 2 = (3 - trace(r0^T r1)) / 4.
            double trace = 0.0;
            for (int k = 0; k < 9; ++k) trace += r0[k] * r1[k];
            const double blend = py_max(0.0, 0.25 * (3.0 - trace));
            for (Index cy = wy; cy < wy + wide_y; ++cy) {
                for (Index cx = wx; cx < wx + wide_x; ++cx) {
                    const Index c = cx + t.nx * cy;
                    for (Index k = t.start[c]; k < t.start[c + 1]; ++k) {
                        const Index i = t.members[k];
                        const double ax = ref[i] - ry[0], ay = ref[n + i] - ry[1], az = ref[2 * n + i] - ry[2];
                        const double d0x = x0[i] - m0[0] - (r0[0] * ax + r0[1] * ay + r0[2] * az);
                        const double d0y = x0[n + i] - m0[1] - (r0[3] * ax + r0[4] * ay + r0[5] * az);
                        const double d0z = x0[2 * n + i] - m0[2] - (r0[6] * ax + r0[7] * ay + r0[8] * az);
                        const double d1x = x1[i] - m1[0] - (r1[0] * ax + r1[1] * ay + r1[2] * az);
                        const double d1y = x1[n + i] - m1[1] - (r1[3] * ax + r1[4] * ay + r1[5] * az);
                        const double d1z = x1[2 * n + i] - m1[2] - (r1[6] * ax + r1[7] * ay + r1[8] * az);
                        const double d2 = worse(d0x * d0x + d0y * d0y + d0z * d0z, d1x * d1x + d1y * d1y + d1z * d1z);
                        if (!particle(i, d2, ax * ax + ay * ay + az * az, blend)) return false;
                    }
                }
            }
            if (!window(blend)) return false;
        }
    }
    return true;
}

}  // namespace

double deviation(const Contact& contact, Index n, int s, const double* ref, const double* x0, const double* x1) {
    double largest = 0.0, worst = 0.0, radius = 0.0;
    scan_windows(
        contact, n, s, ref, x0, x1,
        [&](Index, double d2, double a2, double) {
            worst = worse(worst, d2);
            radius = py_max(radius, a2);
            return true;
        },
        [&](double blend) {
            largest = worse(largest, std::sqrt(worst) + blend * std::sqrt(radius));
            worst = 0.0, radius = 0.0;
            return true;
        });
    return largest;
}

bool within_allowances(const Contact& contact, Index n, int s, const double* ref, const double* x0,
                       const double* x1, const double* allowance) {
    return scan_windows(
        contact, n, s, ref, x0, x1,
        [&](Index i, double d2, double a2, double blend) {
            return std::sqrt(d2) + blend * std::sqrt(a2) <= allowance[i];  // false if NaN
        },
        [](double) { return true; });
}

double shifted_deviation(Index n, const double* ref, const double* x0, const double* x1) {
    double shift0[3], shift1[3];
    for (int c = 0; c < 3; ++c) {
        double lo0 = INF, hi0 = -INF, lo1 = INF, hi1 = -INF;
        for (Index i = 0; i < n; ++i) {
            const double y = ref[c * n + i], d0 = x0[c * n + i] - y, d1 = x1[c * n + i] - y;
            lo0 = py_min(lo0, d0), hi0 = py_max(hi0, d0);
            lo1 = py_min(lo1, d1), hi1 = py_max(hi1, d1);
        }
        shift0[c] = 0.5 * (lo0 + hi0), shift1[c] = 0.5 * (lo1 + hi1);
    }
    double worst = 0.0;
    for (Index i = 0; i < n; ++i) {
        double a2 = 0.0, b2 = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double y = ref[c * n + i], a = x0[c * n + i] - y - shift0[c], b = x1[c * n + i] - y - shift1[c];
            a2 += a * a;
            b2 += b * b;
        }
        worst = worse(worse(worst, a2), b2);
    }
    return std::sqrt(worst);
}

}  // namespace wc::self_contact
