// The plane preconditioner on a mesh (wetcloth/plane_parts.hpp): the same three components in each
// particle's frame as on a grid (plane.cpp), each a scalar system over the mesh's in-plane springs,
// approximately inverted by one algebraic multigrid V-cycle: the prolongators of a smoothed aggregation
// of the spring graph (built once with the cloth, preconditioner.py), Galerkin coarse matrices R A P
// computed here at every rebuild, Gauss-Seidel sweeps as on the grid (multigrid.hpp's SWEEPS, forward
// before the coarse correction, backward after it: the cycle is symmetric positive definite), and the
// coarsest level's band factors (band.cpp) in the reverse Cuthill-McKee order of its graph.  A mesh of
// at most ALGEBRAIC_SIZE particles has one level: its band factors solve the systems exactly.  The
// particles a step holds (free 0: at rest on a support, or pinned) are constraints of its solve; on the
// finest level the cycle keeps to them, as the Jacobian's systems do (no coupling to a held end): its
// sweeps leave them at zero and no residual is restricted from them, so that the sweeps are those of the
// free particles' own system (the coarse levels stay the whole mesh's, factored once for many steps).  The
// round mesh draped on a ball takes 5.1 CG iterations per Newton iteration so, 6.9 with the whole mesh's
// cycle (docs/benchmarks.md).
#include <cmath>
#include <cstring>
#include <vector>

#include "wetcloth/band.hpp"
#include "wetcloth/multigrid.hpp"
#include "wetcloth/plane.hpp"
#include "wetcloth/plane_parts.hpp"

