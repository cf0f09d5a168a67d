// The rest sheet's tiers of windows and the cloth's deviation from a rigid motion in each (see
// wetcloth/self_contact/tiers.hpp).
#include "wetcloth/self_contact/tiers.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "wetcloth/lanes.hpp"
#include "wetcloth/self_contact/geometry.hpp"

namespace wc::self_contact {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();
constexpr Index HEADER = 2;  // a tier's cells along x and y, before its arrays

//: Per cell sums of the reference: count; rest position (2); reference (3); reference times the rest position
//: (3 x 2, row by row).  Of one end of a motion: the end (3); the end times the rest position (3 x 2).
enum RefSum : Index { COUNT = 0, REST = 1, REF = 3, REF_REST = 6, REF_SUMS = 12 };
enum EndSum : Index { END = 0, END_REST = 3, END_SUMS = 9 };
//: A window's shape in the reference: its count and rest position sums (as RefSum), whether its frame is
//: not degenerate, the frame (9), the centroid (3) and the largest squared distance of a particle from it.
enum Shape : Index { S_OK = 3, S_FRAME = 4, S_CENTROID = 13, S_RADIUS = 16, SHAPE = 17 };
//: A window's fit at one end: the rotation from the reference (9, row-major), where the fit takes the reference's
//: centroid (3), the largest squared distance of a particle from where these take its reference position.
enum Fit : Index { ROTATION = 0, CENTROID = 9, WORST = 12, FIT = 13 };

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
    const Vec3 e3 = cross(e1, e2);
    const double cols[3][3] = {{e1.x, e2.x, e3.x}, {e1.y, e2.y, e3.y}, {e1.z, e2.z, e3.z}};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) e[3 * r + c] = cols[r][c];
    return true;
}

//: The frame of the positions whose sums are `pos` (3) and, times the rest position, `pos_rest` (6) over the
//: particles whose count and rest position sums start `rest` (as RefSum): of their gradient along the rest
//: sheet's axes (least squares).
bool frame_of(const double* rest, const double* pos, const double* pos_rest, double e[9]) {
    double f[6];
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 2; ++k) f[2 * c + k] = pos_rest[2 * c + k] - pos[c] * rest[REST + k] / rest[COUNT];
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

//: Whether contact.lists->tiers was cut from this rest sheet (its positions, triangles and edges, compared bit for
//: bit); if not, remember it as the one the tiers are about to be cut from.
bool cut_from(const Contact& contact, Index n) {
    ContactLists& lists = *contact.lists;
    const std::size_t positions = static_cast<std::size_t>(3 * n);
    const std::size_t corners = static_cast<std::size_t>(3 * contact.triangle_count);
    const std::size_t ends = static_cast<std::size_t>(2 * contact.edge_count);
    const bool same = lists.tiers_made > 0 && lists.tiers_rest.size() == positions &&
                      lists.tiers_elements.size() == corners + ends &&
                      std::memcmp(lists.tiers_rest.data(), contact.rest, positions * sizeof(double)) == 0 &&
                      std::memcmp(lists.tiers_elements.data(), contact.triangles, corners * sizeof(Index)) == 0 &&
                      std::memcmp(lists.tiers_elements.data() + corners, contact.edges, ends * sizeof(Index)) == 0;
    if (!same) {
        lists.tiers_rest.assign(contact.rest, contact.rest + positions);
        lists.tiers_elements.assign(contact.triangles, contact.triangles + corners);
        lists.tiers_elements.insert(lists.tiers_elements.end(), contact.edges, contact.edges + ends);
    }
    return same;
}

}  // namespace

