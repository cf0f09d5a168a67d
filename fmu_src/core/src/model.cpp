// The native model (model.hpp): scene, topology, per-particle constants, control and storage.
#include "wetcloth/model.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <type_traits>

#include "wetcloth/byte_record.hpp"
#include "wetcloth/collider_mesh.hpp"
#include "wetcloth/collider_motion.hpp"
#include "wetcloth/colliders.hpp"
#include "wetcloth/grip.hpp"
#include "wetcloth/implicit.hpp"
#include "wetcloth/integration.hpp"
#include "wetcloth/multigrid.hpp"
#include "wetcloth/plane.hpp"
#include "wetcloth/reused_plane.hpp"
#include "wetcloth/self_contact.hpp"
#include "wetcloth/stepping.hpp"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "snapshots are written in the host's (little-endian) order");

namespace wc {

namespace {

constexpr double PI = 3.141592653589793;  // math.pi
constexpr double INF = std::numeric_limits<double>::infinity();
constexpr double NaN = std::numeric_limits<double>::quiet_NaN();

//: Python's max(a, b) and min(a, b): the first argument unless the second is strictly beyond it.
inline double pymax(double a, double b) { return b > a ? b : a; }
inline double pymin(double a, double b) { return b < a ? b : a; }

//: x ** 2 as Python and NumPy compute it (libm's pow, not folded into x * x by the compiler).
double square_as_python(double x) {
    double (*volatile power)(double, double) = std::pow;
    return power(x, 2.0);
}

//: NumPy's max and min of an array (NaN if any value is NaN).
double np_max(const std::vector<double>& a) {
    double best = -INF;
    for (double v : a) {
        if (std::isnan(v)) return NaN;
        if (v > best) best = v;
    }
    return best;
}

double np_min(const std::vector<double>& a) {
    double best = INF;
    for (double v : a) {
        if (std::isnan(v)) return NaN;
        if (v < best) best = v;
    }
    return best;
}

//: Multigrid (plane.py's MULTIGRID_SIDE, COARSEST_SIDE) and the preconditioner's shares and stencil slots
//: of each family (plane.py's _SHARE, _SLOT; the bending families are left out).
constexpr double SHARE[6][2] = {{1.0, 0.0}, {0.0, 1.0}, {0.5, 0.5}, {0.5, 0.5}, {0.0, 0.0}, {0.0, 0.0}};
constexpr Index SLOT[6] = {5, 7, 8, 6, -1, -1};

constexpr char SNAPSHOT_MAGIC[] = "wetcloth-native-snapshot\n";
constexpr std::size_t MAGIC_SIZE = sizeof(SNAPSHOT_MAGIC) - 1;
//: 4: the reused Jacobian systems' rule and source; 3: the scene's 44 fields (pinned_vertices, grip_x/y/z); 2: 40
//: (wind).
constexpr std::uint32_t SNAPSHOT_VERSION = 4;
constexpr std::size_t PREAMBLE = MAGIC_SIZE + 4 + 8;  // magic, version, checksum

//: Whether an nx x ny grid's preconditioner has a multigrid hierarchy, and so reused Jacobian systems.
bool multigrid(Index nx, Index ny) { return std::min(nx, ny) > MULTIGRID_SIDE; }

//: Where each kept array starts in `values` (doubles), and at [KEPT] their end, for n particles, `along`
//: entries of the springs' Jacobian and a reused systems' source of `source` doubles.
KeptOffsets kept_offsets(std::size_t n, std::size_t along, std::size_t source) {
    const std::size_t rule = REUSE_RULE_SIZE;
    const std::size_t sizes[KEPT] = {3 * n, 3 * n, n, 3 * n, 3 * n, n, 3 * n, 3 * n, n, along, n, 3 * n, rule, source};
    KeptOffsets at{};
    for (int k = 0; k < KEPT; ++k) at[k + 1] = at[k] + sizes[k];
    return at;
}

//: Doubles of a checkpoint's `values` for an nx x ny grid and F spring families (see Checkpoint).
std::size_t value_count(Index nx, Index ny, Index families) {
    const Index n = nx * ny;
    const Index source = multigrid(nx, ny) ? reused_source_size(n, families) : 0;
    return kept_offsets(static_cast<std::size_t>(n), static_cast<std::size_t>(families * n),
                        static_cast<std::size_t>(source))[KEPT];
}

}  // namespace

// ------------------------------------------------------------------------------------------ scene
namespace {

//: The fields' values in SCENE_FIELDS order (codes and counts exactly, as doubles).
std::vector<double> field_values(const Scene& scene) {
    std::vector<double> values;
    values.reserve(SCENE_FIELD_COUNT);
    for_each_field(scene, [&](const char*, const auto& v) { values.push_back(static_cast<double>(v)); });
    return values;
}

}  // namespace

std::string fixed_differences(const Scene& a, const Scene& b) {
    const std::vector<double> x = field_values(a), y = field_values(b);
    std::string text;
    for (Index k = 0; k < SCENE_FIELD_COUNT; ++k) {
        if (!scene_input(SCENE_FIELDS[k]) && !(x[k] == y[k])) text += (text.empty() ? "" : ", ") + std::string(SCENE_FIELDS[k]);
    }
    return text;
}

std::string grid_rigidity_problem(const Scene& s) {
    if (s.bend_rigidity == 0.0) return "";
    return "parameter 'bend_rigidity': " + py_repr(s.bend_rigidity) + " N m bends by hinges; allowed: 0 N m in this "
           "native unit of the built-in grid, built without hinges (it bends by its springs, bend_stiffness); for "
           "hinges build it from a scene with bend_rigidity > 0 (wetcloth build-fmu --native --scene)";
}

std::string scene_problem(const Scene& s, const ClothMesh* mesh, const Pins* pins) {
    if (mesh != nullptr) return mesh_scene_problem(s, *mesh, pins);
    const std::string rigidity = grid_rigidity_problem(s);
    if (!rigidity.empty()) return rigidity;
    return grid_start_problem(s, pins);
}

//: "" or the ParameterError's text of a grid whose cells are more than LONGEST_CELL times longer one way than
//: the other, naming the particle counts that would make them squarer.
std::string grid_cells_problem(const Scene& s) {
    const double dx = s.width / static_cast<double>(s.nx - 1), dy = s.length / static_cast<double>(s.ny - 1);
    const double longer = std::max(dx, dy), shorter = std::min(dx, dy);
    if (longer <= LONGEST_CELL * shorter) return "";
    const bool across_y = dy < dx;  // the short side is y's: fewer particles along y, or more along x
    const std::string short_name = across_y ? "ny" : "nx", long_name = across_y ? "nx" : "ny";
    const auto fewest = static_cast<long long>(std::floor((across_y ? s.length : s.width) * LONGEST_CELL / longer)) + 1;
    const auto most = static_cast<long long>(std::ceil((across_y ? s.width : s.length) / (LONGEST_CELL * shorter))) + 1;
    std::string fixes;
    if (fewest >= 2) fixes = short_name + " <= " + std::to_string(fewest) + ", ";
    if (most <= MOST_ALONG) fixes += long_name + " >= " + std::to_string(most) + ", ";
    const std::string& name = fewest < 2 && most <= MOST_ALONG ? long_name : short_name;  // the first fix's count
    const auto ratio = static_cast<long long>(std::nearbyint(longer / shorter));  // Python's round: half to even
    return "parameter '" + name + "': the grid's cells are " + std::to_string(ratio) +
           " times longer one way than the other (width/(nx-1) = " + py_g(dx, 3) + " m, length/(ny-1) = " +
           py_g(dy, 3) + " m): the springs across them would be that squared stiffer than along; allowed: at most " +
           py_g(LONGEST_CELL) + " times (" + fixes + "or change width or length)";
}

std::string grid_start_problem(const Scene& s, const Pins* pins) {
    const std::string cells = grid_cells_problem(s);
    if (!cells.empty()) return cells;
    const double half_drop = 0.5 * s.length * std::fabs(std::sin(s.initial_tilt * (PI / 180.0)));
    const double lowest = s.initial_height - half_drop - 0.5 * s.thickness;
    if (lowest <= s.floor_level) {
        return "parameter 'initial_height': the cloth starts at or below the floor (lowest point " + py_g(lowest) +
               " m, floor_level " + py_g(s.floor_level) + " m); allowed: initial_height > floor_level + " +
               py_g(half_drop + 0.5 * s.thickness) + " m";
    }
    if (pins == nullptr || s.nx < 2 || s.ny < 2) return "";
    std::vector<char> pinned(static_cast<std::size_t>(s.nx * s.ny), 0);
    return pins->pin(s.nx * s.ny, grid_start(s).data(), pinned);
}

std::string stability_problem(const Control& control) {
    const double stable = stable_step(control, 0.0);  // (infinite for the implicit schemes)
    if (!(stable < control.smallest_step)) return "";
    // What sets the bound (stable_step): the damping rate (1/s: the springs' and the drag's at rest) or the
    // frequency (rad/s: the springs'; the buoyancy's stays below 2e4 rad/s within the parameters' ranges).
    const double gamma = control.damping_rate + control.drag_rate_offset;
    const double omega = std::sqrt(control.omega_squared + control.buoyancy_omega_squared);
    const bool by_rate =
        control.integrator == EXPLICIT_EULER ? 2.0 / gamma <= control.spring_limit : gamma >= 2.0 * omega;
    std::string cause, fix;
    if (by_rate && control.damping_rate >= control.drag_rate_offset) {
        cause = "the springs' damping (parameter damping: a rate of " + py_g(control.damping_rate, 2) + " 1/s)";
        fix = "less damping";
    } else if (by_rate) {
        cause = "the drag at rest (water_density, the drag coefficients, the current, the wind, water_viscosity for "
                "Stokes drag, over areal_density: a rate of " + py_g(control.drag_rate_offset, 2) + " 1/s)";
        fix = "less drag";
    } else {
        cause = "the springs' stiffness over the particles' masses (stretch_stiffness, bend_stiffness, areal_density, "
                "the cloth's cells: up to " + py_g(omega, 2) + " rad/s)";
        fix = "softer springs or larger cells";
    }
    return "parameter 'integrator': " + py_repr(std::string_view(INTEGRATOR_NAMES[control.integrator])) +
           " is stable on this cloth only at steps up to " + py_g(stable, 2) + " s, below the smallest step (" +
           py_g(control.smallest_step) + " s), set by " + cause + "; allowed: 'bdf2' or 'implicit_euler' (stable at "
           "any step), or an explicit scheme with " + fix;
}

std::vector<double> grid_start(const Scene& scene) {
    const Index nx = scene.nx, n = scene.nx * scene.ny;
    const double dx = scene.width / static_cast<double>(nx - 1);
    const double dy = scene.length / static_cast<double>(scene.ny - 1);
    const double tilt = scene.initial_tilt * (PI / 180.0);  // math.radians
    const double cos_tilt = std::cos(tilt), sin_tilt = std::sin(tilt);
    std::vector<double> pos(3 * static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i) {
        const double x = static_cast<double>(i % nx) * dx - 0.5 * scene.width;  // Topology.rest_xy
        const double y = static_cast<double>(i / nx) * dy - 0.5 * scene.length;
        pos[i] = x;
        pos[n + i] = y * cos_tilt;
        pos[2 * n + i] = scene.initial_height + y * sin_tilt;
    }
    return pos;
}

// ------------------------------------------------------------------------------------------ formatting
std::string py_repr(double value) {
    if (std::isnan(value)) return "nan";
    if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
    if (value == 0.0) return std::signbit(value) ? "-0.0" : "0.0";
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::scientific);
    const std::string text(buffer, result.ptr);  // shortest round trip: [-]d[.ddd]e[+-]XX
    const std::size_t e = text.find('e');
    std::string mantissa = text.substr(0, e);
    const int exponent = std::stoi(text.substr(e + 1));
    const bool negative = mantissa[0] == '-';
    if (negative) mantissa.erase(0, 1);
    std::string digits;
    for (char c : mantissa) {
        if (c != '.') digits += c;
    }
    const int point = exponent + 1;  // value = 0.digits x 10^point
    std::string out;
    if (point <= -4 || point > 16) {  // Python's repr: exponent notation, at least two exponent digits
        out = digits.substr(0, 1);
        if (digits.size() > 1) out += "." + digits.substr(1);
        char tail[16];
        std::snprintf(tail, sizeof(tail), "e%c%02d", exponent < 0 ? '-' : '+', std::abs(exponent));
        out += tail;
    } else if (point <= 0) {
        out = "0." + std::string(static_cast<std::size_t>(-point), '0') + digits;
    } else if (static_cast<std::size_t>(point) >= digits.size()) {
        out = digits + std::string(static_cast<std::size_t>(point) - digits.size(), '0') + ".0";
    } else {
        out = digits.substr(0, point) + "." + digits.substr(point);
    }
    return negative ? "-" + out : out;
}

