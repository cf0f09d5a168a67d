// Water forces (docs/model.md section 4): submerged fraction, buoyancy, Stokes drag and face drag, the
// latter also in the air above the water (section 4.4) (port of bf41571:fmu_src/wetcloth/kernels/water.py;
// layout of the face-drag rows in wetcloth/water.hpp).
#include "wetcloth/water.hpp"

#include <cmath>

namespace wc {
namespace {

//: numba's (Python's) max(a, b) and min(a, b): b if b > a (b < a) else a.
inline double py_max(double a, double b) { return b > a ? b : a; }
inline double py_min(double a, double b) { return b < a ? b : a; }

//: Views (x, y, z, vx, vy, vz, s) of the particles from index `start` on.
struct Corner {
    const double* x;
    const double* y;
    const double* z;
    const double* vx;
    const double* vy;
    const double* vz;
    const double* s;
};

inline Corner corner(Index n, const double* pos, const double* vel, const double* s, Index start) {
    return {pos + start, pos + n + start, pos + 2 * n + start, vel + start, vel + n + start, vel + 2 * n + start,
            s + start};
}

//: 1 / max(x, 1e-300) as numba's min(1 / x, 1 / 1e-300): the same value for every x >= 0, inf or NaN
//: (division rounds monotonically; NaN stays NaN), with the division outside the select.  GCC folds
//: 1 / 1e-300 in the select's one branch and then may not speculate the other's division
//: (-ftrapping-math): the loop would not vectorise.
constexpr double INV_TINY_AREA = 1.0 / 1e-300;
inline double inverse_area(double twice_area) {
    const double inv = 1.0 / twice_area;
    return INV_TINY_AREA < inv ? INV_TINY_AREA : inv;
}

//: A triangle's unit normal, half its area's magnitude (m^2) and its corners' mean submerged fraction: what
//: its drag on each corner shares (shape_row_loop computes them once for the three corners).
struct TriangleShape {
    double nx, ny, nz, half_area, submerged;
};

inline TriangleShape triangle_shape(double ax, double ay, double az, double as, double bx, double by, double bz,
                                    double bs, double cx_, double cy_, double cz_, double cs) {
    const double e1x = bx - ax;
    const double e1y = by - ay;
    const double e1z = bz - az;
    const double e2x = cx_ - ax;
    const double e2y = cy_ - ay;
    const double e2z = cz_ - az;
    const double cx = e1y * e2z - e1z * e2y;
    const double cy = e1z * e2x - e1x * e2z;
    const double cz = e1x * e2y - e1y * e2x;
    const double twice_area = std::sqrt(cx * cx + cy * cy + cz * cz);
    const double inv = inverse_area(twice_area);
    return {cx * inv, cy * inv, cz * inv, 0.5 * twice_area, (as + bs + cs) * (1.0 / 3.0)};
}

//: One triangle's drag (N) at one of its corners' velocity (vx, vy, vz) and, if Blocks, its Jacobian blocks
//: (N s/m: xx, yy, zz, xy, xz, yz), from its shape: unit normal n, half area, and the part of it in the fluid
//: share_base + share_sign s_t (s_t its corners' mean submerged fraction: 0 + 1 s_t in water, 1 - 1 s_t in
//: the air above it); dF/du = k_normal n n^T + k_tangential (I - n n^T) + k_linear I + k_slip s s^T, with u
//: the fluid's velocity (flow) relative to the corner and s its in-plane part (the slip).  A corner takes its
//: share of the drag at its own velocity (docs/model.md 4.3), so the drag's power on it is -share u . F(u)
//: <= 0 and these blocks are its exact velocity Jacobian.  Branch-free, so the loops vectorise around it.
struct TriangleDrag {
    double fx, fy, fz, xx, yy, zz, xy, xz, yz;
};

template <bool Blocks>
inline TriangleDrag corner_drag(double density, double c_normal, double c_tangential, double c_linear,
                                double flow_x, double flow_y, double flow_z, double share_base, double share_sign,
                                double normal_x, double normal_y, double normal_z, double half_area,
                                double submerged, double vx, double vy, double vz) {
    const double st = share_base + share_sign * submerged;
    const double wet_area = half_area * st;
    const double ux = flow_x - vx;
    const double uy = flow_y - vy;
    const double uz = flow_z - vz;
    const double un = ux * normal_x + uy * normal_y + uz * normal_z;
    const double utx = ux - un * normal_x;
    const double uty = uy - un * normal_y;
    const double utz = uz - un * normal_z;
    const double ut = std::sqrt(utx * utx + uty * uty + utz * utz);
    const double q = 0.5 * density * wet_area;
    const double kn = q * c_normal * std::fabs(un);
    const double kt = q * c_tangential * ut;
    const double kl = c_linear * wet_area;
    TriangleDrag d{kn * un * normal_x + kt * utx + kl * ux, kn * un * normal_y + kt * uty + kl * uy,
                   kn * un * normal_z + kt * utz + kl * uz, 0, 0, 0, 0, 0, 0};
    if (Blocks) {
        // d(|w| w)/dw = |w| I + w w^T / |w|: along w twice the force's coefficient, across it once.
        const double ks = q * c_tangential / py_max(ut, 1e-300);
        const double diff = 2.0 * kn - kt;
        const double iso = kt + kl;
        d.xx = iso + diff * normal_x * normal_x + ks * utx * utx;
        d.yy = iso + diff * normal_y * normal_y + ks * uty * uty;
        d.zz = iso + diff * normal_z * normal_z + ks * utz * utz;
        d.xy = diff * normal_x * normal_y + ks * utx * uty;
        d.xz = diff * normal_x * normal_z + ks * utx * utz;
        d.yz = diff * normal_y * normal_z + ks * uty * utz;
    }
    return d;
}

//: The shapes (triangle_shape) of triangles (a[k], b[k], c[k]) for k < count into the SHAPE_ROWS rows
//: out + r * stride.
constexpr Index SHAPE_ROWS = 5;
void shape_row_loop(Index count, const double* __restrict ax, const double* __restrict ay,
                    const double* __restrict az, const double* __restrict as, const double* __restrict bx,
                    const double* __restrict by, const double* __restrict bz, const double* __restrict bs,
                    const double* __restrict cx_, const double* __restrict cy_, const double* __restrict cz_,
                    const double* __restrict cs, double* __restrict normal_x, double* __restrict normal_y,
                    double* __restrict normal_z, double* __restrict half_area, double* __restrict submerged) {
    for (Index k = 0; k < count; ++k) {
        const TriangleShape t = triangle_shape(ax[k], ay[k], az[k], as[k], bx[k], by[k], bz[k], bs[k], cx_[k],
                                               cy_[k], cz_[k], cs[k]);
        normal_x[k] = t.nx;
        normal_y[k] = t.ny;
        normal_z[k] = t.nz;
        half_area[k] = t.half_area;
        submerged[k] = t.submerged;
    }
}

//: Triangles of shapes (SHAPE_ROWS rows: normal, half area, submerged) k < count at the velocities v[k] of one
//: of their corners (corner_drag): force (N) into fx, fy, fz and, if Blocks, the Jacobian blocks (N s/m) into
//: xx..yz.  Every row is a __restrict parameter: GCC ignores __restrict on locals and struct members, and with
//: nine written rows run-time overlap checks would be too many.
template <bool Blocks>
void drag_row_loop(Index count, double density, double c_normal, double c_tangential, double c_linear,
                   double flow_x, double flow_y, double flow_z, double share_base, double share_sign,
                   const double* __restrict normal_x, const double* __restrict normal_y,
                   const double* __restrict normal_z, const double* __restrict half_area,
                   const double* __restrict submerged, const double* __restrict vx, const double* __restrict vy,
                   const double* __restrict vz, double* __restrict fx_, double* __restrict fy_,
                   double* __restrict fz_, double* __restrict xx, double* __restrict yy, double* __restrict zz,
                   double* __restrict xy, double* __restrict xz, double* __restrict yz) {
    for (Index k = 0; k < count; ++k) {
        const TriangleDrag d = corner_drag<Blocks>(density, c_normal, c_tangential, c_linear, flow_x, flow_y, flow_z,
                                                   share_base, share_sign, normal_x[k], normal_y[k], normal_z[k],
                                                   half_area[k], submerged[k], vx[k], vy[k], vz[k]);
        fx_[k] = d.fx;
        fy_[k] = d.fy;
        fz_[k] = d.fz;
        if (Blocks) {
            xx[k] = d.xx;
            yy[k] = d.yy;
            zz[k] = d.zz;
            xy[k] = d.xy;
            xz[k] = d.xz;
            yz[k] = d.yz;
        }
    }
}

//: drag_row_loop over the shapes' SHAPE_ROWS rows `shape` at the velocities of corner `at`; out is 9 rows;
//: every row `stride` apart.
template <bool Blocks>
void drag_row(Index count, const double* shape, const Corner& at, const Fluid& fluid, double* out, Index stride) {
    const double base = fluid.above ? 1.0 : 0.0, sign = fluid.above ? -1.0 : 1.0;
    drag_row_loop<Blocks>(count, fluid.density, fluid.c_normal, fluid.c_tangential, fluid.c_linear, fluid.flow_x,
                          fluid.flow_y, fluid.flow_z, base, sign, shape, shape + stride, shape + 2 * stride,
                          shape + 3 * stride, shape + 4 * stride, at.vx, at.vy, at.vz, out, out + stride,
                          out + 2 * stride, out + 3 * stride, out + 4 * stride, out + 5 * stride, out + 6 * stride,
                          out + 7 * stride, out + 8 * stride);
}

//: shape_row_loop over corners a, b, c into the SHAPE_ROWS rows from `out`, `stride` apart.
void shape_row(Index count, const Corner& a, const Corner& b, const Corner& c, double* out, Index stride) {
    shape_row_loop(count, a.x, a.y, a.z, a.s, b.x, b.y, b.z, b.s, c.x, c.y, c.z, c.s, out, out + stride,
                   out + 2 * stride, out + 3 * stride, out + 4 * stride);
}

//: Whether a particle with submerged fraction s is out of the fluid: it does not touch water (s = 0)
//: or, for the air above it (above), it is wholly under water (s = 1).
inline bool out_of_fluid(double s, bool above) { return above ? s >= 1.0 : s <= 0.0; }

//: Whether no particle from start to stop is in the fluid.
inline bool outside(const double* s, Index start, Index stop, bool above) {
    for (Index i = start; i < stop; ++i) {
        if (!out_of_fluid(s[i], above)) return false;
    }
    return true;
}

inline void zero(double* a, Index count) {
    for (Index i = 0; i < count; ++i) a[i] = 0.0;
}

inline void gather_corner_loop(Index n, double first_weight, double second_weight, const double* __restrict first,
                               const double* __restrict second, double* __restrict out) {
    for (Index v = 0; v < n; ++v) out[v] += first_weight * first[v] + second_weight * second[v];
}

//: Every particle's share of the drag of the two triangles (rows t1, t2 of n + nx + 1) of which it is corner
//: `corner` (0, 1, 2: a, b, d of the first, a, d, c of the second), out[v] += scale * share.  Particle v is
//: corner a (weight 1/4) of both triangles of cell v, the right-angle corner b (1/2) of cell v-1's first
//: triangle, corner d (1/4) of both triangles of cell v-nx-1, and the right-angle corner c (1/2) of cell
//: v-nx's second triangle.
void gather_corner(Index nx, Index n, Index corner, const double* t1, const double* t2, double* out, double scale) {
    const Index pad = nx + 1;
    if (corner == 0) return gather_corner_loop(n, 0.25 * scale, 0.25 * scale, t1 + pad, t2 + pad, out);
    if (corner == 1) return gather_corner_loop(n, 0.5 * scale, 0.25 * scale, t1 + pad - 1, t2, out);
    gather_corner_loop(n, 0.25 * scale, 0.5 * scale, t1, t2 + 1, out);
}

//: Every particle's share of its six triangles' drag, each at its own velocity, into force and, with blocks,
//: h times their Jacobian into blocks.  cells (DRAG_CELL_ROWS, n + nx + 1): both triangles' drag rows (9
//: each) and their shapes' (SHAPE_ROWS each, from row 18).  The cells between the highest and lowest rows in
//: the fluid are computed in one run along the grid, as if every particle began a cell (fewer, longer loops),
//: their shapes once, then for each corner in turn their drag at that corner's velocities, gathered into that
//: corner's particles; the last column's slots, which are no cells, are zeroed, and with skip_dry_rows the
//: rows of cells outside the fluid are zeroed, not computed (their area in it is zero anyway).
void drag_forces(Index nx, Index ny, const double* pos, const double* vel, const double* s, const Fluid& fluid,
                 double h, double* force, double* blocks, double* cells, bool skip_dry_rows) {
    const Index n = nx * ny;
    const Index pad = nx + 1;
    const Index length = n + pad;
    Index first = 0, last = ny - 2;
    if (skip_dry_rows) {
        while (first <= last && outside(s, first * nx, first * nx + 2 * nx, fluid.above)) ++first;
        while (last >= first && outside(s, last * nx, last * nx + 2 * nx, fluid.above)) --last;
    }
    const Index below = pad + first * nx;        // cells[:18, pad:below] = 0
    const Index above = pad + (last + 1) * nx;  // cells[:18, above:] = 0
    for (Index row = 0; row < 18; ++row) {
        double* r = cells + row * length;
        if (below > pad) zero(r + pad, (below < length ? below : length) - pad);
        if (above < length) zero(r + (above > 0 ? above : 0), length - (above > 0 ? above : 0));
    }
    const Index start = first * nx;
    const Index count = first <= last ? (last - first + 1) * nx - 1 : 0;
    const Corner a = corner(n, pos, vel, s, start);
    const Corner b = corner(n, pos, vel, s, start + 1);
    const Corner c = corner(n, pos, vel, s, start + nx);
    const Corner d = corner(n, pos, vel, s, start + nx + 1);
    const Index lo = pad + start;
    double* first_shapes = cells + 18 * length + lo;
    double* second_shapes = first_shapes + SHAPE_ROWS * length;
    if (count > 0) {
        shape_row(count, a, b, d, first_shapes, length);
        shape_row(count, a, d, c, second_shapes, length);
    }
    for (Index at = 0; at < 3; ++at) {
        if (count > 0) {
            const Corner& first_at = at == 0 ? a : at == 1 ? b : d;  // the corner of (a, b, d) and of (a, d, c)
            const Corner& second_at = at == 0 ? a : at == 1 ? d : c;
            if (blocks != nullptr) {
                drag_row<true>(count, first_shapes, first_at, fluid, cells + lo, length);
                drag_row<true>(count, second_shapes, second_at, fluid, cells + 9 * length + lo, length);
            } else {
                drag_row<false>(count, first_shapes, first_at, fluid, cells + lo, length);
                drag_row<false>(count, second_shapes, second_at, fluid, cells + 9 * length + lo, length);
            }
            for (Index r = first; r < last; ++r) {
                for (Index row = 0; row < 18; ++row) cells[row * length + pad + r * nx + nx - 1] = 0.0;
            }
        }
        for (Index comp = 0; comp < 3; ++comp) {
            gather_corner(nx, n, at, cells + comp * length, cells + (9 + comp) * length, force + comp * n, 1.0);
        }
        if (blocks == nullptr) continue;
        for (Index comp = 0; comp < 6; ++comp) {
            gather_corner(nx, n, at, cells + (3 + comp) * length, cells + (9 + 3 + comp) * length,
                          blocks + comp * n, h);
        }
    }
}

//: Triangles a mesh's face drag takes at a time: their corners gathered into rows (MESH_INPUTS of
//: them) so that drag_row_loop vectorises over them as over a grid's rows, then scattered back.
constexpr Index MESH_CHUNK = 128;
constexpr Index MESH_INPUTS = 21;  // x, y, z, vx, vy, vz, s of each of the three corners

//: Corner rows (MESH_INPUTS, MESH_CHUNK) of the triangles `kept` (count of them), their shapes
//: (shape_row_loop), and the drag's rows (9, MESH_CHUNK) that drag_row_loop fills for each fluid (at most
//: MESH_FLUIDS).
struct MeshChunk {
    Index kept[MESH_CHUNK];
    double in[MESH_INPUTS][MESH_CHUNK];
    double shape[SHAPE_ROWS][MESH_CHUNK];
    double out[MESH_FLUIDS][9][MESH_CHUNK];
};

//: The drag of fluid f (fluids[f]) on the chunk's count triangles at the velocities of their corner `at`
//: (0, 1, 2) into its rows out[f].
template <bool Blocks>
void mesh_chunk_drag(MeshChunk& m, Index f, Index count, Index at, const Fluid& fluid) {
    double(*out)[MESH_CHUNK] = m.out[f];
    double(*v)[MESH_CHUNK] = m.in + 7 * at + 3;
    const double base = fluid.above ? 1.0 : 0.0, sign = fluid.above ? -1.0 : 1.0;
    drag_row_loop<Blocks>(count, fluid.density, fluid.c_normal, fluid.c_tangential, fluid.c_linear, fluid.flow_x,
                          fluid.flow_y, fluid.flow_z, base, sign, m.shape[0], m.shape[1], m.shape[2], m.shape[3],
                          m.shape[4], v[0], v[1], v[2], out[0], out[1], out[2], out[3], out[4], out[5], out[6],
                          out[7], out[8]);
}

}  // namespace

double submerged_fractions(Index n, const double* z, double water_level, double thickness, bool smooth, double* s) {
    double top = 0.0;
    const double inv_thickness = 1.0 / thickness;
    for (Index i = 0; i < n; ++i) {
        double v;
        if (smooth) {
            v = py_min(py_max((water_level - z[i]) * inv_thickness + 0.5, 0.0), 1.0);
        } else {
            v = z[i] < water_level ? 1.0 : 0.0;
        }
        s[i] = v;
        top = py_max(top, v);
    }
    return top;
}

void buoyancy(Index n, const double* __restrict s, const double* __restrict volume, double density, double gravity,
              double* force) {
    double* __restrict fz = force + 2 * n;
    const double scale = density * gravity;
    for (Index i = 0; i < n; ++i) fz[i] += scale * volume[i] * s[i];
}

namespace {

inline void stokes_loop(Index n, const double* __restrict s, const double* __restrict coefficient, double current_x,
                        double current_y, const double* __restrict vx, const double* __restrict vy,
                        const double* __restrict vz, double* __restrict fx, double* __restrict fy,
                        double* __restrict fz) {
    for (Index i = 0; i < n; ++i) {
        const double c = coefficient[i] * s[i];
        fx[i] -= c * (vx[i] - current_x);
        fy[i] -= c * (vy[i] - current_y);
        fz[i] -= c * vz[i];
    }
}

}  // namespace

void stokes_drag(Index n, const double* s, const double* coefficient, double current_x, double current_y,
                 const double* vel, double* force) {
    stokes_loop(n, s, coefficient, current_x, current_y, vel, vel + n, vel + 2 * n, force, force + n, force + 2 * n);
}

void face_drag(Index nx, Index ny, const double* pos, const double* vel, const double* s, const Fluid& fluid,
               double* force, double* cells, bool skip_dry_rows) {
    drag_forces(nx, ny, pos, vel, s, fluid, 0.0, force, nullptr, cells, skip_dry_rows);
}

void face_drag_and_blocks(Index nx, Index ny, const double* pos, const double* vel, const double* s,
                          const Fluid& fluid, double h, double* force, double* blocks, double* cells,
                          bool skip_dry_rows) {
    drag_forces(nx, ny, pos, vel, s, fluid, h, force, blocks, cells, skip_dry_rows);
}

void mesh_face_drag(Index triangle_count, const Index* triangles, const double* shares, const Fluid* fluids,
                    Index fluid_count, double h, const MeshRecords& records, bool skip_idle) {
    const bool blocks = records.stride == SUM_SLOTS;
    const double* state = records.state;
    MeshChunk m;
    for (Index first = 0; first < triangle_count; first += MESH_CHUNK) {
        const Index stop = first + MESH_CHUNK < triangle_count ? first + MESH_CHUNK : triangle_count;
        Index count = 0;
        for (Index t = first; t < stop; ++t) {
            const Index* v = triangles + 3 * t;
            const double* corners[3] = {state + STATE_SLOTS * v[0], state + STATE_SLOTS * v[1],
                                        state + STATE_SLOTS * v[2]};
            bool idle = skip_idle;
            for (Index f = 0; f < fluid_count && idle; ++f) {
                idle = out_of_fluid(corners[0][STATE_SUBMERGED], fluids[f].above) &&
                       out_of_fluid(corners[1][STATE_SUBMERGED], fluids[f].above) &&
                       out_of_fluid(corners[2][STATE_SUBMERGED], fluids[f].above);
            }
            if (idle) continue;
            for (Index corner = 0; corner < 3; ++corner) {
                double* column = &m.in[7 * corner][count];
                const double* c = corners[corner];
                for (Index r = 0; r < 6; ++r) column[r * MESH_CHUNK] = c[STATE_X + r];
                column[6 * MESH_CHUNK] = c[STATE_SUBMERGED];
            }
            m.kept[count++] = t;
        }
        // Each corner's share of the drag at its own velocity (docs/model.md 4.3), corner by corner.
        double(*in)[MESH_CHUNK] = m.in;
        shape_row_loop(count, in[0], in[1], in[2], in[6], in[7], in[8], in[9], in[13], in[14], in[15], in[16],
                       in[20], m.shape[0], m.shape[1], m.shape[2], m.shape[3], m.shape[4]);
        for (Index corner = 0; corner < 3; ++corner) {
            for (Index f = 0; f < fluid_count; ++f) {
                if (blocks) {
                    mesh_chunk_drag<true>(m, f, count, corner, fluids[f]);
                } else {
                    mesh_chunk_drag<false>(m, f, count, corner, fluids[f]);
                }
            }
            const Index rows = blocks ? 9 : 3;
            for (Index f = 1; f < fluid_count; ++f)
                for (Index r = 0; r < rows; ++r)
                    for (Index k = 0; k < count; ++k) m.out[0][r][k] += m.out[f][r][k];
            for (Index k = 0; k < count; ++k) {
                const Index t = m.kept[k];
                double* sum = records.sums + records.stride * triangles[3 * t + corner];
                const double share = shares[3 * t + corner];
                for (Index r = 0; r < 3; ++r) sum[SUM_FORCE + r] += share * m.out[0][r][k];
                if (blocks)
                    for (Index r = 0; r < 6; ++r) sum[SUM_BLOCKS + r] += (h * share) * m.out[0][3 + r][k];
            }
        }
    }
}

}  // namespace wc