namespace wc {
namespace {

//: The sparse rows' loops below (a few entries each, summed in order) as plain scalar loops: GCC's
//: vectoriser runs them four entries at a time, their x gathered lane by lane, and each row's few
//: remaining entries in a loop after it, which cost more than it saved (the 10k disc's cycle 5-7 %,
//: its coarse matrices 8 % faster without).  The same operations in the same order: the same bits.
#if defined(__GNUC__) && !defined(__clang__)
#define SCALAR_ROWS __attribute__((optimize("no-tree-vectorize")))
#else
#define SCALAR_ROWS
#endif

//: Column `column` (AlgebraicColumn) of `level`'s row of the hierarchy's table.
inline Index level_of(const Algebraic& h, Index level, Index column) { return h.levels[level * ALGEBRAIC_COLUMNS + column]; }

//: Position in x, b or r (Algebraic) of component c's value at index v of the per-level vectors.
inline Index entry_of(const Algebraic& h, Index c, Index v) { return c == NORMAL ? NORMAL * h.vectors + v : 2 * v + c; }

//: Band storage of component c: row p holds entries (p, p) .. (p, p + kd) of the band order.
inline double* band_of(Plane& plane, Index c) { return plane.bands + c * plane.coarse_n * (plane.kd + 1); }
inline double* rows_of(Plane& plane, Index c) { return plane.rows + c * plane.coarse_n * (plane.kd + 1); }

//: Component c's level-0 matrix zeroed, diagonal (n) on its diagonal.
void diagonal_matrix(Plane& plane, Index n, Index c, const double* diagonal) {
    Algebraic& h = plane.algebraic;
    double* a = h.a_value + c * h.entries;
    for (Index e = 0; e < h.a_start[n]; ++e) a[e] = 0.0;
    for (Index i = 0; i < n; ++i) a[h.diagonal[i]] = diagonal[i];
}

inline void add_diagonal(Plane& plane, Index c, Index i, double value) {
    plane.algebraic.a_value[c * plane.algebraic.entries + plane.algebraic.diagonal[i]] += value;
}

//: Add value to the entries (i, j) and (j, i) of component c's level-0 matrix, i, j the ends of
//: coupled spring e (Algebraic::coupled: the in-plane springs, then the hinges' terms it couples).
inline void add_between(Plane& plane, Index c, Index e, double value) {
    Algebraic& h = plane.algebraic;
    double* a = h.a_value + c * h.entries;
    a[h.spring_entries[e]] += value;
    a[h.spring_entries[h.coupled + e]] += value;
}

//: Component c's matrix of level + 1, R A P of `level`'s, and the inverse diagonal of `level`.  Row
//: by row of R: marker maps each column of the coarse row to its entry (the coarse patterns hold every
//: product, preconditioner.py).
SCALAR_ROWS void galerkin(Algebraic& h, Index level, Index c) {
    const Index n = level_of(h, level, SIZE), first = level_of(h, level, VECTOR);
    const Index* a_rows = h.a_start + level_of(h, level, A_ROWS);
    const Index* coarse_rows = h.a_start + level_of(h, level + 1, A_ROWS);
    const Index* p_rows = h.p_start + level_of(h, level, P_ROWS);
    const Index* r_rows = h.r_start + level_of(h, level, R_ROWS);
    double* a = h.a_value + c * h.entries;  // both levels' entries (at their own positions)
    double* inverse = h.inverse_diagonal + c * h.vectors + first;
    for (Index i = 0; i < n; ++i) inverse[i] = 1.0 / a[h.diagonal[first + i]];
    Index* marker = h.marker;
    const Index coarse_n = level_of(h, level + 1, SIZE);
    for (Index row = 0; row < coarse_n; ++row) {
        for (Index q = coarse_rows[row]; q < coarse_rows[row + 1]; ++q) {
            marker[h.a_column[q]] = q;
            a[q] = 0.0;
        }
        for (Index t = r_rows[row]; t < r_rows[row + 1]; ++t) {
            const Index k = h.r_column[t];
            const double weight = h.r_value[t];
            for (Index s = a_rows[k]; s < a_rows[k + 1]; ++s) {
                const Index i = h.a_column[s];
                const double ra = weight * a[s];
                for (Index u = p_rows[i]; u < p_rows[i + 1]; ++u) a[marker[h.p_column[u]]] += ra * h.p_value[u];
            }
        }
    }
}

//: Component c's coarsest matrix into its band (in the order of plane.order), factored; returns
//: band_factor's info.
Index factor_coarsest(Plane& plane, Index c) {
    const Algebraic& h = plane.algebraic;
    const Index last = h.level_count - 1, width = plane.kd + 1;
    const Index* rows = h.a_start + level_of(h, last, A_ROWS);
    const double* a = h.a_value + c * h.entries;
    double* band = band_of(plane, c);
    for (Index e = 0; e < plane.coarse_n * width; ++e) band[e] = 0.0;
    for (Index position = 0; position < plane.coarse_n; ++position) {
        const Index i = plane.order[position];
        for (Index e = rows[i]; e < rows[i + 1]; ++e) {
            const Index other = plane.rank[h.a_column[e]];
            if (other >= position) band[position * width + other - position] = a[e];
        }
    }
    return band_factor(band, rows_of(plane, c), plane.coarse_n, plane.kd);
}

//: Component c's coarse matrices from its level-0 matrix, and the coarsest one's band factors.
Index factor_component(Plane& plane, Index c) {
    for (Index level = 0; level + 1 < plane.algebraic.level_count; ++level) galerkin(plane.algebraic, level, c);
    return factor_coarsest(plane, c);
}

//: The cycle's vectors x, b and r hold t1 and t2 side by side, [2 v + c] over their first two rows
//: (COMPONENTS, vectors), the normal in the third row as it is: a row's entry reads both components'
//: values in one load and updates both in one two-lane operation (each lane the operations of its own
//: component in their order: the same bits as one component at a time).
#if defined(__GNUC__)
using Pair = double __attribute__((vector_size(16)));
#else
struct Pair {  // the two lanes one at a time
    double lane[2];
    Pair(double value = 0.0) : lane{value, value} {}
    Pair(double first, double second) : lane{first, second} {}
    friend Pair operator*(Pair p, Pair q) { return {p.lane[0] * q.lane[0], p.lane[1] * q.lane[1]}; }
    friend Pair operator+(Pair p, Pair q) { return {p.lane[0] + q.lane[0], p.lane[1] + q.lane[1]}; }
    friend Pair operator-(Pair p, Pair q) { return {p.lane[0] - q.lane[0], p.lane[1] - q.lane[1]}; }
    Pair& operator+=(Pair q) { return *this = *this + q; }
    Pair& operator-=(Pair q) { return *this = *this - q; }
};
#endif
inline Pair both(double value) { return Pair{value, value}; }
inline Pair load_pair(const double* from) {
    Pair p;
    std::memcpy(&p, from, sizeof p);
    return p;
}
inline void store_pair(double* to, Pair p) { std::memcpy(to, &p, sizeof p); }

//: The V-cycle's loops over a level's rows do C components side by side (2: t1 and t2, whose systems
//: at the rest stiffness are one (mesh_factor), so that their loops read component 0's matrix; 3: and the
//: normal, each its own): one pass over the pattern for all, and independent chains in each row's sums.
template <Index C>
struct Rows {
    const Index* start;   // the level's rows in a_start
    const Column* column;  // a_column
    const Index* diagonal;
    const double* a[COMPONENTS];  // t1's, t2's (t1's when C is 2) and the normal's matrices
    const double* inverse[COMPONENTS];
    double* x;  // the pair's (t1, t2) at [2 i + c]
    double* b;
    double* normal_x;  // the normal's (C 3)
    double* normal_b;
    Index n;
    Rows(Algebraic& h, Index level)
        : start(h.a_start + level_of(h, level, A_ROWS)), column(h.a_column),
          diagonal(h.diagonal + level_of(h, level, VECTOR)), n(level_of(h, level, SIZE)) {
        const Index first = level_of(h, level, VECTOR);
        for (Index c = 0; c < COMPONENTS; ++c) {
            const Index system = C == NORMAL && c < NORMAL ? 0 : c;
            a[c] = h.a_value + system * h.entries;
            inverse[c] = h.inverse_diagonal + system * h.vectors + first;
        }
        x = h.x + 2 * first, b = h.b + 2 * first;
        normal_x = h.x + NORMAL * h.vectors + first, normal_b = h.b + NORMAL * h.vectors + first;
    }
    //: Entry e of the pair's matrices (one value for both when C is 2).
    Pair pair_entry(Index e) const { return C == NORMAL ? both(a[0][e]) : Pair{a[0][e], a[1][e]}; }
    Pair pair_inverse(Index i) const { return C == NORMAL ? both(inverse[0][i]) : Pair{inverse[0][i], inverse[1][i]}; }
    //: s -= A's entries e in [from, to) times x: the pair, and the normal when C is 3.
    void subtract(Index from, Index to, Pair& s, double& normal) const {
        for (Index e = from; e < to; ++e) {
            const Index j = column[e];
            s -= pair_entry(e) * load_pair(x + 2 * j);
            if (C == COMPONENTS) normal -= a[NORMAL][e] * normal_x[j];
        }
    }
};

//: A coarse level's forward Gauss-Seidel sweep from x = 0 (only the entries left of the diagonal meet
//: values already set), then the residual b - A x, which that sweep leaves as -U x (U the entries right
//: of the diagonal), row by row into the pair's residual and the normal's.
template <Index C>
SCALAR_ROWS void sweep_forward(const Rows<C>& m, double* residual, double* normal_residual) {
    for (Index i = 0; i < m.n; ++i) {
        Pair s = load_pair(m.b + 2 * i);
        double normal = C == COMPONENTS ? m.normal_b[i] : 0.0;
        m.subtract(m.start[i], m.diagonal[i], s, normal);
        store_pair(m.x + 2 * i, s * m.pair_inverse(i));
        if (C == COMPONENTS) m.normal_x[i] = normal * m.inverse[NORMAL][i];
    }
    for (Index i = 0; i < m.n; ++i) {
        Pair s = both(0.0);
        double normal = 0.0;
        m.subtract(m.diagonal[i] + 1, m.start[i + 1], s, normal);
        store_pair(residual + 2 * i, s);
        if (C == COMPONENTS) normal_residual[i] = normal;
    }
}

//: The same on level 0, whose matrices are symmetric to the bit (every spring adds one value to a_ij
//: and a_ji): as the sweep sets x_i, it takes a_ij x_i from the residual of each j < i it meets (a_ji x_i
//: of row j's U x), so that each row's residual gets its terms in their order (the same sums) without a
//: second pass over the rows, whose few entries each end in a branch the processor cannot tell.  The rows
//: of held particles (free 0) stay zero and their residual is zero.
template <Index C>
SCALAR_ROWS void sweep_forward_finest(const Rows<C>& m, const double* free, double* residual, double* normal_residual) {
    for (Index i = 0; i < m.n; ++i) {
        store_pair(residual + 2 * i, both(0.0));
        if (C == COMPONENTS) normal_residual[i] = 0.0;
    }
    for (Index i = 0; i < m.n; ++i) {
        Pair s = load_pair(m.b + 2 * i);
        double normal = C == COMPONENTS ? m.normal_b[i] : 0.0;
        m.subtract(m.start[i], m.diagonal[i], s, normal);
        const Pair x = both(free[i]) * s * m.pair_inverse(i);
        const double normal_x = free[i] * normal * m.inverse[NORMAL][i];
        store_pair(m.x + 2 * i, x);
        if (C == COMPONENTS) m.normal_x[i] = normal_x;
        for (Index e = m.start[i]; e < m.diagonal[i]; ++e) {
            const Index j = m.column[e];
            if (free[j] == 0.0) continue;  // a held row's residual is zero
            store_pair(residual + 2 * j, load_pair(residual + 2 * j) - m.pair_entry(e) * x);
            if (C == COMPONENTS) normal_residual[j] -= m.a[NORMAL][e] * normal_x;
        }
    }
}

//: Down one level: the forward sweep and its residual, restricted to b of level + 1 (R = P^T, row by
//: row of R: each coarse sum in a register, its terms in the order of the fine rows).  `free`: level 0's
//: particles' flags, else nullptr.
template <Index C>
SCALAR_ROWS void down(Algebraic& h, Index level, const double* free) {
    static_assert(SWEEPS == 1, "the residual is -U x after one sweep from zero");
    const Rows<C> m(h, level);
    const Index first = level_of(h, level, VECTOR);
    const Index coarse_first = level_of(h, level + 1, VECTOR), coarse_n = level_of(h, level + 1, SIZE);
    const Index* r_rows = h.r_start + level_of(h, level, R_ROWS);
    double* residual = h.r + 2 * first;
    double* normal_residual = h.r + NORMAL * h.vectors + first;
    double* coarse_b = h.b + 2 * coarse_first;
    double* coarse_normal_b = h.b + NORMAL * h.vectors + coarse_first;
    if (free != nullptr) {
        sweep_forward_finest(m, free, residual, normal_residual);
    } else {
        sweep_forward(m, residual, normal_residual);
    }
    const Column* r_column = h.r_column;
    const double* r_value = h.r_value;
    for (Index k = 0; k < coarse_n; ++k) {
        Pair s = both(0.0);
        double normal = 0.0;
        for (Index t = r_rows[k]; t < r_rows[k + 1]; ++t) {
            s += both(r_value[t]) * load_pair(residual + 2 * r_column[t]);
            if (C == COMPONENTS) normal += r_value[t] * normal_residual[r_column[t]];
        }
        store_pair(coarse_b + 2 * k, s);
        if (C == COMPONENTS) coarse_normal_b[k] = normal;
    }
}

//: Up one level, once x of level + 1 holds its correction: x += P x of level + 1, then a backward
//: Gauss-Seidel sweep; with `free`, both on the free rows alone.  P's product is taken by R's rows
//: (R = P^T, both sorted by column: preconditioner.make_algebraic): each coarse point's correction added
//: to the fine rows it reaches, coarse points in order, so that each fine row gets the terms of its row
//: of P in their order (the same sums), over R's long rows rather than P's short ones of 1-5 entries
//: (each row's end a branch the processor cannot tell).
template <Index C>
SCALAR_ROWS void up(Algebraic& h, Index level, const double* free) {
    const Rows<C> m(h, level);
    const Index coarse_first = level_of(h, level + 1, VECTOR), coarse_n = level_of(h, level + 1, SIZE);
    const Index* r_rows = h.r_start + level_of(h, level, R_ROWS);
    const Column* r_column = h.r_column;
    const double* r_value = h.r_value;
    const double* coarse_x = h.x + 2 * coarse_first;
    const double* coarse_normal_x = h.x + NORMAL * h.vectors + coarse_first;
    for (Index k = 0; k < coarse_n; ++k) {
        const Pair correction = load_pair(coarse_x + 2 * k);
        const double normal = C == COMPONENTS ? coarse_normal_x[k] : 0.0;
        for (Index t = r_rows[k]; t < r_rows[k + 1]; ++t) {
            const Index i = r_column[t];
            if (free != nullptr && free[i] == 0.0) continue;  // held rows stay zero
            store_pair(m.x + 2 * i, load_pair(m.x + 2 * i) + both(r_value[t]) * correction);
            if (C == COMPONENTS) m.normal_x[i] += r_value[t] * normal;
        }
    }
    for (Index i = m.n - 1; i >= 0; --i) {
        if (free != nullptr && free[i] == 0.0) continue;
        Pair s = load_pair(m.b + 2 * i);
        double normal = C == COMPONENTS ? m.normal_b[i] : 0.0;
        m.subtract(m.start[i], m.start[i + 1], s, normal);
        store_pair(m.x + 2 * i, load_pair(m.x + 2 * i) + s * m.pair_inverse(i));
        if (C == COMPONENTS) m.normal_x[i] += normal * m.inverse[NORMAL][i];
    }
}

//: First half of the V-cycle from b of level 0, for the first `components` components: leaves the
//: coarsest level's right-hand side in b.  free (n): the particles' flags, held ones (0) kept at zero.
void cycle_down(Algebraic& h, Index components, const double* free) {
    for (Index level = 0; level + 1 < h.level_count; ++level) {
        const double* held_rows = level == 0 ? free : nullptr;
        if (components == COMPONENTS) {
            down<COMPONENTS>(h, level, held_rows);
        } else {
            down<NORMAL>(h, level, held_rows);
        }
    }
}

//: Second half, once x of the coarsest level holds its solution; leaves the result in x of level 0.
void cycle_up(Algebraic& h, Index components, const double* free) {
    for (Index level = h.level_count - 2; level >= 0; --level) {
        const double* held_rows = level == 0 ? free : nullptr;
        if (components == COMPONENTS) {
            up<COMPONENTS>(h, level, held_rows);
        } else {
            up<NORMAL>(h, level, held_rows);
        }
    }
}

}  // namespace

Index mesh_factor(Plane& plane, const Cloth& cloth, const double* mass, double scale, const double* weights) {
    const Index n = cloth.n, count = cloth.pair_count, in_plane_springs = in_plane_count(cloth);
    diagonal_matrix(plane, n, 0, mass);
    for (Index k = 0; k < in_plane_springs; ++k) {
        const double w = 0.5 * scale * weights[k];
        const Index i = cloth.pairs[k], j = cloth.pairs[count + k];
        add_diagonal(plane, 0, i, w);
        add_diagonal(plane, 0, j, w);
        add_between(plane, 0, k, -w);
    }
    const Index info = factor_component(plane, 0);
    if (info != 0) return info;
    Algebraic& h = plane.algebraic;  // t2's system is t1's
    for (Index e = 0; e < h.entries; ++e) h.a_value[h.entries + e] = h.a_value[e];
    for (Index e = 0; e < h.vectors; ++e) h.inverse_diagonal[h.vectors + e] = h.inverse_diagonal[e];
    for (Index e = 0; e < plane.coarse_n * (plane.kd + 1); ++e) {
        band_of(plane, 1)[e] = band_of(plane, 0)[e];
        rows_of(plane, 1)[e] = rows_of(plane, 0)[e];
    }
    return 0;
}

void mesh_follow_cloth(Plane& plane, const Cloth& cloth, const double* pos) {
    const Index n = cloth.n;
    double* frame = plane.frame;  // frame[(3 r + c) n + i]
    double* normal = frame + 6 * n;
    for (Index e = 0; e < 3 * n; ++e) normal[e] = 0.0;
    for (Index t = 0; t < cloth.triangle_count; ++t) {
        const Index* v = cloth.triangles + 3 * t;
        double e1[3], e2[3];
        for (Index c = 0; c < 3; ++c) {
            e1[c] = pos[c * n + v[1]] - pos[c * n + v[0]];
            e2[c] = pos[c * n + v[2]] - pos[c * n + v[0]];
        }
        const double cross[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                 e1[0] * e2[1] - e1[1] * e2[0]};
        for (Index corner = 0; corner < 3; ++corner)
            for (Index c = 0; c < 3; ++c) normal[c * n + v[corner]] += cross[c];
    }
    for (Index i = 0; i < n; ++i) {
        double x = normal[i], y = normal[n + i], z = normal[2 * n + i];
        const double length = std::sqrt(x * x + y * y + z * z);
        if (length > 0.0) {
            x /= length, y /= length, z /= length;
        } else {  // crumpled past telling: the axes
            x = 0.0, y = 0.0, z = 1.0;
        }
        normal[i] = x, normal[n + i] = y, normal[2 * n + i] = z;
        const double sign = std::copysign(1.0, z);
        const double a = -1.0 / (sign + z), b = x * y * a;
        frame[i] = 1.0 + sign * x * x * a, frame[n + i] = sign * b, frame[2 * n + i] = -sign * x;
        frame[3 * n + i] = b, frame[4 * n + i] = sign + y * y * a, frame[5 * n + i] = -y;
    }
}

Index mesh_systems_from_jacobian(Plane& plane, const Cloth& cloth, const double* mass, const Work& work) {
    const Index n = cloth.n, count = cloth.pair_count, in_plane_springs = in_plane_count(cloth);
    const Index coupled = plane.algebraic.coupled, hinges = first_hinge(cloth);
    plane.reference[1] = plane.reference[2] = 0.0;  // the rest-stiffness factors are overwritten
    plane.reference[3] = 1.0;
    Index result = 1;
    std::vector<double> in_plane(static_cast<std::size_t>(n));
    const double* u = work.pair_direction;
    for (Index c = 0; c < COMPONENTS; ++c) {
        double* diagonal = c == NORMAL ? plane.normal : in_plane.data();
        axis_diagonal<false>(plane, n, c, mass, nullptr, work.blocks, diagonal);
        diagonal_matrix(plane, n, c, diagonal);
        const double* t = plane.frame + 3 * c * n;
        // the in-plane springs, then the hinges' terms the pattern couples (fixed steps); bending springs left
        // out whole, as on a grid
        for (Index e = 0; e < coupled; ++e) {
            const Index k = e < in_plane_springs ? e : hinges + (e - in_plane_springs);
            const Index i = cloth.pairs[k], j = cloth.pairs[count + k];
            const double along = work.pair_along[k], across = work.pair_across[k];
            if (along == 0.0 && across == 0.0) continue;
            const Coupling s = spring_coupling(t[i], t[n + i], t[2 * n + i], t[j], t[n + j], t[2 * n + j], u[k],
                                               u[count + k], u[2 * count + k], along, across);
            add_diagonal(plane, c, i, s.at_i);
            add_diagonal(plane, c, j, s.at_j);
            if (cloth.free[i] != 0.0 && cloth.free[j] != 0.0) add_between(plane, c, e, s.between);
        }
        if (factor_component(plane, c) == 0) continue;
        diagonal_matrix(plane, n, c, diagonal);  // not positive definite (round-off on a crumpled cloth)
        if (factor_component(plane, c) != 0) result = -1;
    }
    return result;
}

void mesh_apply(Plane& plane, Index n, const double* free, const double* r, double* z) {
    // The normal component goes through the cycle and the band solves when it has a system
    // (mesh_systems_from_jacobian), else it is divided by its diagonal.
    const double* f = plane.frame;
    Algebraic& h = plane.algebraic;
    const Index components = plane.reference[3] != 0.0 ? COMPONENTS : NORMAL;
    for (Index c = 0; c < COMPONENTS; ++c) {  // b of t1 and t2 side by side (Pair), the normal's in its row
        double* b = c == NORMAL ? h.b + NORMAL * h.vectors : h.b + c;
        const Index stride = c == NORMAL ? 1 : 2;
        for (Index i = 0; i < n; ++i)
            b[stride * i] = f[3 * c * n + i] * r[i] + f[(3 * c + 1) * n + i] * r[n + i] + f[(3 * c + 2) * n + i] * r[2 * n + i];
    }
    double* normal = h.x + NORMAL * h.vectors;
    if (components == NORMAL)
        for (Index i = 0; i < n; ++i) normal[i] = h.b[NORMAL * h.vectors + i] / plane.normal[i];
    cycle_down(h, components, free);
    const Index coarse_n = plane.coarse_n, last = level_of(h, h.level_count - 1, VECTOR);
    double* local = plane.local;  // (COMPONENTS, n_c) in band order
    for (Index c = 0; c < components; ++c)
        for (Index position = 0; position < coarse_n; ++position)
            local[c * coarse_n + position] = h.b[entry_of(h, c, last + plane.order[position])];
    band_solve_two(plane.bands, plane.rows, local, coarse_n, plane.kd);
    if (components == COMPONENTS)
        band_solve_one(band_of(plane, NORMAL), rows_of(plane, NORMAL), local + NORMAL * coarse_n, coarse_n, plane.kd);
    for (Index c = 0; c < components; ++c)
        for (Index position = 0; position < coarse_n; ++position)
            h.x[entry_of(h, c, last + plane.order[position])] = local[c * coarse_n + position];
    cycle_up(h, components, free);
    const double* x = h.x;  // t1's and t2's side by side
    for (Index c = 0; c < 3; ++c) {  // one row of z at a time
        const double* t1 = f + c * n;
        const double* t2 = f + (3 + c) * n;
        const double* axis = f + (6 + c) * n;
        double* zc = z + c * n;
        for (Index i = 0; i < n; ++i) zc[i] = free[i] * (t1[i] * x[2 * i] + t2[i] * x[2 * i + 1] + axis[i] * normal[i]);
    }
}

}  // namespace wc