std::string py_repr(std::string_view text) {
    const bool double_quotes = text.find('\'') != std::string_view::npos && text.find('"') == std::string_view::npos;
    const char quote = double_quotes ? '"' : '\'';
    std::string out(1, quote);
    for (char c : text) {
        if (c == '\\' || c == quote) out += '\\';
        if (c == '\n') {
            out += "\\n";
            continue;
        }
        out += c;
    }
    return out + quote;
}

std::string py_g(double value, int precision) {
    if (std::isnan(value)) return "nan";
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.*g", precision, value);
    return buffer;
}

// ------------------------------------------------------------------------------------------ topology
std::vector<double> Topology::per_particle_sum(const double* per_spring, const std::vector<Index>& offsets) const {
    std::vector<double> total(static_cast<std::size_t>(n), 0.0);
    for (std::size_t f = 0; f < offsets.size(); ++f) {
        const Index off = offsets[f];
        const double* values = per_spring + f * static_cast<std::size_t>(n);
        for (Index i = 0; i < n - off; ++i) total[i] += values[i];
        for (Index i = 0; i < n - off; ++i) total[i + off] += values[i];
    }
    return total;
}

Topology build_topology(const Scene& scene, const ClothMesh* mesh, const Pins* pins) {
    return mesh != nullptr ? mesh_topology(scene, *mesh, pins) : grid_topology(scene, pins);
}

bool on_pinned_edge(const Scene& scene, Index i) {
    const Index col = i % scene.nx, row = i / scene.nx;
    return (scene.pinned_edge == EDGE_X_MIN && col == 0) || (scene.pinned_edge == EDGE_X_MAX && col == scene.nx - 1) ||
           (scene.pinned_edge == EDGE_Y_MIN && row == 0) || (scene.pinned_edge == EDGE_Y_MAX && row == scene.ny - 1);
}

Topology grid_topology(const Scene& scene, const Pins* pins) {
    if (scene.nx < 2 || scene.ny < 2) {
        throw std::invalid_argument("the grid needs at least 2 x 2 particles, got " + std::to_string(scene.nx) +
                                    " x " + std::to_string(scene.ny));
    }
    Topology t;
    const Index nx = scene.nx, ny = scene.ny, n = nx * ny;
    t.nx = nx;
    t.ny = ny;
    t.n = n;
    t.size = pymax(scene.width, scene.length);
    t.dx = scene.width / static_cast<double>(nx - 1);
    t.dy = scene.length / static_cast<double>(ny - 1);
    const double dx = t.dx, dy = t.dy;
    std::vector<Index> col(n), row(n);
    std::vector<double> wc(n), wr(n);  // a particle's share of the cells along each axis: 1/2 on the edges
    t.rest_xy.resize(2 * n);
    t.area.resize(n);
    for (Index i = 0; i < n; ++i) {
        col[i] = i % nx;
        row[i] = i / nx;
        wc[i] = (col[i] == 0 || col[i] == nx - 1) ? 0.5 : 1.0;
        wr[i] = (row[i] == 0 || row[i] == ny - 1) ? 0.5 : 1.0;
        t.rest_xy[i] = static_cast<double>(col[i]) * dx - 0.5 * scene.width;
        t.rest_xy[n + i] = static_cast<double>(row[i]) * dy - 0.5 * scene.length;
        t.area[i] = dx * dy * wc[i] * wr[i];
    }
    // Each spring stands for a strip of the sheet of area a_s; with rest length l its constant is
    // k = stiffness * a_s / l**2, likewise for damping (topology.py).
    const double diag = std::hypot(dx, dy);
    for (Index family = STRUCTURAL_X; family <= BEND_Y; ++family) {
        const bool bending = family == BEND_X || family == BEND_Y;
        const double modulus = bending ? scene.bend_stiffness : scene.stretch_stiffness;
        Index offset = 0;
        double rest = 0.0;
        switch (family) {
            case STRUCTURAL_X: offset = 1; rest = dx; break;
            case STRUCTURAL_Y: offset = nx; rest = dy; break;
            case SHEAR_UP_RIGHT: offset = nx + 1; rest = diag; break;
            case SHEAR_UP_LEFT: offset = nx - 1; rest = diag; break;
            case BEND_X: offset = 2; rest = 2 * dx; break;
            default: offset = 2 * nx; rest = 2 * dy; break;
        }
        std::vector<double> strip(n);
        std::vector<char> exists(n);
        bool any = false;
        for (Index i = 0; i < n; ++i) {
            switch (family) {
                case STRUCTURAL_X: strip[i] = dx * dy * wr[i]; exists[i] = col[i] < nx - 1; break;
                case STRUCTURAL_Y: strip[i] = dy * dx * wc[i]; exists[i] = row[i] < ny - 1; break;
                case SHEAR_UP_RIGHT:
                    strip[i] = 0.5 * dx * dy;
                    exists[i] = col[i] < nx - 1 && row[i] < ny - 1;
                    break;
                case SHEAR_UP_LEFT:
                    strip[i] = 0.5 * dx * dy;
                    exists[i] = col[i] > 0 && row[i] < ny - 1;
                    break;
                case BEND_X: strip[i] = 2 * dx * dy * wr[i]; exists[i] = col[i] < nx - 2; break;
                default: strip[i] = 2 * dy * dx * wc[i]; exists[i] = row[i] < ny - 2; break;
            }
            any = any || exists[i];
        }
        if (modulus == 0.0 || !any) continue;
        const double rest2 = square_as_python(rest);
        t.family.push_back(family);
        t.offset.push_back(offset);
        t.rest.push_back(rest);
        for (Index i = 0; i < n; ++i) {
            t.stiffness.push_back(exists[i] ? modulus * strip[i] / rest2 : 0.0);
            t.damping.push_back(exists[i] ? scene.damping * strip[i] / rest2 : 0.0);
            t.shape.push_back(exists[i] ? strip[i] / rest2 : 0.0);
        }
    }
    const Index families = t.families();
    t.tension_only.reset(new bool[static_cast<std::size_t>(std::max<Index>(families, 1))]);
    for (Index f = 0; f < families; ++f) t.tension_only[f] = t.family[f] != BEND_X && t.family[f] != BEND_Y;

    std::vector<Index> quads;
    for (Index i = 0; i < n; ++i) {
        if (col[i] < nx - 1 && row[i] < ny - 1) quads.push_back(i);
    }
    t.triangles.reserve(6 * quads.size());
    for (Index a : quads) t.triangles.insert(t.triangles.end(), {a, a + 1, a + nx + 1});
    for (Index a : quads) t.triangles.insert(t.triangles.end(), {a, a + nx + 1, a + nx});

    t.free.assign(n, 1.0);
    for (Index i = 0; i < n; ++i) {
        if (on_pinned_edge(scene, i)) t.free[i] = 0.0;
    }
    t.start = grid_start(scene);
    if (pins != nullptr) {  // pinned_vertices' box, over the start positions
        std::vector<char> pinned(static_cast<std::size_t>(n), 0);
        const std::string problem = pins->pin(n, t.start.data(), pinned);
        if (!problem.empty()) throw std::invalid_argument(problem);
        for (Index i = 0; i < n; ++i) {
            if (pinned[i]) t.free[i] = 0.0;
        }
    }
    return t;
}