void prepare_tiers(Contact& contact, Index n) {
    if (cut_from(contact, n)) return;  // cut already: the rest sheet does not change while a cloth moves
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
    contact.lists->tiers_made += 1;
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

//: Tier s's windows in the order they are scanned (wx fastest): `across` x `down` of `wide_x` x `wide_y` cells.
struct Windows {
    Index wide_x, wide_y, across, down;
    explicit Windows(const Tier& t)
        : wide_x(std::min(WINDOW, t.nx)), wide_y(std::min(WINDOW, t.ny)), across(t.nx - wide_x + 1),
          down(t.ny - wide_y + 1) {}
    Index count() const { return across * down; }
};

//: Add the sums (`width` each) of the cells of window (wx, wy) to w (zeroed first).
void window_sums(const Tier& t, const Windows& ws, Index wx, Index wy, const double* cells, Index width, double* w) {
    for (Index k = 0; k < width; ++k) w[k] = 0.0;
    for (Index cy = wy; cy < wy + ws.wide_y; ++cy)
        for (Index cx = wx; cx < wx + ws.wide_x; ++cx) {
            const double* c = cells + (cx + t.nx * cy) * width;
            for (Index k = 0; k < width; ++k) w[k] += c[k];
        }
}

//: Call visit(i) for each particle of window (wx, wy), cell by cell.
template <class Visit>
inline void for_members(const Tier& t, const Windows& ws, Index wx, Index wy, Visit visit) {
    for (Index cy = wy; cy < wy + ws.wide_y; ++cy)
        for (Index cx = wx; cx < wx + ws.wide_x; ++cx) {
            const Index c = cx + t.nx * cy;
            for (Index k = t.start[c]; k < t.start[c + 1]; ++k) visit(t.members[k]);
        }
}

//: Tier t's cells' sums (`stride` doubles a cell) of their particles' positions x (3, n), at columns at ..
//: at + 2, and of those times the particles' rest coordinates, at at_rest .. at_rest + 5; `with_rest`: also
//: their count (COUNT) and rest coordinates (REST).  Into `cells`, and the whole sheet's into `whole` (stride).
void cell_sums(const Contact& contact, Index n, const Tier& t, const double* x, Index stride, Index at, Index at_rest,
               bool with_rest, std::vector<double>& cells, double* whole) {
    const Index count = t.nx * t.ny;
    cells.assign(static_cast<std::size_t>(count * stride), 0.0);
    const double* rest = contact.rest;
    for (Index i = 0; i < n; ++i) {
        double* c = cells.data() + t.cell[i] * stride;
        const double r[2] = {rest[i], rest[n + i]};
        if (with_rest) {
            c[COUNT] += 1.0;
            for (int k = 0; k < 2; ++k) c[REST + k] += r[k];
        }
        for (int d = 0; d < 3; ++d) {
            const double y = x[d * n + i];
            c[at + d] += y;
            for (int k = 0; k < 2; ++k) c[at_rest + 2 * d + k] += y * r[k];
        }
    }
    for (Index k = 0; k < stride; ++k) whole[k] = 0.0;
    for (Index c = 0; c < count; ++c)
        for (Index k = 0; k < stride; ++k) whole[k] += cells[c * stride + k];
}

//: Tier t's windows' shapes in the reference positions `ref` (3, n), SHAPE each in scan order, then the whole
//: sheet's, into `out` (`cells`: scratch).
void shapes_of(const Contact& contact, Index n, const Tier& t, const double* ref, std::vector<double>& cells,
               std::vector<double>& out) {
    const Windows ws(t);
    double w[REF_SUMS];
    cell_sums(contact, n, t, ref, REF_SUMS, REF, REF_REST, true, cells, w);
    out.assign(static_cast<std::size_t>((ws.count() + 1) * SHAPE), 0.0);
    // The whole sheet's: its frame alone.
    double* sheet = out.data() + ws.count() * SHAPE;
    for (Index k = 0; k < S_OK; ++k) sheet[k] = w[k];
    sheet[S_OK] = frame_of(w, w + REF, w + REF_REST, sheet + S_FRAME) ? 1.0 : 0.0;
    for (Index wy = 0; wy < ws.down; ++wy) {
        for (Index wx = 0; wx < ws.across; ++wx) {
            double* shape = out.data() + (wx + ws.across * wy) * SHAPE;
            window_sums(t, ws, wx, wy, cells.data(), REF_SUMS, w);
            for (Index k = 0; k < S_OK; ++k) shape[k] = w[k];
            if (w[COUNT] == 0.0) continue;
            shape[S_OK] = frame_of(w, w + REF, w + REF_REST, shape + S_FRAME) ? 1.0 : 0.0;
            const double inv = 1.0 / w[COUNT];
            const double* centroid = shape + S_CENTROID;
            for (int d = 0; d < 3; ++d) shape[S_CENTROID + d] = w[REF + d] * inv;
            double radius = 0.0;
            for_members(t, ws, wx, wy, [&](Index i) {
                const double ax = ref[i] - centroid[0], ay = ref[n + i] - centroid[1], az = ref[2 * n + i] - centroid[2];
                radius = py_max(radius, ax * ax + ay * ay + az * az);
            });
            shape[S_RADIUS] = radius;
        }
    }
}

//: Tier t's windows' fits (FIT each, in scan order) at positions x (3, n), from their shapes in `ref` (3, n), into
//: `out`; then, if `visits`, each window's particles' squared distances from where its fit takes them, in scan
//: order.  A window's rotation is the whole sheet's where its frame is degenerate (its particles on a line in
//: the rest sheet, as on a mesh's rim: any rotation gives a valid bound), the identity where that one is.  Its
//: translation takes the reference's centroid to the end's, or on to the centre of the box around the
//: particles' offsets from there where half the box's diagonal is less (any translation gives a valid bound
//: too; a window bent into an arc then deviates by half its sagitta, where its centroid's translation leaves
//: its ends up to two thirds away: the 81 x 81 hanging sheet's fixed-step mode rebuilt its list 24 times in 3 s
//: instead of 31).
void fit_end(const Contact& contact, Index n, const Tier& t, const double* ref, const double* shapes,
             const double* x, bool visits, std::vector<double>& cells, std::vector<double>& out) {
    const Windows ws(t);
    double w[END_SUMS];
    cell_sums(contact, n, t, x, END_SUMS, END, END_REST, false, cells, w);
    out.resize(static_cast<std::size_t>(ws.count() * FIT));
    double sheet_rotation[9];
    {
        const double identity[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
        const double* sheet = shapes + ws.count() * SHAPE;
        double e[9];
        const bool ok = frame_of(sheet, w + END, w + END_REST, e);
        rotation(sheet[S_OK] != 0.0, sheet + S_FRAME, ok, e, identity, sheet_rotation);
    }
    for (Index wy = 0; wy < ws.down; ++wy) {
        for (Index wx = 0; wx < ws.across; ++wx) {
            const Index at = wx + ws.across * wy;
            const double* shape = shapes + at * SHAPE;
            if (shape[COUNT] == 0.0) continue;
            window_sums(t, ws, wx, wy, cells.data(), END_SUMS, w);
            double e[9];
            const bool ok = frame_of(shape, w + END, w + END_REST, e);
            double r[9];
            rotation(shape[S_OK] != 0.0, shape + S_FRAME, ok, e, sheet_rotation, r);
            const double inv = 1.0 / shape[COUNT];
            double m[3] = {w[END] * inv, w[END + 1] * inv, w[END + 2] * inv};
            const double y[3] = {shape[S_CENTROID], shape[S_CENTROID + 1], shape[S_CENTROID + 2]};
            // Each particle's offset from where the rotation about the centroids takes it.
            const auto offset = [&](Index i, double d[3]) {
                const double ax = ref[i] - y[0], ay = ref[n + i] - y[1], az = ref[2 * n + i] - y[2];
                d[0] = x[i] - m[0] - (r[0] * ax + r[1] * ay + r[2] * az);
                d[1] = x[n + i] - m[1] - (r[3] * ax + r[4] * ay + r[5] * az);
                d[2] = x[2 * n + i] - m[2] - (r[6] * ax + r[7] * ay + r[8] * az);
            };
            // The farthest offset (its square; NaN if any is: their sum is), and the box around the offsets.
            double worst = 0.0, total = 0.0, lo[3] = {INF, INF, INF}, hi[3] = {-INF, -INF, -INF};
            const std::size_t first_visit = out.size();
            const auto visit = [&](Index i) {
                double d[3];
                offset(i, d);
                for (int c = 0; c < 3; ++c) lo[c] = py_min(lo[c], d[c]), hi[c] = py_max(hi[c], d[c]);
                const double d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                worst = d2 > worst ? d2 : worst;
                total += d2;
                return d2;
            };
            if (visits) {
                for_members(t, ws, wx, wy, [&](Index i) { out.push_back(visit(i)); });
            } else {
                for_members(t, ws, wx, wy, visit);
            }
            if (!(total == total)) worst = total;
            const double box[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
            const double half_diagonal = 0.25 * (box[0] * box[0] + box[1] * box[1] + box[2] * box[2]);
            if (half_diagonal < worst) {  // (never where worst is NaN)
                worst = half_diagonal;
                const double shift[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
                if (visits) {
                    std::size_t slot = first_visit;
                    for_members(t, ws, wx, wy, [&](Index i) {
                        double d[3];
                        offset(i, d);
                        for (int c = 0; c < 3; ++c) d[c] -= shift[c];
                        out[slot++] = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    });
                }
                for (int c = 0; c < 3; ++c) m[c] += shift[c];
            }
            double* fit = out.data() + at * FIT;  // (after the visits, which may move `out`)
            for (int k = 0; k < 9; ++k) fit[ROTATION + k] = r[k];
            for (int d = 0; d < 3; ++d) fit[CENTROID + d] = m[d];
            fit[WORST] = worst;
        }
    }
}

//: Whether fits (as fit_end makes them) hold each visit's squared distance.
inline bool has_visits(const std::vector<double>& fits, const Tier& t) {
    return fits.size() > static_cast<std::size_t>(Windows(t).count() * FIT);
}

//: How far the straight lines between a window's rotations at the two ends (fits f0, f1) fall short of a
//: rotation, per metre from its centroid: (1 - cos(angle / 2)) at every point along the motion, at most
//: (1 - cos(angle)) / 2 = (3 - trace(r0^T r1)) / 4.
inline double blend_of(const double* f0, const double* f1) {
    double trace = 0.0;
    for (int k = 0; k < 9; ++k) trace += f0[ROTATION + k] * f1[ROTATION + k];
    return py_max(0.0, 0.25 * (3.0 - trace));
}

//: The largest deviation over tier t's windows of shapes `shapes` of the motion between fits f0 and f1.
double deviation_of(const Tier& t, const double* shapes, const double* f0, const double* f1) {
    const Windows ws(t);
    double largest = 0.0;
    for (Index at = 0; at < ws.count(); ++at) {
        const double* shape = shapes + at * SHAPE;
        if (shape[COUNT] == 0.0) continue;
        const double* a = f0 + at * FIT;
        const double* b = f1 + at * FIT;
        const double worst = worse(a[WORST], b[WORST]);
        largest = worse(largest, std::sqrt(worst) + blend_of(a, b) * std::sqrt(shape[S_RADIUS]));
    }
    return largest;
}

//: Whether the motion between fits f0 and f1 (with visits) of tier t's windows of shapes `shapes` in `ref`
//: (3, n) leaves each particle i within allowance[i] (m); false if a position is not finite.
bool within_of(Index n, const Tier& t, const double* ref, const double* shapes, const std::vector<double>& f0,
               const std::vector<double>& f1, const double* allowance) {
    const Windows ws(t);
    std::size_t visit = static_cast<std::size_t>(ws.count() * FIT);
    for (Index wy = 0; wy < ws.down; ++wy) {
        for (Index wx = 0; wx < ws.across; ++wx) {
            const Index at = wx + ws.across * wy;
            const double* shape = shapes + at * SHAPE;
            if (shape[COUNT] == 0.0) continue;
            const double blend = blend_of(f0.data() + at * FIT, f1.data() + at * FIT);
            const double* y = shape + S_CENTROID;
            bool within = true;
            for_members(t, ws, wx, wy, [&](Index i) {
                const double ax = ref[i] - y[0], ay = ref[n + i] - y[1], az = ref[2 * n + i] - y[2];
                const double d2 = worse(f0[visit], f1[visit]);
                visit += 1;
                within = within && std::sqrt(d2) + blend * std::sqrt(ax * ax + ay * ay + az * az) <= allowance[i];
            });
            if (!within) return false;  // also if NaN
        }
    }
    return true;
}

}  // namespace

double deviation(const Contact& contact, Index n, int s, const double* ref, const double* x0, const double* x1) {
    WindowFits& scratch = contact.lists->fits;
    const Tier t = tier_of(contact, n, s);
    shapes_of(contact, n, t, ref, scratch.cells, scratch.shape);
    fit_end(contact, n, t, ref, scratch.shape.data(), x0, false, scratch.cells, scratch.start_fit);
    fit_end(contact, n, t, ref, scratch.shape.data(), x1, false, scratch.cells, scratch.end_fit);
    return deviation_of(t, scratch.shape.data(), scratch.start_fit.data(), scratch.end_fit.data());
}

StepFits::StepFits(const Contact& contact, Index n, const double* x0, const double* x1)
    : contact_(contact), n_(n), x0_(x0), x1_(x1), kept_(contact.lists->fits) {
    const std::size_t size = static_cast<std::size_t>(3 * n);
    const std::size_t tiers = static_cast<std::size_t>(FINE_TIER + 1);
    const double* ref = contact.reference;
    const bool same_tiers = kept_.tiers_made == contact.lists->tiers_made;
    const bool same_reference = same_tiers && kept_.reference.size() == size &&
                                std::memcmp(kept_.reference.data(), ref, size * sizeof(double)) == 0;
    const bool starts_at_end = same_reference && kept_.end.size() == size &&
                               std::memcmp(kept_.end.data(), x0, size * sizeof(double)) == 0;
    if (kept_.shapes.size() != tiers) {
        kept_.shapes.assign(tiers, {}), kept_.at.assign(tiers, {}), kept_.next.assign(tiers, {});
        kept_.shaped.assign(tiers, 0), kept_.kept.assign(tiers, 0);
    }
    if (!same_reference) {
        kept_.reference.assign(ref, ref + size);
        kept_.tiers_made = contact.lists->tiers_made;
        kept_.shaped.assign(tiers, 0);
    }
    if (!starts_at_end) kept_.kept.assign(tiers, 0);
    kept_.made.assign(tiers, 0);
}

StepFits::~StepFits() {
    for (std::size_t s = 0; s < kept_.made.size(); ++s) {
        if (kept_.made[s]) kept_.at[s].swap(kept_.next[s]);
        kept_.kept[s] = kept_.made[s];
    }
    kept_.end.assign(x1_, x1_ + 3 * n_);
}

const double* StepFits::shapes(int s, const Tier& t) {
    if (!kept_.shaped[s]) {
        shapes_of(contact_, n_, t, contact_.reference, kept_.cells, kept_.shapes[s]);
        kept_.shaped[s] = 1;
    }
    return kept_.shapes[s].data();
}

void StepFits::fit(int s, const Tier& t, bool visits) {
    const double* shape = shapes(s, t);
    if (!(kept_.kept[s] && (!visits || has_visits(kept_.at[s], t)))) {
        fit_end(contact_, n_, t, contact_.reference, shape, x0_, visits, kept_.cells, kept_.at[s]);
        kept_.kept[s] = 1;
    }
    if (!(kept_.made[s] && (!visits || has_visits(kept_.next[s], t)))) {
        fit_end(contact_, n_, t, contact_.reference, shape, x1_, visits, kept_.cells, kept_.next[s]);
        kept_.made[s] = 1;
    }
}

double StepFits::deviation(int s) {
    const Tier t = tier_of(contact_, n_, s);
    fit(s, t, false);
    return deviation_of(t, kept_.shapes[s].data(), kept_.at[s].data(), kept_.next[s].data());
}

bool StepFits::within_allowances(int s, const double* allowance) {
    const Tier t = tier_of(contact_, n_, s);
    fit(s, t, true);
    return within_of(n_, t, contact_.reference, kept_.shapes[s].data(), kept_.at[s], kept_.next[s], allowance);
}

double shifted_deviation(Index n, const double* ref, const double* x0, const double* x1) {
    // Particles in SHIFT_LANES interleaved lanes (in_lanes), so that the lanes' comparisons do not wait on each
    // other: the same extremes as one pass in order (py_min and py_max never take a NaN, `worse` keeps one
    // wherever it comes).
    constexpr Index SHIFT_LANES = 4;
    double shift0[3], shift1[3];
    for (int c = 0; c < 3; ++c) {
        double lo0[SHIFT_LANES], hi0[SHIFT_LANES], lo1[SHIFT_LANES], hi1[SHIFT_LANES];
        for (Index l = 0; l < SHIFT_LANES; ++l) lo0[l] = INF, hi0[l] = -INF, lo1[l] = INF, hi1[l] = -INF;
        in_lanes<SHIFT_LANES>(n, [&](Index l, Index i) {
            const double y = ref[c * n + i], d0 = x0[c * n + i] - y, d1 = x1[c * n + i] - y;
            lo0[l] = py_min(lo0[l], d0), hi0[l] = py_max(hi0[l], d0);
            lo1[l] = py_min(lo1[l], d1), hi1[l] = py_max(hi1[l], d1);
        });
        for (Index l = 1; l < SHIFT_LANES; ++l) {
            lo0[0] = py_min(lo0[0], lo0[l]), hi0[0] = py_max(hi0[0], hi0[l]);
            lo1[0] = py_min(lo1[0], lo1[l]), hi1[0] = py_max(hi1[0], hi1[l]);
        }
        shift0[c] = 0.5 * (lo0[0] + hi0[0]), shift1[c] = 0.5 * (lo1[0] + hi1[0]);
    }
    double worst[SHIFT_LANES] = {};
    in_lanes<SHIFT_LANES>(n, [&](Index l, Index i) {
        double a2 = 0.0, b2 = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double y = ref[c * n + i], a = x0[c * n + i] - y - shift0[c], b = x1[c * n + i] - y - shift1[c];
            a2 += a * a;
            b2 += b * b;
        }
        worst[l] = worse(worse(worst[l], a2), b2);
    });
    for (Index l = 1; l < SHIFT_LANES; ++l) worst[0] = worse(worst[0], worst[l]);
    return std::sqrt(worst[0]);
}

}  // namespace wc::self_contact
