// The finest tier's windows shown to hold no candidate pair (see wetcloth/self_contact/flat_windows.hpp).
#include "wetcloth/self_contact/flat_windows.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "wetcloth/self_contact/geometry.hpp"
#include "wetcloth/self_contact/tiers.hpp"

namespace wc::self_contact {

namespace {

constexpr double INF = std::numeric_limits<double>::infinity();
//: A window counts as shown where its bound exceeds the reach by this fraction (room for the bounds' rounding).
constexpr double SURELY = 1e-9;
//: Per triangle: its Jacobian onto space (3 x 2, row-major), its unit normal (3), its least altitude (m), twice
//: its area (m2).
enum TriangleFigure : Index { T_JACOBIAN = 0, T_NORMAL = 6, T_ALTITUDE = 9, T_AREA = 10, T_FIGURES = 11 };
//: Per cell of a tier, over its triangles: count; sum of their normals times twice their areas (3); sum
//: of their Jacobians (6); the farthest Jacobian from their mean (Frobenius norm); the least cosine between a
//: normal and their sum's; the least altitude (m).
enum CellFigure : Index { C_COUNT = 0, C_NORMAL = 1, C_JACOBIAN = 4, C_SPREAD = 10, C_CONE = 11, C_ALTITUDE = 12, C_FIGURES = 13 };

//: Twice the signed area of the triangle o, a, b in the plane.
inline double cross2(const double o[2], const double a[2], const double b[2]) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

//: Whether the rest sheet (rows x, y of `rest`) covers its convex hull: its triangles' areas add up to the
//: hull's (Andrew's monotone chain), to rounding.
bool covers_its_hull(const Contact& contact, Index n) {
    std::vector<std::pair<double, double>> points(static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i) points[i] = {contact.rest[i], contact.rest[n + i]};
    std::sort(points.begin(), points.end());
    std::vector<std::pair<double, double>> hull(2 * points.size() + 1);
    std::size_t k = 0;
    const auto turn = [](const std::pair<double, double>& o, const std::pair<double, double>& a,
                         const std::pair<double, double>& b) {
        const double po[2] = {o.first, o.second}, pa[2] = {a.first, a.second}, pb[2] = {b.first, b.second};
        return cross2(po, pa, pb);
    };
    for (std::size_t i = 0; i < points.size(); ++i) {
        while (k >= 2 && turn(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && turn(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
        hull[k++] = points[i];
    }
    double hull_area = 0.0;
    for (std::size_t i = 0; i + 1 < k; ++i)
        hull_area += hull[i].first * hull[i + 1].second - hull[i + 1].first * hull[i].second;
    hull_area = 0.5 * std::fabs(hull_area);
    double area = 0.0;
    for (Index t = 0; t < contact.triangle_count; ++t) {
        const Index* c = contact.triangles + 3 * t;
        const double a[2] = {contact.rest[c[0]], contact.rest[n + c[0]]}, b[2] = {contact.rest[c[1]], contact.rest[n + c[1]]},
                     d[2] = {contact.rest[c[2]], contact.rest[n + c[2]]};
        area += 0.5 * std::fabs(cross2(a, b, d));
    }
    return hull_area > 0.0 && area >= hull_area * (1.0 - 1e-9);
}

//: The rest sheet's figures (ContactLists::flat_*), made once for the tiers as cut.
void prepare_rest(const Contact& contact, Index n) {
    ContactLists& lists = *contact.lists;
    if (lists.flat_made == lists.tiers_made) return;
    lists.flat_made = lists.tiers_made;
    const Index m = contact.triangle_count;
    const Tier t = tier_of(contact, n, 0);
    lists.flat_convex = covers_its_hull(contact, n);
    lists.flat_inverse.assign(static_cast<std::size_t>(4 * m), 0.0);
    for (Index k = 0; k < m; ++k) {
        const Index* c = contact.triangles + 3 * k;
        const double* r = contact.rest;
        const double a = r[c[1]] - r[c[0]], b = r[c[2]] - r[c[0]], d = r[n + c[1]] - r[n + c[0]], e = r[n + c[2]] - r[n + c[0]];
        const double det = a * e - b * d;  // rest edges as columns [[a, b], [d, e]]
        double* inv = lists.flat_inverse.data() + 4 * k;
        inv[0] = e / det, inv[1] = -b / det, inv[2] = -d / det, inv[3] = a / det;
    }
    // The rim: the particles of edges that border one triangle.
    std::vector<std::pair<Index, Index>> sides;
    sides.reserve(static_cast<std::size_t>(3 * m));
    for (Index k = 0; k < m; ++k)
        for (int j = 0; j < 3; ++j) {
            const Index a = contact.triangles[3 * k + j], b = contact.triangles[3 * k + (j + 1) % 3];
            sides.emplace_back(std::min(a, b), std::max(a, b));
        }
    std::sort(sides.begin(), sides.end());
    lists.flat_rim.assign(static_cast<std::size_t>(t.nx * t.ny), 0);
    for (std::size_t i = 0; i < sides.size();) {
        std::size_t j = i + 1;
        while (j < sides.size() && sides[j] == sides[i]) ++j;
        if (j - i == 1) lists.flat_rim[t.cell[sides[i].first]] = lists.flat_rim[t.cell[sides[i].second]] = 1;
        i = j;
    }
}

//: Each triangle's figures (TriangleFigure) at positions x, into `figures`; false if one is not finite (or a
//: triangle has no area).
bool triangle_figures(const Contact& contact, Index n, const double* x, std::vector<double>& figures) {
    const Index m = contact.triangle_count;
    const double* inverse = contact.lists->flat_inverse.data();
    figures.resize(static_cast<std::size_t>(T_FIGURES * m));
    bool finite = true;
    for (Index k = 0; k < m; ++k) {
        const Index* p = contact.triangles + 3 * k;
        const Vec3 a = point(x, n, p[0]), b = point(x, n, p[1]), c = point(x, n, p[2]);
        const Vec3 e1 = sub(b, a), e2 = sub(c, a), e3 = sub(c, b);
        const Vec3 normal = cross(e1, e2);
        const double twice_area = norm(normal);
        const double longest = std::sqrt(py_max(py_max(dot(e1, e1), dot(e2, e2)), dot(e3, e3)));
        const double* inv = inverse + 4 * k;
        double* f = figures.data() + T_FIGURES * k;
        const double rows[3][2] = {{e1.x, e2.x}, {e1.y, e2.y}, {e1.z, e2.z}};
        double size = 0.0;
        for (int d = 0; d < 3; ++d) {
            f[T_JACOBIAN + 2 * d] = rows[d][0] * inv[0] + rows[d][1] * inv[2];
            f[T_JACOBIAN + 2 * d + 1] = rows[d][0] * inv[1] + rows[d][1] * inv[3];
            size += std::fabs(f[T_JACOBIAN + 2 * d]) + std::fabs(f[T_JACOBIAN + 2 * d + 1]);
        }
        f[T_NORMAL] = normal.x / twice_area, f[T_NORMAL + 1] = normal.y / twice_area, f[T_NORMAL + 2] = normal.z / twice_area;
        f[T_ALTITUDE] = twice_area / longest;
        f[T_AREA] = twice_area;
        finite = finite && twice_area > 0.0 && std::isfinite(twice_area) && std::isfinite(size);
    }
    return finite;
}

//: Tier t's cells' figures (CellFigure, C_FIGURES each) from the triangles' (each in the cell of its first
//: particle), into `cells`.
void cell_figures(const Contact& contact, const Tier& t, const std::vector<double>& figures, std::vector<double>& cells) {
    const Index m = contact.triangle_count, count = t.nx * t.ny;
    cells.assign(static_cast<std::size_t>(C_FIGURES * count), 0.0);
    for (Index c = 0; c < count; ++c) cells[c * C_FIGURES + C_CONE] = 1.0, cells[c * C_FIGURES + C_ALTITUDE] = INF;
    for (Index k = 0; k < m; ++k) {
        const double* f = figures.data() + T_FIGURES * k;
        double* cell = cells.data() + t.cell[contact.triangles[3 * k]] * C_FIGURES;
        cell[C_COUNT] += 1.0;
        for (int d = 0; d < 3; ++d) cell[C_NORMAL + d] += f[T_NORMAL + d] * f[T_AREA];
        for (int j = 0; j < 6; ++j) cell[C_JACOBIAN + j] += f[T_JACOBIAN + j];
        cell[C_ALTITUDE] = py_min(cell[C_ALTITUDE], f[T_ALTITUDE]);
    }
    // Each cell's spread about its mean Jacobian and its normals' cone about their sum.
    for (Index k = 0; k < m; ++k) {
        const double* f = figures.data() + T_FIGURES * k;
        double* cell = cells.data() + t.cell[contact.triangles[3 * k]] * C_FIGURES;
        const double inv_count = 1.0 / cell[C_COUNT];
        double spread = 0.0;
        for (int j = 0; j < 6; ++j) {
            const double d = f[T_JACOBIAN + j] - cell[C_JACOBIAN + j] * inv_count;
            spread += d * d;
        }
        cell[C_SPREAD] = py_max(cell[C_SPREAD], std::sqrt(spread));
        const Vec3 axis = {cell[C_NORMAL], cell[C_NORMAL + 1], cell[C_NORMAL + 2]};
        const double length = norm(axis);
        const double cosine = length > 0.0 ? (f[T_NORMAL] * axis.x + f[T_NORMAL + 1] * axis.y + f[T_NORMAL + 2] * axis.z) / length : -1.0;
        cell[C_CONE] = py_min(cell[C_CONE], cosine);
    }
}

//: cos(a + b) from cos a and cos b (both angles in [0, pi]).
inline double cosine_of_sum(double cos_a, double cos_b) {
    const double sin_a = std::sqrt(py_max(0.0, 1.0 - cos_a * cos_a)), sin_b = std::sqrt(py_max(0.0, 1.0 - cos_b * cos_b));
    return cos_a * cos_b - sin_a * sin_b;
}

//: Whether window (wx, wy) of tier t (`wide_x` x `wide_y` cells, figures `cells`) is shown to hold no pair within
//: `reach` (m): its pairs lie at least `apart_at_rest` (m) apart in the rest sheet; `rim` (per cell, or null):
//: the projected altitudes are also tried for a window none of whose cells holds a particle of the rim.
bool shown(const Tier& t, const double* cells, Index wx, Index wy, Index wide_x, Index wide_y, double reach,
           double apart_at_rest, const char* rim) {
    // The window's cells and the ring around them.
    const Index x0 = wx > 0 ? wx - 1 : 0, x1 = std::min(wx + wide_x, t.nx - 1);
    const Index y0 = wy > 0 ? wy - 1 : 0, y1 = std::min(wy + wide_y, t.ny - 1);
    double count = 0.0, normal[3] = {0.0, 0.0, 0.0}, mean[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    for (Index cy = y0; cy <= y1; ++cy)
        for (Index cx = x0; cx <= x1; ++cx) {
            const double* c = cells + (cx + t.nx * cy) * C_FIGURES;
            count += c[C_COUNT];
            for (int d = 0; d < 3; ++d) normal[d] += c[C_NORMAL + d];
            for (int j = 0; j < 6; ++j) mean[j] += c[C_JACOBIAN + j];
        }
    const double length = std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(count > 0.0) || !(length > 0.0)) return false;
    const Vec3 nu = {normal[0] / length, normal[1] / length, normal[2] / length};
    for (double& v : mean) v /= count;
    // The plane across nu: t1 across nu and the axis least along it, t2 = nu x t1.
    const Vec3 axis = std::fabs(nu.x) <= std::fabs(nu.y) && std::fabs(nu.x) <= std::fabs(nu.z) ? Vec3{1.0, 0.0, 0.0}
                      : std::fabs(nu.y) <= std::fabs(nu.z)                                   ? Vec3{0.0, 1.0, 0.0}
                                                                                              : Vec3{0.0, 0.0, 1.0};
    Vec3 t1 = cross(nu, axis);
    const double l1 = norm(t1);
    t1 = {t1.x / l1, t1.y / l1, t1.z / l1};
    const Vec3 t2 = cross(nu, t1);
    // A: the mean Jacobian projected onto the plane (2 x 2); its least singular value.
    double a[4];
    for (int k = 0; k < 2; ++k) {
        a[k] = t1.x * mean[k] + t1.y * mean[2 + k] + t1.z * mean[4 + k];
        a[2 + k] = t2.x * mean[k] + t2.y * mean[2 + k] + t2.z * mean[4 + k];
    }
    const double frobenius = a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + a[3] * a[3], det = a[0] * a[3] - a[1] * a[2];
    const double sigma_min =
        std::sqrt(py_max(0.0, 0.5 * (frobenius - std::sqrt(py_max(0.0, frobenius * frobenius - 4.0 * det * det)))));
    // eps: how far any triangle's Jacobian lies from the mean (projection shortens no difference); and the
    // triangles' projected altitudes: at least a cell's least altitude times the cosine of the largest angle
    // between one of its normals and nu (its cone about its axis, and the axis's angle).
    double eps = 0.0, height = INF;
    for (Index cy = y0; cy <= y1; ++cy)
        for (Index cx = x0; cx <= x1; ++cx) {
            const double* c = cells + (cx + t.nx * cy) * C_FIGURES;
            if (c[C_COUNT] == 0.0) continue;
            double off = 0.0;
            for (int j = 0; j < 6; ++j) {
                const double d = c[C_JACOBIAN + j] / c[C_COUNT] - mean[j];
                off += d * d;
            }
            eps = py_max(eps, c[C_SPREAD] + std::sqrt(off));
            const double cell_length = std::sqrt(c[C_NORMAL] * c[C_NORMAL] + c[C_NORMAL + 1] * c[C_NORMAL + 1] +
                                                 c[C_NORMAL + 2] * c[C_NORMAL + 2]);
            const double cos_axis = (c[C_NORMAL] * nu.x + c[C_NORMAL + 1] * nu.y + c[C_NORMAL + 2] * nu.z) / cell_length;
            const double cosine = cos_axis > 0.0 && c[C_CONE] > 0.0 ? cosine_of_sum(cos_axis, c[C_CONE]) : 0.0;
            height = py_min(height, c[C_ALTITUDE] * py_max(0.0, cosine));
        }
    const double need = reach * (1.0 + SURELY);
    const double stretch = sigma_min - eps;  // the map's least stretch over the window's neighbourhood
    if (stretch * apart_at_rest >= need) return true;
    if (rim == nullptr || !(stretch > 0.0)) return false;
    for (Index cy = wy; cy < wy + wide_y; ++cy)
        for (Index cx = wx; cx < wx + wide_x; ++cx)
            if (rim[cx + t.nx * cy]) return false;
    return height >= need;
}

//: Call visit(wx, wy) for each window of tier t (WINDOW x WINDOW cells, or all along an axis with fewer).
template <class Visit>
void for_windows(const Tier& t, Visit visit) {
    const Index wide_x = std::min(WINDOW, t.nx), wide_y = std::min(WINDOW, t.ny);
    for (Index wy = 0; wy + wide_y <= t.ny; ++wy)
        for (Index wx = 0; wx + wide_x <= t.nx; ++wx) visit(wx, wy, wide_x, wide_y);
}

}  // namespace

FlatWindows::FlatWindows(const Contact& contact, Index n, const double* x, double reach, bool tried)
    : contact_(contact), n_(n), reach_(reach) {
    if (!tried) return;
    prepare_rest(contact, n);
    judged_ = contact.lists->flat_convex && triangle_figures(contact, n, x, contact.lists->flat_triangles);
}

const double* FlatWindows::cells_of(int s) {
    std::vector<std::vector<double>>& cells = contact_.lists->flat_cells;
    if (cells.size() != static_cast<std::size_t>(LOCAL_TIERS)) cells.assign(LOCAL_TIERS, {});
    if (!figured_[s]) cell_figures(contact_, tier_of(contact_, n_, s), contact_.lists->flat_triangles, cells[s]);
    figured_[s] = true;
    return cells[s].data();
}

Index FlatWindows::unproven(std::vector<char>& inside, Index& windows) {
    const Tier t = tier_of(contact_, n_, 0);
    const double* cells = cells_of(0);
    const char* rim = contact_.lists->flat_rim.data();
    inside.assign(static_cast<std::size_t>(n_), 0);
    windows = 0;
    Index unproven = 0;
    for_windows(t, [&](Index wx, Index wy, Index wide_x, Index wide_y) {
        windows += 1;
        if (shown(t, cells, wx, wy, wide_x, wide_y, reach_, contact_.rest_gap, rim)) return;
        unproven += 1;
        for (Index cy = wy; cy < wy + wide_y; ++cy)
            for (Index cx = wx; cx < wx + wide_x; ++cx) {
                const Index c = cx + t.nx * cy;
                for (Index q = t.start[c]; q < t.start[c + 1]; ++q) inside[t.members[q]] = 1;
            }
    });
    return unproven;
}

int FlatWindows::shown_through() {
    int through = 0;
    for (int s = 1; s < LOCAL_TIERS; ++s) {
        const Tier t = tier_of(contact_, n_, s);
        const double* cells = cells_of(s);
        const double apart = rest_distance_beyond(contact_, n_, s - 1);
        bool all = true;
        for_windows(t, [&](Index wx, Index wy, Index wide_x, Index wide_y) {
            all = all && shown(t, cells, wx, wy, wide_x, wide_y, reach_, apart, nullptr);
        });
        if (!all) break;
        through = s;
    }
    return through;
}

}  // namespace wc::self_contact