std::vector<Index> grid_edges(const std::vector<Index>& triangles) {
    std::vector<std::pair<Index, Index>> edges;
    const std::size_t m = triangles.size() / 3;
    edges.reserve(3 * m);
    for (int k = 0; k < 3; ++k) {  // the edges [0, 1], then [1, 2], then [2, 0] of every triangle
        for (std::size_t t = 0; t < m; ++t) {
            const Index a = triangles[3 * t + k], b = triangles[3 * t + (k + 1) % 3];
            edges.emplace_back(std::min(a, b), std::max(a, b));
        }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    std::vector<Index> flat;
    flat.reserve(2 * edges.size());
    for (const auto& [a, b] : edges) flat.insert(flat.end(), {a, b});
    return flat;
}

std::vector<std::pair<Index, Index>> level_sizes(Index nx, Index ny, Index coarsest_side) {
    std::vector<std::pair<Index, Index>> sizes{{nx, ny}};
    while (std::min(sizes.back().first, sizes.back().second) > coarsest_side) {
        const auto [cx, cy] = sizes.back();
        sizes.emplace_back(cx / 2 + 1, cy / 2 + 1);
    }
    return sizes;
}

// ------------------------------------------------------------------------------------------ fixtures
ColliderMeshes Fixtures::meshes() const {
    ColliderMeshes m;
    if (mesh_headers.empty()) return m;
    m.count = static_cast<Index>(mesh_headers.size() / MESH_COLUMNS);
    m.vertex_count = static_cast<Index>(mesh_vertices.size() / 3);
    m.headers = mesh_headers.data();
    m.vertices = mesh_vertices.data();
    m.triangles = mesh_triangles.data();
    m.face_normals = face_normals.data();
    m.edge_normals = edge_normals.data();
    m.vertex_normals = vertex_normals.data();
    m.cell_start = cell_start.data();
    m.cell_items = cell_items.data();
    return m;
}

namespace {

inline constexpr const char* SHAPE_NAMES[] = {"plane", "box", "sphere", "cylinder", "mesh"};

//: Topology.per_particle_pair_sum of a mesh's per-listed-spring `values` (S): np.bincount onto the first
//: ends plus np.bincount onto the second ends, over the stretch springs alone if `stretch_only`; empty for
//: a grid.
std::vector<double> pair_sum(const Topology& topo, const double* values, bool stretch_only) {
    if (topo.mesh == nullptr) return {};
    const ClothMesh& m = *topo.mesh;
    const std::size_t count = m.pair_rest.size(), n = static_cast<std::size_t>(topo.n);
    std::vector<double> first(n, 0.0), second(n, 0.0);
    for (std::size_t k = 0; k < count; ++k) {
        first[m.pairs[k]] += stretch_only && m.pair_kind[k] != PAIR_STRETCH ? 0.0 : values[k];
    }
    for (std::size_t k = 0; k < count; ++k) {
        second[m.pairs[count + k]] += stretch_only && m.pair_kind[k] != PAIR_STRETCH ? 0.0 : values[k];
    }
    for (std::size_t i = 0; i < n; ++i) first[i] = first[i] + second[i];
    return first;
}

//: scene._check_collider_start: "" or the ParameterError's text of every collider closer than thickness / 2
//: to a particle at `pos` (3, n) m, one line each ("parameter 'collider1': the sphere overlaps ...").
std::string collider_overlaps(const Physics& phys, Index n, const double* pos) {
    const double gap = 0.5 * phys.thickness;
    std::vector<std::string> lines;
    for (Index k = 0; k < phys.collider_count; ++k) {
        double nearest = INF, normal[3];
        Index at = 0;
        for (Index i = 0; i < n; ++i) {
            const double p[3] = {pos[i], pos[n + i], pos[2 * n + i]};
            const double d = collider_distance(phys, k, p, 2.0 * gap, normal);
            if (d < nearest) nearest = d, at = i;  // the first of the nearest, as numpy's argmin
        }
        if (!(nearest < gap * (1.0 - 1e-9))) continue;
        const Index shape = static_cast<Index>(phys.colliders[k * COLLIDER_COLUMNS + C_SHAPE]);
        lines.push_back("parameter 'collider" + std::to_string(k + 1) + "': the " + SHAPE_NAMES[shape] +
                        " overlaps the cloth at t = 0 (particle " + std::to_string(at) + " at (" + py_g(pos[at]) +
                        ", " + py_g(pos[n + at]) + ", " + py_g(pos[2 * n + at]) + ") m is " + py_g(nearest) +
                        " m from its surface); allowed: every particle at least thickness/2 = " + py_g(gap) +
                        " m outside it (move the collider or the cloth: initial_height)");
    }
    if (lines.size() == 1) return lines[0];
    std::string text = lines.empty() ? "" : std::to_string(lines.size()) + " mistakes";
    for (const std::string& line : lines) text += "\n  " + line;
    return text;
}

}  // namespace

// ------------------------------------------------------------------------------------------ simulation
Simulation::Simulation(const Scene& scene, Fixtures fixtures)
    : scene_(fixtures.cloth_mesh != nullptr ? fixtures.cloth_mesh->on_grid(scene) : scene),
      fixtures_(std::move(fixtures)), topo_(build_topology(scene_, fixtures_.cloth_mesh.get(), fixtures_.pins.get())) {
    const ClothMesh* mesh = topo_.mesh;  // null for the grid, also a file's that forms it
    const std::string problem = scene_problem(scene_, fixtures_.cloth_mesh.get(), fixtures_.pins.get());
    if (!problem.empty()) throw std::invalid_argument(problem);
    const Index n = topo_.n, families = topo_.families();
    const std::size_t un = static_cast<std::size_t>(n);

    // Model: the per-particle constants (set_scene fills them), the wicking links.
    dry_mass_.assign(un, 0.0);
    volume_.assign(un, 0.0);
    stokes_.assign(un, 0.0);
    capacity_.assign(un, 0.0);
    for (Index f = 0; f < families; ++f) {
        if (topo_.family[f] == STRUCTURAL_X || topo_.family[f] == STRUCTURAL_Y) wick_offsets_.push_back(topo_.offset[f]);
    }
    wick_conductance_.assign(wick_offsets_.size() * un, 0.0);

    Cloth& cloth = core_.cloth;
    cloth.grid_x = topo_.nx;
    cloth.grid_y = topo_.ny;
    cloth.n = n;
    cloth.families = families;
    cloth.offsets = topo_.offset.data();
    cloth.rest = topo_.rest.data();
    cloth.tension_only = topo_.tension_only.get();
    cloth.stiffness = topo_.stiffness.data();
    cloth.damping = topo_.damping.data();
    cloth.free = topo_.free.data();
    cloth.dry_mass = dry_mass_.data();
    cloth.volume = volume_.data();
    cloth.stokes_coefficient = stokes_.data();
    cloth.capacity = capacity_.data();
    cloth.wick_families = static_cast<Index>(wick_offsets_.size());
    cloth.wick_offsets = wick_offsets_.data();
    cloth.wick_conductance = wick_conductance_.data();
    if (mesh != nullptr) {  // listed springs and wicking links, face drag over the mesh's triangles (Model)
        cloth.grid_x = cloth.grid_y = 0;
        cloth.pair_count = static_cast<Index>(mesh->pair_rest.size());
        cloth.pair_tension_count = mesh->pair_tension_count;
        cloth.pair_buckling_count = mesh->pair_buckling_count;
        cloth.pair_hinge_count = mesh->hinge_count();
        cloth.pairs = mesh->pairs.data();
        cloth.pair_rest = mesh->pair_rest.data();
        cloth.pair_stiffness = topo_.pair_stiffness.data();
        cloth.pair_damping = topo_.pair_damping.data();
        for (Index k = 0; k < cloth.pair_count; ++k) {
            if (mesh->pair_kind[k] == PAIR_STRETCH) wick_pair_springs_.push_back(k);
        }
        const std::size_t links = wick_pair_springs_.size();
        wick_pairs_.resize(2 * links);
        for (std::size_t l = 0; l < links; ++l) {
            wick_pairs_[l] = mesh->pairs[wick_pair_springs_[l]];
            wick_pairs_[links + l] = mesh->pairs[cloth.pair_count + wick_pair_springs_[l]];
        }
        wick_pair_conductance_.assign(links, 0.0);
        cloth.wick_pair_count = static_cast<Index>(links);
        cloth.wick_pairs = wick_pairs_.data();
        cloth.wick_pair_conductance = wick_pair_conductance_.data();
        const Index m = topo_.triangle_count();  // in topology.cloth_order: by their least vertex, stably
        std::vector<Index> order(static_cast<std::size_t>(m)), least(static_cast<std::size_t>(m));
        for (Index t = 0; t < m; ++t) {
            const Index* v = topo_.triangles.data() + 3 * t;
            order[t] = t;
            least[t] = std::min(v[0], std::min(v[1], v[2]));
        }
        std::stable_sort(order.begin(), order.end(), [&least](Index a, Index b) { return least[a] < least[b]; });
        cloth_triangles_.resize(3 * order.size());
        cloth_shares_.resize(3 * order.size());
        for (Index t = 0; t < m; ++t) {
            for (Index c = 0; c < 3; ++c) {
                cloth_triangles_[3 * t + c] = topo_.triangles[3 * order[t] + c];
                cloth_shares_[3 * t + c] = mesh->corner_shares[3 * order[t] + c];
            }
        }
        cloth.triangle_count = m;
        cloth.triangles = cloth_triangles_.data();
        cloth.corner_shares = cloth_shares_.data();
    }

    // Work (bundles.make_work).
    const std::size_t cells = static_cast<std::size_t>(DRAG_CELL_ROWS * cells_length(cloth));
    const std::size_t uf = static_cast<std::size_t>(families);
    const std::size_t pairs = static_cast<std::size_t>(cloth.pair_count);
    work_.assign(un * (3 + 1 + 1 + 6 + 6 + 3 * uf + uf + uf + 4 + 6) + cells + 5 * pairs, 0.0);
    {
        double* p = work_.data();
        auto take = [&p](std::size_t count) {
            double* start = p;
            p += count;
            return start;
        };
        Work& w = core_.work;
        w.force = take(3 * un);
        w.submerged = take(un);
        w.saturation = take(un);
        w.blocks = take(6 * un);
        w.diagonal_blocks = take(6 * un);
        w.direction = take(3 * uf * un);
        w.along = take(uf * un);
        w.across = take(uf * un);
        w.buf = take(4 * un);
        w.cells = take(cells);
        w.wick_buffer = take(6 * un);
        w.pair_direction = take(3 * pairs);
        w.pair_along = take(pairs);
        w.pair_across = take(pairs);
    }
    single_work_.assign((5 * uf + 6) * un, 0.0f);
    core_.work.single_blocks = single_work_.data();
    core_.work.single_buf = core_.work.single_blocks + 5 * uf * un;

    // Solver (make_solver).
    solver_.assign(un * (1 + 10 * 3), 0.0);
    counters_.assign(SOLVER_COUNTERS, 0);
    {
        double* p = solver_.data();
        auto take = [&p](std::size_t count) {
            double* start = p;
            p += count;
            return start;
        };
        Solver& s = core_.solver;
        s.mass = take(un);
        s.rhs = take(3 * un);
        s.dv = take(3 * un);
        s.r = take(3 * un);
        s.z = take(3 * un);
        s.p = take(3 * un);
        s.ap = take(3 * un);
        s.hat_pos = take(3 * un);
        s.hat_vel = take(3 * un);
        s.predicted = take(3 * un);
        s.step_acceleration = take(3 * un);
        s.counters = counters_.data();
    }

    if (mesh != nullptr) {
        build_mesh_plane();
    } else {
        build_plane();
    }

    // Self-collision (make_contact).
    {
        edges_ = grid_edges(topo_.triangles);
        zone_.resize(un);
        for (Index i = 0; i < n; ++i) zone_[i] = i;
        contact_counters_.assign(CONTACT_COUNTERS, 0);
        contact_.assign(3 * un + 3 * un + 1 + ZONE_ROWS * un, 0.0);
        Contact& c = core_.contact;
        c.enabled = scene.self_collision == SWITCH_ON;
        c.friction = scene.self_friction;
        if (mesh != nullptr) {  // the smallest and median altitudes of its rest triangles
            c.least_margin = mesh->least_margin;
            c.rest_gap = mesh->rest_gap;
            c.typical_gap = mesh->typical_gap;
        } else {
            c.least_margin = MARGIN_FRACTION * pymin(topo_.dx, topo_.dy);
            c.rest_gap = topo_.dx * topo_.dy / std::hypot(topo_.dx, topo_.dy);
            c.typical_gap = c.rest_gap;
        }
        c.triangle_count = topo_.triangle_count();
        c.triangles = topo_.triangles.data();
        c.edge_count = static_cast<Index>(edges_.size() / 2);
        c.edges = edges_.data();
        double* rest = contact_.data();
        std::copy(topo_.rest_xy.begin(), topo_.rest_xy.end(), rest);  // z = 0
        c.rest = rest;
        c.reference = rest + 3 * un;
        c.margin = c.reference + 3 * un;
        c.zone = zone_.data();
        c.zone_sums = c.margin + 1;
        c.counters = contact_counters_.data();
        c.lists = &lists_;
    }

    // The state at rest (initial_state) and the buffers around it (Simulation.__init__).
    {
        buffers_.assign(un * (3 + 3 + 1) * 3 + un * 3 + un * 3 + un, 0.0);
        double* p = buffers_.data();
        auto take = [&p](std::size_t count) {
            double* at = p;
            p += count;
            return at;
        };
        Buffers& b = core_.buf;
        b.pos = take(3 * un);
        b.vel = take(3 * un);
        b.water = take(un);
        b.trial_pos = take(3 * un);
        b.trial_vel = take(3 * un);
        b.trial_water = take(un);
        b.prev_pos = take(3 * un);
        b.prev_vel = take(3 * un);
        b.prev_water = take(un);
        b.acceleration = take(3 * un);
        b.anchor = take(3 * un);
        b.held = take(un);
        for (Index i = 0; i < n; ++i) {
            for (Index k = 0; k < 3; ++k) b.pos[k * n + i] = topo_.start[k * n + i];  // initial_positions
            b.water[i] = scene.initial_saturation * scene.absorption_capacity * scene.areal_density * topo_.area[i];
        }
        copy(3 * n, b.pos, b.trial_pos);
        copy(n, b.water, b.trial_water);
        copy(3 * n, b.pos, b.prev_pos);
        copy(n, b.water, b.prev_water);
        copy(3 * n, b.pos, b.anchor);
        bool pinned = false;
        for (Index i = 0; i < n; ++i) pinned = pinned || topo_.free[i] == 0.0;
        if (pinned) grip_origin_.assign(b.pos, b.pos + 3 * n);  // the grip's zero (Model.grip_origin)
        clock_[NEXT_STEP] = scene.max_step;
        core_.clock = clock_;
    }

    set_scene(scene);
    const std::string overlaps = collider_overlaps(core_.phys, n, core_.buf.pos);
    if (!overlaps.empty()) throw std::invalid_argument(overlaps);

    // The integrator's stability data (Integrator.__init__), from the first scene.
    const double stiffest = 1.0 + pymax(scene.wet_stiffness_factor, 0.0);  // a saturated, stiffened cloth
    std::vector<double> ratio = topo_.per_particle_sum(topo_.stiffness.data(), topo_.offset);
    std::vector<double> listed = pair_sum(topo_, topo_.pair_stiffness.data(), false);
    for (Index i = 0; i < n; ++i) ratio[i] = (listed.empty() ? ratio[i] : ratio[i] + listed[i]) / dry_mass_[i];
    omega_squared_ = 2.0 * stiffest * np_max(ratio);
    ratio = topo_.per_particle_sum(topo_.damping.data(), topo_.offset);
    listed = pair_sum(topo_, topo_.pair_damping.data(), false);
    for (Index i = 0; i < n; ++i) ratio[i] = (listed.empty() ? ratio[i] : ratio[i] + listed[i]) / dry_mass_[i];
    damping_rate_ = 2.0 * np_max(ratio);
    std::vector<double> spring_ratio;
    for (std::size_t k = 0; k < topo_.stiffness.size(); ++k) {
        if (topo_.stiffness[k] > 0) spring_ratio.push_back(topo_.damping[k] / topo_.stiffness[k]);
    }
    for (std::size_t k = 0; k < topo_.pair_stiffness.size(); ++k) {
        if (topo_.pair_stiffness[k] > 0) spring_ratio.push_back(topo_.pair_damping[k] / topo_.pair_stiffness[k]);
    }
    double limit = spring_ratio.empty() ? INF : np_min(spring_ratio) / stiffest;
    if (omega_squared_ > 0) limit = pymax(limit, 0.1 / std::sqrt(omega_squared_));
    spring_limit_ = limit;
    set_control();
    const std::string unstable = stability_problem(core_.control);
    if (!unstable.empty()) throw std::invalid_argument(unstable);
}

namespace {

//: Point the plane's arrays that grids and meshes share into `storage` (sized here), in this order:
//: bands and rows (band values each), reference (4), reference_mass (n), `between` values of the
//: caller's own (returned), jacobian_along (along values), jacobian_mass (n), the frame (9 n, each
//: particle's the identity), normal (n, ones) and local (COMPONENTS n_c).
double* lay_out_plane(Plane& pl, std::vector<double>& storage, Index n, Index n_c, std::size_t band,
                      std::size_t between, std::size_t along) {
    const std::size_t un = static_cast<std::size_t>(n);
    storage.assign(2 * band + 4 + un + between + along + un + 9 * un + un + COMPONENTS * static_cast<std::size_t>(n_c),
                   0.0);
    double* p = storage.data();
    auto take = [&p](std::size_t count) {
        double* at = p;
        p += count;
        return at;
    };
    pl.bands = take(band);
    pl.rows = take(band);
    pl.reference = take(4);
    pl.reference_mass = take(un);
    double* own = take(between);
    pl.jacobian_along = take(along);
    pl.jacobian_mass = take(un);
    pl.frame = take(9 * un);
    for (Index a = 0; a < 3; ++a) {
        for (Index i = 0; i < n; ++i) pl.frame[(4 * a) * n + i] = 1.0;  // frame[a, a, i]
    }
    pl.normal = take(un);
    std::fill(pl.normal, pl.normal + n, 1.0);
    pl.local = take(COMPONENTS * static_cast<std::size_t>(n_c));
    return own;
}

}  // namespace

void Simulation::build_plane() {
    const Index n = topo_.n, nx = topo_.nx, ny = topo_.ny, families = topo_.families();
    const std::size_t un = static_cast<std::size_t>(n), uf = static_cast<std::size_t>(families);
    const auto sizes = multigrid(nx, ny) ? level_sizes(nx, ny, COARSEST_SIDE)
                                                         : std::vector<std::pair<Index, Index>>{{nx, ny}};
    const Index levels = static_cast<Index>(sizes.size());
    levels_.assign(4 * sizes.size(), 0);
    Index start = 0;
    for (Index l = 0; l < levels; ++l) {
        const auto [lx, ly] = sizes[l];
        levels_[4 * l + NX] = lx;
        levels_[4 * l + NY] = ly;
        levels_[4 * l + START] = start;
        levels_[4 * l + PAD_X] = lx + 3;
        start += (lx + 3) * (ly + 3);
    }
    const std::size_t size = static_cast<std::size_t>(start);
    const std::size_t components = COMPONENTS;
    grid_.assign(9 * components * size + 3 * components * size + static_cast<std::size_t>(nx + 3), 0.0);
    Hierarchy& g = core_.plane.grid;
    g.level_count = levels;
    g.size = start;
    g.levels = levels_.data();
    g.coef = grid_.data();
    g.inverse_diagonal = g.coef + 9 * components * size;
    g.x = g.inverse_diagonal + components * size;
    g.b = g.x + components * size;
    g.row = g.b + components * size;
    single_grid_.assign(9 * components * size + 4 * components * size, 0.0f);
    g.single_coef = single_grid_.data();
    g.single_inverse_diagonal = g.single_coef + 9 * components * size;
    g.single_x = g.single_inverse_diagonal + components * size;
    g.single_b = g.single_x + components * size;
    g.single_r = g.single_b + components * size;

    const auto [cx, cy] = sizes.back();
    const Index n_c = cx * cy;
    std::vector<Index> ordered(n_c);
    Index kd;
    if (cx <= cy) {
        for (Index k = 0; k < n_c; ++k) ordered[k] = k;
        kd = cx + 1;
    } else {  // along the columns, the shorter side: position j is column j / cy, row j % cy
        for (Index j = 0; j < n_c; ++j) ordered[j] = (j % cy) * cx + j / cy;
        kd = cy + 1;
    }
    kd = std::min(kd, n_c - 1);
    const Index first = levels_[4 * (levels - 1) + START], pad = levels_[4 * (levels - 1) + PAD_X];
    order_.resize(n_c);
    rank_.assign(static_cast<std::size_t>(pad * (cy + 3)), -1);
    for (Index j = 0; j < n_c; ++j) {
        const Index k = ordered[j];
        order_[j] = first + (k / cx + 1) * pad + k % cx + 1;
        rank_[order_[j] - first] = j;
    }
    slots_.resize(uf);
    for (Index f = 0; f < families; ++f) slots_[f] = SLOT[topo_.family[f]];
    const std::size_t band = COMPONENTS * static_cast<std::size_t>(n_c * (kd + 1));
    Plane& pl = core_.plane;
    pl.families = families;
    pl.stiffness = topo_.stiffness.data();
    pl.slots = slots_.data();
    pl.coarse_n = n_c;
    pl.kd = kd;
    pl.order = order_.data();
    pl.rank = rank_.data();
    pl.rank_size = static_cast<Index>(rank_.size());
    double* shares = lay_out_plane(pl, plane_, n, n_c, band, 2 * uf, uf * un);
    for (Index f = 0; f < families; ++f) {
        shares[f] = SHARE[topo_.family[f]][0];
        shares[families + f] = SHARE[topo_.family[f]][1];
    }
    pl.shares = shares;
    if (reuses_jacobian(pl)) {
        attach_reused(reused_, pl, n);
        core_.reused = &reused_;
    }
}

void Simulation::build_mesh_plane() {
    const ClothMesh& m = *topo_.mesh;
    const Index n = topo_.n, n_c = static_cast<Index>(m.order.size()), kd = m.kd;
    const std::size_t count = m.pair_rest.size();
    order_ = m.order;
    rank_ = m.rank;
    const std::size_t band = COMPONENTS * static_cast<std::size_t>(n_c * (kd + 1));
    Plane& pl = core_.plane;
    pl.families = 0;
    pl.stiffness = topo_.pair_stiffness.data();
    pl.coarse_n = n_c;
    pl.kd = kd;
    pl.order = order_.data();
    pl.rank = rank_.data();
    pl.rank_size = n_c;
    lay_out_plane(pl, plane_, n, n_c, band, 0, count);
    // The algebraic hierarchy (make_algebraic): its structure the mesh's, its values and vectors here.
    Algebraic& h = pl.algebraic;
    h.level_count = m.level_count();
    h.entries = static_cast<Index>(m.a_column.size());
    h.vectors = static_cast<Index>(m.diagonal.size());
    h.levels = m.levels.data();
    h.a_start = m.a_start.data();
    h.a_column = m.a_column.data();
    h.diagonal = m.diagonal.data();
    h.p_start = m.p_start.data();
    h.p_column = m.p_column.data();
    h.p_value = m.p_value.data();
    h.r_start = m.r_start.data();
    h.r_column = m.r_column.data();
    h.r_value = m.r_value.data();
    h.spring_entries = m.spring_entries.data();
    h.coupled = static_cast<Index>(m.spring_entries.size() / 2);
    const std::size_t entries = static_cast<std::size_t>(h.entries), vectors = static_cast<std::size_t>(h.vectors);
    algebraic_.assign(COMPONENTS * (entries + 4 * vectors), 0.0);
    h.a_value = algebraic_.data();
    h.inverse_diagonal = h.a_value + COMPONENTS * entries;
    h.x = h.inverse_diagonal + COMPONENTS * vectors;
    h.b = h.x + COMPONENTS * vectors;
    h.r = h.b + COMPONENTS * vectors;
    marker_.assign(static_cast<std::size_t>(m.marker_size), 0);
    h.marker = marker_.data();
}

void Simulation::set_scene(const Scene& scene) {
    scene_ = scene;
    const Index n = topo_.n;
    for (Index i = 0; i < n; ++i) {
        const double area = topo_.area[i];
        dry_mass_[i] = scene.areal_density * area;
        volume_[i] = scene.thickness * area;
        stokes_[i] = 6.0 * PI * std::sqrt(area / PI) * scene.water_viscosity;
        capacity_[i] = scene.absorption_capacity * dry_mass_[i];  // kg of water each particle holds at most
    }
    floor_z_ = scene.floor_level + 0.5 * scene.thickness;
    // Wicking (Model._set_wicking): conductances of the structural links, and the sub-step limit.
    std::vector<double> shape;
    for (Index f = 0; f < topo_.families(); ++f) {
        if (topo_.family[f] == STRUCTURAL_X || topo_.family[f] == STRUCTURAL_Y) {
            shape.insert(shape.end(), topo_.shape.begin() + f * n, topo_.shape.begin() + (f + 1) * n);
        }
    }
    for (std::size_t k = 0; k < shape.size(); ++k) {
        wick_conductance_[k] = scene.wicking_rate * scene.absorption_capacity * scene.areal_density * shape[k];
    }
    std::vector<double> links = topo_.per_particle_sum(shape.data(), wick_offsets_);
    if (topo_.mesh != nullptr) {  // its links: the stretch springs (Model._set_wicking)
        const double per_shape = scene.wicking_rate * scene.absorption_capacity * scene.areal_density;
        for (std::size_t l = 0; l < wick_pair_springs_.size(); ++l) {
            wick_pair_conductance_[l] = per_shape * topo_.mesh->pair_shape[wick_pair_springs_[l]];
        }
        const std::vector<double> listed = pair_sum(topo_, topo_.mesh->pair_shape.data(), true);
        for (Index i = 0; i < n; ++i) links[i] = links[i] + listed[i];
    }
    for (Index i = 0; i < n; ++i) links[i] = topo_.area[i] / (scene.wicking_rate * links[i]);
    wick_step_limit_ = np_min(links);

    Physics& p = core_.phys;
    const bool wet = scene.wet_stiffness_factor != 0.0 && scene.absorption_capacity > 0.0;
    p.projected = scene.damping_model == DAMPING_PROJECTED;
    p.wet_factor = wet ? scene.wet_stiffness_factor : 0.0;
    p.water_level = scene.water_level;
    p.water_density = scene.water_density;
    p.thickness = scene.thickness;
    p.smooth = scene.buoyancy_model == BUOYANCY_SMOOTH;
    p.stokes = scene.drag_model == DRAG_STOKES;
    p.drag_normal = scene.drag_normal;
    p.drag_tangential = scene.drag_tangential;
    p.drag_linear = scene.drag_linear;
    p.current_x = scene.current_x;
    p.current_y = scene.current_y;
    p.air_density = scene.air_density;
    p.wind_x = scene.wind_x;
    p.wind_y = scene.wind_y;
    p.wind_z = scene.wind_z;
    p.floor_z = floor_z_;
    p.floor_friction = scene.floor_friction;
    p.absorption_capacity = scene.absorption_capacity;
    p.absorption_rate = scene.absorption_rate;
    p.drying_rate = scene.drying_rate;
    p.wicking_rate = scene.wicking_rate;
    p.wick_step_limit = wick_step_limit_;
    p.skip_idle = true;
    p.grip_x = scene.grip_x;
    p.grip_y = scene.grip_y;
    p.grip_z = scene.grip_z;
    p.grip_origin = grip_origin_.empty() ? nullptr : grip_origin_.data();
    p.collider_count = fixtures_.collider_count();
    p.colliders = fixtures_.colliders.empty() ? nullptr : fixtures_.colliders.data();
    p.meshes = fixtures_.meshes();
    p.grip_key_count = static_cast<Index>(fixtures_.grip_keys.size() / 4);
    p.grip_keys = fixtures_.grip_keys.empty() ? nullptr : fixtures_.grip_keys.data();
    p.collider_key_count = static_cast<Index>(fixtures_.collider_keys.size() / COLLIDER_KEY_COLUMNS);
    p.collider_keys = fixtures_.collider_keys.empty() ? nullptr : fixtures_.collider_keys.data();
    if (p.collider_key_count > 0) collider_motion_.resize(static_cast<std::size_t>(p.collider_count * MOTION_COLUMNS));
    p.collider_motion = collider_motion_.empty() ? nullptr : collider_motion_.data();
}

void Simulation::set_control() {
    const Scene& sc = scene_;
    const double size = topo_.size;  // a mesh's own, not the scene's width and length
    double drag_offset, drag_slope;
    if (sc.drag_model == DRAG_STOKES) {
        std::vector<double> rate(stokes_.size());
        for (std::size_t i = 0; i < rate.size(); ++i) rate[i] = stokes_[i] / dry_mass_[i];
        drag_offset = np_max(rate);
        drag_slope = 0.0;
    } else {  // the water's speed past the cloth is at most a particle's speed plus the current's
        drag_slope = sc.water_density * (sc.drag_normal + sc.drag_tangential) / sc.areal_density;
        drag_offset = drag_slope * std::hypot(sc.current_x, sc.current_y) + sc.drag_linear / sc.areal_density;
    }
    if (sc.air_density > 0) {  // the air's share of a triangle is what the water leaves: the larger rate bounds both
        const double air_slope = sc.air_density * (sc.drag_normal + sc.drag_tangential) / sc.areal_density;
        drag_slope = pymax(drag_slope, air_slope);
        const double wind = std::sqrt(sc.wind_x * sc.wind_x + sc.wind_y * sc.wind_y + sc.wind_z * sc.wind_z);
        drag_offset += air_slope * wind;
    }
    const double allowed = sc.tolerance * size;  // m of local position error per step
    Control& c = core_.control;
    c.integrator = sc.integrator;
    c.tolerance = sc.tolerance;
    c.allowed = allowed;
    c.max_step = sc.max_step;
    c.newton_tolerance = allowed > 0 ? NEWTON_FRACTION * allowed : FIXED_STEP_NEWTON_TOLERANCE * size;
    c.cg_tolerance = allowed > 0 ? CG_TOLERANCE : FIXED_STEP_CG_TOLERANCE;
    c.omega_squared = omega_squared_;
    c.buoyancy_omega_squared = sc.water_density * GRAVITY / sc.areal_density;
    c.damping_rate = damping_rate_;
    c.spring_limit = spring_limit_;
    c.drag_rate_offset = drag_offset;
    c.drag_rate_slope = drag_slope;
    c.smallest_step = SMALLEST_STEP;
    c.growth = STEP_GROWTH;
    c.shrink = STEP_SHRINK;
    c.blow_up_speed = BLOW_UP_SPEED;
    c.sleep_distance = SLEEP_DISTANCE;
    c.sleep_after = SLEEP_AFTER;
}

bool Simulation::set_inputs(const Scene& next) {
    const std::string fixed = fixed_differences(scene_, next);
    if (!fixed.empty()) {
        throw std::invalid_argument(fixed + " are fixed once the simulation starts; only inputs may change");
    }
    if (field_values(scene_) == field_values(next)) return false;  // Python's scene equality: 0.0 == -0.0
    const Scene previous = scene_;
    set_scene(next);
    set_control();
    const std::string unstable = stability_problem(core_.control);
    if (!unstable.empty()) {  // refused: the scene stays as it was
        set_scene(previous);
        set_control();
        throw std::invalid_argument(unstable);
    }
    // Wake a sleeping cloth (Simulation._wake).
    clock_[SLEEPING] = 0.0;
    clock_[CALM_TIME] = 0.0;
    copy(3 * topo_.n, core_.buf.pos, core_.buf.anchor);
    return true;
}

Status Simulation::advance(double duration) {
    if (!(duration >= 0.0 && std::isfinite(duration))) {
        throw std::invalid_argument("duration must be a finite number >= 0 s, got " + py_repr(duration));
    }
    const double target = time() + duration;
    advance_end_ = target;
    clock_[LARGEST_ERROR] = 0.0;
    const Index steps_per_call = std::max<Index>(1, STEPS_PER_CALL / topo_.n);
    Status status = PAUSED;
    while (status == PAUSED) status = wc::advance(core_, target, steps_per_call);
    return status;
}

void Simulation::outputs(double* row) const {
    record_outputs(topo_.n, dry_mass_.data(), core_.phys.water_level, core_.buf.pos, core_.buf.water, row);
}

void Simulation::positions(double* xyz) const {
    const Index n = topo_.n;
    for (Index i = 0; i < n; ++i) {
        for (Index c = 0; c < 3; ++c) xyz[3 * i + c] = core_.buf.pos[c * n + i];
    }
}

void Simulation::wetness(double* out) const {
    for (Index i = 0; i < topo_.n; ++i) {
        const double capacity = scene_.absorption_capacity * dry_mass_[i];
        double value = capacity > 0 ? core_.buf.water[i] / capacity : 0.0;
        if (value < 0.0) value = 0.0;  // np.clip: NaN stays NaN
        if (value > 1.0) value = 1.0;
        out[i] = value;
    }
}

std::string fast_move_cause(const Physics& phys, const Index* numbers, Index n, const double* pos, const double* free,
                            const double* held, double t, double h, double end, double blow_up_speed) {
    const double after = t, before = t + h;
    // Each move between consecutive keys of the grip and of each collider (from its start at t = 0 to its first
    // key) under way between `after` and `before` s, as (speed m/s, what).
    std::vector<std::pair<double, std::string>> moves;
    const auto keyed = [&](const std::string& name, const std::string& what, const double* start, const double* key) {
        // start, key: (time s, x, y, z m) of the mover's previous key (0 at t = 0) and of this one
        if (start[0] < before && key[0] >= after) {
            const double distance = std::hypot(start[1] - key[1], start[2] - key[2], start[3] - key[3]);
            moves.emplace_back(distance / (key[0] - start[0]),
                               name + " moves " + what + " " + py_g(distance, 3) + " m in " +
                                   py_g(key[0] - start[0], 3) + " s from t = " + py_g(start[0]) + " s");
        }
    };
    double last[4] = {0.0, 0.0, 0.0, 0.0};
    for (Index k = 0; k < phys.grip_key_count; ++k) {
        const double* key = phys.grip_keys + 4 * k;
        keyed("grip_key" + std::to_string(k + 1), "the pinned particles", last, key);
        std::copy(key, key + 4, last);
    }
    Index mover = -1;
    for (Index k = 0; k < phys.collider_key_count; ++k) {
        const double* row = phys.collider_keys + COLLIDER_KEY_COLUMNS * k;
        const Index collider = static_cast<Index>(row[K_COLLIDER]);
        if (collider != mover) std::fill(last, last + 4, 0.0);  // by collider, then time: its first key
        mover = collider;
        const double key[4] = {row[K_TIME], row[K_X], row[K_Y], row[K_Z]};
        const Index number = numbers == nullptr ? k + 1 : numbers[k];
        keyed("collider_key" + std::to_string(number), "collider " + std::to_string(collider + 1), last, key);
        std::copy(key, key + 4, last);
    }
    // The inputs' part of the grip, reached linearly by the call's end, as the first pinned particle not held
    // has it (the core's grip reads the same).
    Index p = -1;
    for (Index i = 0; i < n && p < 0; ++i) {
        if (free[i] == 0.0 && held[i] == 0.0) p = i;
    }
    if (p >= 0 && phys.grip_origin != nullptr && end > t) {
        double keys_now[3];
        key_displacement(phys, t, keys_now);
        const double target[3] = {phys.grip_x, phys.grip_y, phys.grip_z};
        double change[3];
        std::string names;
        for (Index c = 0; c < 3; ++c) {
            const double part = pos[c * n + p] - phys.grip_origin[c * n + p] - keys_now[c];
            change[c] = target[c] - part;
            if (std::fabs(change[c]) > GRIP_RESOLUTION) {
                names += std::string(names.empty() ? "" : ", ") + "grip_" + "xyz"[c];
            }
        }
        const double distance =
            std::sqrt(change[0] * change[0] + change[1] * change[1] + change[2] * change[2]);
        if (!names.empty()) {
            moves.emplace_back(distance / (end - t),
                               "the grip's inputs (" + names + ") move the pinned particles " + py_g(distance, 3) +
                                   " m over the " + py_g(end - t, 3) + " s to t = " + py_g(end) + " s");
        }
    }
    // The fastest (Python's max of (speed, what)), if fast enough.
    std::pair<double, std::string> fastest{0.0, ""};
    for (const auto& move : moves) fastest = std::max(fastest, move);
    if (fastest.first < FAST_MOVE * blow_up_speed) return "";
    return fastest.second + ": " + py_g(fastest.first, 3) + " m/s, too fast for the cloth (it blows up at " +
           py_g(blow_up_speed) + " m/s); make that move smaller or slower (a later key; for the grip's inputs, a "
           "longer advance)";
}

std::string blow_up_advice(const Scene& scene, double stable) {
    std::vector<std::string> options;
    if (scene.integrator != IMPLICIT_EULER) options.emplace_back("integrator 'implicit_euler' (stable at any step)");
    if (scene.tolerance == 0.0 && scene.max_step > stable) {
        options.push_back("a smaller max_step (now " + py_g(scene.max_step) + " s; " +
                          INTEGRATOR_NAMES[scene.integrator] + " is stable on this cloth at rest at steps up to " +
                          py_g(stable, 2) + " s, a cautious bound)");
    } else {
        options.push_back("a smaller max_step (now " + py_g(scene.max_step) + " s)");
    }
    options.push_back(scene.tolerance == 0.0 ? "a tolerance > 0 (steps adapted to an error bound)"
                                             : "a smaller tolerance (now " + py_g(scene.tolerance) + ")");
    std::string advice = "use ";
    for (std::size_t k = 0; k < options.size(); ++k) {
        advice += (k == 0 ? "" : k + 1 == options.size() ? " or " : ", ") + options[k];
    }
    return advice;
}

std::string pinned_cause(const Physics& phys, Index n, const double* free, const double* pos) {
    const PinnedPressed pinned = pinned_pressed(phys, n, free, pos);
    if (pinned.particle < 0) return "";
    const Index shape = static_cast<Index>(phys.colliders[pinned.collider * COLLIDER_COLUMNS + C_SHAPE]);
    return "the grip presses pinned particle " + std::to_string(pinned.particle) + " into collider " +
           std::to_string(pinned.collider + 1) + " (a " + SHAPE_NAMES[shape] + "), whose contact puts it back " +
           py_g(pinned.distance, 3) + " m off its surface at every step while the grip holds it in; move the "
           "grip (grip_x, grip_y, grip_z, its keys) or the collider so that the pinned particles stay clear of it";
}

std::string blow_up_text(const Scene& scene, const Control& control, bool finite, double speed, double t, double h,
                         const std::string& cause) {
    const std::string advice = blow_up_advice(scene, stable_step(control, 0.0));  // (infinite if implicit)
    const std::string integrator = py_repr(std::string_view(INTEGRATOR_NAMES[scene.integrator]));
    if (finite && speed < control.blow_up_speed) {  // no step was accepted (stepping.hpp)
        return "the cloth state could not be stepped from t = " + py_g(t) + " s: the step control accepted no step "
               "(rejected more than " + std::to_string(MAX_REJECTIONS) + " times, the last of " + py_g(h, 3) +
               " s; integrator " + integrator + "). Likely cause: " +
               (cause.empty() ? "a state the cloth cannot be in, or a scene stiffer than the smallest step resolves; " +
                                    advice
                              : cause) +
               ". Last good time: " + py_g(t) + " s.";
    }
    const std::string what = !finite ? "became non-finite" : "exploded (speed " + py_g(speed, 3) + " m/s)";
    return "the cloth state " + what + " in the step from t = " + py_g(t) + " s to " + py_g(t + h) + " s (step " +
           py_g(h, 3) + " s, integrator " + integrator + "). Likely cause: " +
           (cause.empty() ? "the step is too large for stretch_stiffness = " + py_g(scene.stretch_stiffness) + " N/m; " +
                                advice
                          : cause) +
           ". Last good time: " + py_g(t) + " s.";
}

std::string Simulation::blow_up_message() const {
    const Buffers& b = core_.buf;
    const SpeedCheck check = speed_and_finiteness(topo_.n, b.trial_pos, b.trial_vel, b.trial_water);
    const double h = clock_[FAILED_STEP];
    const std::vector<Index>& numbers = fixtures_.collider_key_numbers;
    std::string cause = fast_move_cause(core_.phys, numbers.empty() ? nullptr : numbers.data(), topo_.n, b.pos,
                                        core_.cloth.free, b.held, time(), h, advance_end_, core_.control.blow_up_speed);
    if (cause.empty()) cause = pinned_cause(core_.phys, topo_.n, core_.cloth.free, b.trial_pos);
    return blow_up_text(scene_, core_.control, check.finite, check.speed, time(), h, cause);
}

// ------------------------------------------------------------------------------------------ checkpoints
template <class Self>
auto Simulation::kept_arrays(Self& self) {
    using Array = std::conditional_t<std::is_const_v<Self>, const double*, double*>;
    const Buffers& b = self.core_.buf;
    const Plane& pl = self.core_.plane;
    return std::array<Array, KEPT>{b.pos, b.vel, b.water, b.prev_pos, b.prev_vel, b.prev_water, b.acceleration,
                                   b.anchor, pl.reference_mass, pl.jacobian_along, pl.jacobian_mass,
                                   self.core_.contact.reference, self.reused_.rule.data(), self.reused_.source.data()};
}

KeptOffsets Simulation::offsets() const {
    return kept_offsets(topo_.n, along_count(), core_.reused != nullptr ? reused_.source.size() : 0);
}

void Simulation::save(Checkpoint& cp) const {
    const Plane& pl = core_.plane;
    cp.scene = scene_;
    cp.families = topo_.families();
    std::copy(clock_, clock_ + CLOCK_SIZE, cp.clock);
    std::copy(pl.reference, pl.reference + 3, cp.plane_reference);
    cp.contact_margin = core_.contact.margin[0];
    const auto at = offsets();
    cp.values.resize(at[KEPT]);
    const auto arrays = kept_arrays(*this);
    for (int k = 0; k < KEPT; ++k) std::copy(arrays[k], arrays[k] + (at[k + 1] - at[k]), cp.values.data() + at[k]);
}

Index Simulation::along_count() const {
    return topo_.mesh != nullptr ? static_cast<Index>(topo_.mesh->pair_rest.size()) : topo_.families() * topo_.n;
}

void Simulation::check(const Checkpoint& cp) const {
    if (topo_.mesh == nullptr && (cp.scene.nx != scene_.nx || cp.scene.ny != scene_.ny)) {
        throw SnapshotError("snapshot of another grid: " + std::to_string(cp.scene.nx) + " x " +
                            std::to_string(cp.scene.ny) + " particles, this simulation has " +
                            std::to_string(scene_.nx) + " x " + std::to_string(scene_.ny));
    }
    const std::string fixed = fixed_differences(scene_, cp.scene);
    if (!fixed.empty()) throw SnapshotError("snapshot of another scene: " + fixed + " differ (only inputs may)");
    if (cp.families != topo_.families() || cp.values.size() != offsets()[KEPT]) {
        throw SnapshotError("snapshot of another simulation: its arrays do not fit this one's");
    }
    bool finite = std::isfinite(cp.contact_margin);
    for (double v : cp.clock) finite = finite && std::isfinite(v);
    for (double v : cp.plane_reference) finite = finite && std::isfinite(v);
    for_each_field(cp.scene, [&](const char*, const auto& v) { finite = finite && std::isfinite(static_cast<double>(v)); });
    for (double v : cp.values) {
        if (!std::isfinite(v)) finite = false;
    }
    if (!finite) throw SnapshotError("snapshot holds values that are not finite");
    // The state's contents (stepping.hpp, state_problem; Simulation.check_snapshot in Python).
    const auto at = offsets();
    const double* v = cp.values.data();
    StateView state;
    state.pos = v + at[K_POS];
    state.vel = v + at[K_VEL];
    state.water = v + at[K_WATER];
    state.prev_pos = v + at[K_PREV_POS];
    state.prev_vel = v + at[K_PREV_VEL];
    state.prev_water = v + at[K_PREV_WATER];
    state.acceleration = v + at[K_ACCELERATION];
    state.anchor = v + at[K_ANCHOR];
    state.others = v + at[K_REFERENCE_MASS];  // the preconditioner's masses and Jacobian
    state.other_count = static_cast<Index>(at[K_CONTACT_REFERENCE] - at[K_REFERENCE_MASS]);
    state.contact_reference = v + at[K_CONTACT_REFERENCE];
    state.contact_margin = cp.contact_margin;
    state.clock = cp.clock;
    const std::string problem = state_problem(core_.cloth, core_.phys, core_.control, state);
    if (!problem.empty()) throw SnapshotError("snapshot of a state the cloth cannot be in: " + problem);
}

void Simulation::restore(const Checkpoint& cp) {
    check(cp);
    const Index n = topo_.n;
    Plane& pl = core_.plane;
    const auto at = offsets();
    const auto arrays = kept_arrays(*this);
    const double* in = cp.values.data();
    for (int k = 0; k < KEPT; ++k) std::copy(in + at[k], in + at[k + 1], arrays[k]);
    std::copy(cp.clock, cp.clock + CLOCK_SIZE, clock_);
    // The preconditioner as it was factored (Simulation.restore: refresh, refresh_from_jacobian).
    pl.reference[0] = cp.plane_reference[0];
    pl.reference[1] = 0.0;
    pl.reference[2] = cp.plane_reference[2];
    if (cp.plane_reference[1] != 0.0) {
        refresh(pl, core_.cloth, in + at[K_REFERENCE_MASS], cp.plane_reference[0]);
        if (cp.plane_reference[2] != 0.0) {
            refresh_from_jacobian(pl, core_.cloth, in + at[K_JACOBIAN_MASS], in + at[K_JACOBIAN_ALONG]);
        }
    }
    if (core_.reused != nullptr) rebuild_reused(reused_, core_.cloth);
    // Self-collision's candidate list, rebuilt from its reference and margin (self_contact.restore).
    Contact& contact = core_.contact;
    if (cp.contact_margin > 0.0) {
        build(contact, n, scene_.thickness, cp.contact_margin);
    } else {
        invalidate(contact);
    }
    set_scene(cp.scene);
    set_control();
}

std::vector<unsigned char> Simulation::snapshot() const {
    Checkpoint cp;
    save(cp);
    std::vector<unsigned char> out;
    ByteWriter w{out};
    w.begin(SNAPSHOT_MAGIC, MAGIC_SIZE, SNAPSHOT_VERSION);
    w.put(cp.families);
    w.put(static_cast<std::int64_t>(cp.values.size()));
    for_each_field(cp.scene, [&](const char*, const auto& v) { w.put(v); });
    w.put(cp.clock, CLOCK_SIZE);
    w.put(cp.plane_reference, 3);
    w.put(cp.contact_margin);
    w.put(cp.values.data(), cp.values.size());
    w.seal();
    return out;
}

Checkpoint Simulation::from_bytes(const unsigned char* data, std::size_t size) {
    if (data == nullptr || size < PREAMBLE || std::memcmp(data, SNAPSHOT_MAGIC, MAGIC_SIZE) != 0) {
        throw SnapshotError("not a snapshot of a native wetcloth simulation (" + std::to_string(size) +
                            " bytes without its header)");
    }
    ByteReader<SnapshotError> r{data, size, MAGIC_SIZE, "snapshot bytes are truncated"};
    const auto version = r.get<std::uint32_t>();
    if (version != SNAPSHOT_VERSION) {
        throw SnapshotError("snapshot of format version " + std::to_string(version) + "; this build reads version " +
                            std::to_string(SNAPSHOT_VERSION));
    }
    const auto checksum = r.get<std::uint64_t>();
    if (!r.body_matches(checksum)) {
        throw SnapshotError("snapshot bytes are corrupt or truncated (their checksum does not match)");
    }
    Checkpoint cp;
    cp.families = r.get<Index>();
    const auto count = r.get<std::int64_t>();
    for_each_field(cp.scene, [&](const char*, auto& v) { v = r.get<std::remove_reference_t<decltype(v)>>(); });
    const Index nx = cp.scene.nx, ny = cp.scene.ny;
    // A mesh cloth (no families) has as many values as its particles and springs make: Simulation::check's.
    if (nx < 2 || ny < 2 || nx > (1 << 20) || ny > (1 << 20) || cp.families < 0 || cp.families > 6 || count < 0 ||
        (cp.families > 0 ? static_cast<std::size_t>(count) != wc::value_count(nx, ny, cp.families)
                         : count < REUSE_RULE_SIZE || count > (std::int64_t{1} << 40))) {
        throw SnapshotError("snapshot bytes are malformed (grid, families and array sizes do not fit)");
    }
    r.get(cp.clock, CLOCK_SIZE);
    r.get(cp.plane_reference, 3);
    cp.contact_margin = r.get<double>();
    if ((size - r.at) / sizeof(double) != static_cast<std::size_t>(count) || (size - r.at) % sizeof(double) != 0) {
        throw SnapshotError("snapshot bytes are malformed (their arrays do not fill them)");
    }
    cp.values.resize(static_cast<std::size_t>(count));
    r.get(cp.values.data(), cp.values.size());
    if (r.at != size) throw SnapshotError("snapshot bytes are malformed (data after its end)");
    return cp;
}

}  // namespace wc
