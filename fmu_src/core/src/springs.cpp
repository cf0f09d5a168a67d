// Spring forces (docs/model.md section 3) and their Jacobians for the implicit integrator (port of
// bf41571:fmu_src/wetcloth/kernels/springs.py).
//
// A spring family joins particle i to i + offset.  With m = n - offset, a[0..m) is every spring's
// first end and a[offset..n) its second, so every loop indexes all its arrays with the same counter
// and the compiler vectorises it.  Per family, one loop writes each spring's coefficients into rows
// of their own; then a few loops add the springs' terms to their ends, each filling several rows at
// once (x, y, z, or a block's six slots), so that no input is read again for every row.  The rows a
// loop writes never overlap what it reads: its pointers are __restrict, so no run-time overlap check
// (numba's LLVM needed few written rows for its checks; here any number vectorises).
#include "wetcloth/springs.hpp"

#include "wetcloth/listed_springs.hpp"
#include "wetcloth/spring_law.hpp"

namespace wc {
namespace {

using namespace spring_law;

// The loops below take every row as a __restrict parameter (GCC ignores __restrict on locals and
// struct members; on an inlined function's parameters it keeps it).  "First" rows (xi, ...) start at
// particle 0, "second" rows (xj, ...) at particle off: spring k joins k and k + off.

//: t[k] (N/m): spring k's force on its first end is t[k] (x_i - x_j) (plus thesis damping).  Tension
//: (eq. 3.1) -k (L - l0) / L, for tension-only springs with pulling_stretch's stretch; projected
//: damping (damp = 1) -c ((v_i - v_j) . d) / L^2; stiffness scaled by 1 + wet_factor * saturation.
template <Law L>
void tension_loop(Index m, double l0, double damp, double wet_factor, const double* __restrict kf,
                  const double* __restrict cf, const double* __restrict si, const double* __restrict sj,
                  const double* __restrict xi, const double* __restrict yi, const double* __restrict zi,
                  const double* __restrict xj, const double* __restrict yj, const double* __restrict zj,
                  const double* __restrict vxi, const double* __restrict vyi, const double* __restrict vzi,
                  const double* __restrict vxj, const double* __restrict vyj, const double* __restrict vzj,
                  double* __restrict t) {
    const double width = TENSION_ROUNDING * l0;
    for (Index k = 0; k < m; ++k) {
        const Geometry g = spring_geometry(xi[k], yi[k], zi[k], xj[k], yj[k], zj[k], kf[k], si[k], sj[k], wet_factor);
        const double rate = (vxi[k] - vxj[k]) * g.dx + (vyi[k] - vyj[k]) * g.dy + (vzi[k] - vzj[k]) * g.dz;
        t[k] = tension<L>(g, l0, width, damp, cf[k], rate);
    }
}

template <Law L>
void tension(Index n, Index off, double l0, bool projected, const double* kf, const double* cf, double wet_factor,
             const double* saturation, const double* pos, const double* vel, double* t) {
    tension_loop<L>(n - off, l0, projected ? 1.0 : 0.0, wet_factor, kf, cf, saturation, saturation + off,
                              pos, pos + n, pos + 2 * n, pos + off, pos + n + off, pos + 2 * n + off, vel, vel + n,
                              vel + 2 * n, vel + off, vel + n + off, vel + 2 * n + off, t);
}

//: ox, oy, oz[k] += sign * (scale * coefficient[k] * (a_i - a_j)) for the m springs.
inline void pair_term_loop(Index m, double scale, double sign, const double* __restrict coefficient,
                           const double* __restrict xi, const double* __restrict yi, const double* __restrict zi,
                           const double* __restrict xj, const double* __restrict yj, const double* __restrict zj,
                           double* __restrict ox, double* __restrict oy, double* __restrict oz) {
    for (Index k = 0; k < m; ++k) {
        const double c = scale * coefficient[k];
        ox[k] += sign * (c * (xi[k] - xj[k]));
        oy[k] += sign * (c * (yi[k] - yj[k]));
        oz[k] += sign * (c * (zi[k] - zj[k]));
    }
}

//: out += scale * coefficient[k] * (a_i - a_j) at each spring's first end and the opposite at its
//: second; a and out are (3, n).  One loop per end adds all three rows.
inline void add_pair_term(Index n, Index off, double scale, const double* coefficient, const double* a, double* out) {
    for (Index end = 0; end < 2; ++end) {
        const Index start = end * off;
        pair_term_loop(n - off, scale, 1.0 - 2.0 * static_cast<double>(end), coefficient, a, a + n, a + 2 * n, a + off,
                       a + n + off, a + 2 * n + off, out + start, out + n + start, out + 2 * n + start);
    }
}

//: Add the tension t[k] (x_i - x_j) and, unless projected, the thesis damping (eq. 3.2) -c (v_i - v_j)
//: to force at each spring's first end, the opposite at its second.
inline void add_spring_forces(Index n, Index off, const double* t, bool projected, const double* cf, const double* pos,
                              const double* vel, double* force) {
    add_pair_term(n, off, 1.0, t, pos, force);
    if (!projected) add_pair_term(n, off, -1.0, cf, vel, force);
}

//: Per spring: force coefficient t (as tension, without thesis damping), unit direction u (ux, uy,
//: uz) and the system-matrix block along u u^T + across (I - u u^T) (kg).
template <Law L>
void coefficients_loop(Index m, double l0, bool projected, double wet_factor, double h, double slack_slope,
                       const double* __restrict kf,
                       const double* __restrict cf, const double* __restrict si, const double* __restrict sj,
                       const double* __restrict xi, const double* __restrict yi, const double* __restrict zi,
                       const double* __restrict xj, const double* __restrict yj, const double* __restrict zj,
                       const double* __restrict vxi, const double* __restrict vyi, const double* __restrict vzi,
                       const double* __restrict vxj, const double* __restrict vyj, const double* __restrict vzj,
                       double* __restrict t, double* __restrict ux, double* __restrict uy, double* __restrict uz,
                       double* __restrict along, double* __restrict across) {
    const double width = TENSION_ROUNDING * l0;
    for (Index k = 0; k < m; ++k) {
        const Geometry g = spring_geometry(xi[k], yi[k], zi[k], xj[k], yj[k], zj[k], kf[k], si[k], sj[k], wet_factor);
        const Coefficients c = spring_law::coefficients<L>(g, l0, width, projected, h, slack_slope, cf[k],
                                                           vxi[k] - vxj[k], vyi[k] - vyj[k], vzi[k] - vzj[k]);
        t[k] = c.t;
        ux[k] = c.ux;
        uy[k] = c.uy;
        uz[k] = c.uz;
        along[k] = c.along;
        across[k] = c.across;
    }
}

template <Law L>
void coefficients(Index n, Index off, double l0, bool projected, const double* kf, const double* cf,
                  double wet_factor, const double* saturation, const double* pos, const double* vel, double h,
                  double slack_slope, double* t, double* u, double* along, double* across) {
    coefficients_loop<L>(n - off, l0, projected, wet_factor, h, slack_slope, kf, cf, saturation, saturation + off, pos,
                                   pos + n, pos + 2 * n, pos + off, pos + n + off, pos + 2 * n + off, vel, vel + n,
                                   vel + 2 * n, vel + off, vel + n + off, vel + 2 * n + off, t, u, u + n, u + 2 * n,
                                   along, across);
}

//: Rows xx..yz[j] += the block of spring j (along, across, u from that spring on), j < count.
inline void one_end_blocks(Index count, const double* __restrict along, const double* __restrict across,
                           const double* __restrict ux, const double* __restrict uy, const double* __restrict uz,
                           double* __restrict xx, double* __restrict yy, double* __restrict zz,
                           double* __restrict xy, double* __restrict xz, double* __restrict yz) {
    for (Index j = 0; j < count; ++j) {
        const Block b = spring_block(along[j], across[j], ux[j], uy[j], uz[j]);
        xx[j] += b.xx;
        yy[j] += b.yy;
        zz[j] += b.zz;
        xy[j] += b.xy;
        xz[j] += b.xz;
        yz[j] += b.yz;
    }
}

//: Rows xx..yz[j] += the block of spring off + j (first end: along_a ... from spring off on) plus that
//: of spring j (second end: along_b ... from spring 0 on), j < count.
inline void both_ends_blocks(Index count, const double* __restrict along_a, const double* __restrict across_a,
                             const double* __restrict ux_a, const double* __restrict uy_a,
                             const double* __restrict uz_a, const double* __restrict along_b,
                             const double* __restrict across_b, const double* __restrict ux_b,
                             const double* __restrict uy_b, const double* __restrict uz_b, double* __restrict xx,
                             double* __restrict yy, double* __restrict zz, double* __restrict xy,
                             double* __restrict xz, double* __restrict yz) {
    for (Index j = 0; j < count; ++j) {
        const Block a = spring_block(along_a[j], across_a[j], ux_a[j], uy_a[j], uz_a[j]);
        const Block b = spring_block(along_b[j], across_b[j], ux_b[j], uy_b[j], uz_b[j]);
        xx[j] += a.xx + b.xx;
        yy[j] += a.yy + b.yy;
        zz[j] += a.zz + b.zz;
        xy[j] += a.xy + b.xy;
        xz[j] += a.xz + b.xz;
        yz[j] += a.yz + b.yz;
    }
}

//: Add each spring's block to blocks (6, n: xx, yy, zz, xy, xz, yz) at both its ends.  Particle i is
//: the first end of spring i (if i < m = n - off) and the second end of spring i - off (if i >= off).
//: Particles off..m-1 are both and get their two blocks in one pass, so each of the six slots is read
//: and written once, not once per end (measured faster in numba: bench/spring_assembly.py).
void add_blocks(Index n, Index off, const double* along, const double* across, const double* u, double* blocks) {
    const Index m = n - off;
    const Index head = off < m ? off : m;  // min(off, m), max(off, m)
    const Index tail = m > off ? m : off;
    const double* ux = u;
    const double* uy = u + n;
    const double* uz = u + 2 * n;
    auto row = [&](Index slot, Index lo) { return blocks + slot * n + lo; };
    // First ends only: particles 0..head-1, springs 0..head-1.
    one_end_blocks(head, along, across, ux, uy, uz, row(0, 0), row(1, 0), row(2, 0), row(3, 0), row(4, 0), row(5, 0));
    // Particle off + j: first end of spring off + j, second end of spring j.
    both_ends_blocks(m - off, along + off, across + off, ux + off, uy + off, uz + off, along, across, ux, uy, uz,
                     row(0, off), row(1, off), row(2, off), row(3, off), row(4, off), row(5, off));
    // Second ends only: particles tail..n-1, springs tail-off...
    const Index s = tail - off;
    one_end_blocks(n - tail, along + s, across + s, ux + s, uy + s, uz + s, row(0, tail), row(1, tail), row(2, tail),
                   row(3, tail), row(4, tail), row(5, tail));
}

//: One family's blocks in single precision (Work::single_blocks' rows), for springs k < m.
inline void single_blocks_loop(Index m, const double* __restrict ux, const double* __restrict uy,
                               const double* __restrict uz, const double* __restrict al,
                               const double* __restrict ac, float* __restrict sux, float* __restrict suy,
                               float* __restrict suz, float* __restrict sac, float* __restrict saniso) {
    for (Index k = 0; k < m; ++k) {
        sux[k] = static_cast<float>(ux[k]);
        suy[k] = static_cast<float>(uy[k]);
        suz[k] = static_cast<float>(uz[k]);
        sac[k] = static_cast<float>(ac[k]);
        saniso[k] = static_cast<float>(al[k] - ac[k]);
    }
}

//: One family's product per spring as product_loop in single precision from its blocks' rows (ux, uy,
//: uz, across, along - across); p's differences (first ends from xi, ..., second ends from xj, ...) taken
//: in double precision, then rounded.
inline void single_product_loop(Index m, const float* __restrict ux, const float* __restrict uy,
                                const float* __restrict uz, const float* __restrict ac,
                                const float* __restrict aniso, const double* __restrict xi,
                                const double* __restrict yi, const double* __restrict zi,
                                const double* __restrict xj, const double* __restrict yj,
                                const double* __restrict zj, float* __restrict sx, float* __restrict sy,
                                float* __restrict sz) {
    for (Index k = 0; k < m; ++k) {
        const float dx = static_cast<float>(xi[k] - xj[k]), dy = static_cast<float>(yi[k] - yj[k]),
                    dz = static_cast<float>(zi[k] - zj[k]);
        const float proj = aniso[k] * (ux[k] * dx + uy[k] * dy + uz[k] * dz);
        sx[k] = ac[k] * dx + proj * ux[k];
        sy[k] = ac[k] * dy + proj * uy[k];
        sz[k] = ac[k] * dz + proj * uz[k];
    }
}

//: One family's product per spring: s = S (p_i - p_j) for each spring k < m (S = across I + (along -
//: across) u u^T, its block), into the rows sx, sy, sz (p's first ends from xi, ..., its second ends
//: from xj, ...).
inline void product_loop(Index m, const double* __restrict ux, const double* __restrict uy,
                         const double* __restrict uz, const double* __restrict al, const double* __restrict ac,
                         const double* __restrict xi, const double* __restrict yi, const double* __restrict zi,
                         const double* __restrict xj, const double* __restrict yj, const double* __restrict zj,
                         double* __restrict sx, double* __restrict sy, double* __restrict sz) {
    for (Index k = 0; k < m; ++k) {
        const double dx = xi[k] - xj[k], dy = yi[k] - yj[k], dz = zi[k] - zj[k];
        const double proj = (al[k] - ac[k]) * (ux[k] * dx + uy[k] * dy + uz[k] * dz);
        sx[k] = ac[k] * dx + proj * ux[k];
        sy[k] = ac[k] * dy + proj * uy[k];
        sz[k] = ac[k] * dz + proj * uz[k];
    }
}

//: o[k] += s[k] for k < count.
template <class T>
inline void add_row(Index count, const T* __restrict s, T* __restrict o) {
    for (Index k = 0; k < count; ++k) o[k] += s[k];
}

//: o[k] = (o[k] + first[k]) - second[k] for k < count: a particle that is the first end of one spring
//: and the second end of another, in the order of two passes over the ends.
template <class T>
inline void add_both_ends(Index count, const T* __restrict first, const T* __restrict second, T* __restrict o) {
    for (Index k = 0; k < count; ++k) o[k] = (o[k] + first[k]) - second[k];
}

//: o[k] -= s[k] for k < count.
template <class T>
inline void subtract_row(Index count, const T* __restrict s, T* __restrict o) {
    for (Index k = 0; k < count; ++k) o[k] -= s[k];
}

//: out += the product's per-spring rows s (3, n, a family of offset off joining m = n - off pairs):
//: added at each spring's first end, subtracted at its second (particle j is the first end of spring j
//: and the second of spring j - off: its own first, in one pass that reads and writes it once).
template <class T>
void scatter(Index n, Index off, const T* s, T* out) {
    const Index m = n - off;
    const Index head = off < m ? off : m;  // particles 0 .. head - 1: first ends only
    const Index tail = m > off ? m : off;  // particles tail .. n - 1: second ends only
    for (Index c = 0; c < 3; ++c) {
        const T* sc = s + c * n;
        T* o = out + c * n;
        add_row(head, sc, o);
        if (m > off) add_both_ends(m - off, sc + off, sc, o + off);
        subtract_row(n - tail, sc + tail - off, o + tail);
    }
}

//: The families' product in single precision (work.single_blocks, summed in float over the families in
//: work.single_buf), then added to out.
void single_families_matvec(const Cloth& cloth, const Work& work, const double* p, double* out) {
    const Index n = cloth.n;
    float* scratch = work.single_buf;  // (3, n) one family's per-spring products
    float* sum = scratch + 3 * n;      // (3, n) the families' sum
    for (Index k = 0; k < 3 * n; ++k) sum[k] = 0.0f;
    for (Index f = 0; f < cloth.families; ++f) {
        const Index off = cloth.offsets[f];
        const Index m = n - off;
        if (m <= 0) continue;
        const float* b = work.single_blocks + f * 5 * n;
        single_product_loop(m, b, b + n, b + 2 * n, b + 3 * n, b + 4 * n, p, p + n, p + 2 * n, p + off,
                            p + n + off, p + 2 * n + off, scratch, scratch + n, scratch + 2 * n);
        scatter(n, off, scratch, sum);
    }
    for (Index k = 0; k < 3 * n; ++k) out[k] += static_cast<double>(sum[k]);
}

}  // namespace

void spring_forces(const Cloth& cloth, const Physics& phys, const double* saturation, const double* pos,
                   const double* vel, double* force, double* buf) {
    const Index n = cloth.n;
    double* t = buf;
    for (Index f = 0; f < cloth.families; ++f) {
        const Index off = cloth.offsets[f];
        const double* kf = cloth.stiffness + f * n;
        const double* cf = cloth.damping + f * n;
        const double l0 = cloth.rest[f];
        switch (law_of(cloth.tension_only[f], l0)) {
            case Law::BOTH_WAYS:
                tension<Law::BOTH_WAYS>(n, off, l0, phys.projected, kf, cf, phys.wet_factor, saturation, pos, vel, t);
                break;
            case Law::CLAMPED:
                tension<Law::CLAMPED>(n, off, l0, phys.projected, kf, cf, phys.wet_factor, saturation, pos, vel, t);
                break;
            case Law::EXACT:
                tension<Law::EXACT>(n, off, l0, phys.projected, kf, cf, phys.wet_factor, saturation, pos, vel, t);
                break;
        }
        add_spring_forces(n, off, t, phys.projected, cf, pos, vel, force);
    }
}

void spring_forces_and_blocks(const Cloth& cloth, const Physics& phys, const double* saturation, const double* pos,
                              const double* vel, double h, double slack_slope, Work& work) {
    const Index n = cloth.n;
    double* t = work.buf;
    for (Index f = 0; f < cloth.families; ++f) {
        const Index off = cloth.offsets[f];
        double* u = work.direction + f * 3 * n;
        const double* kf = cloth.stiffness + f * n;
        const double* cf = cloth.damping + f * n;
        double* along = work.along + f * n;
        double* across = work.across + f * n;
        const double l0 = cloth.rest[f];
        switch (law_of(cloth.tension_only[f], l0)) {
            case Law::BOTH_WAYS:
                coefficients<Law::BOTH_WAYS>(n, off, l0, phys.projected, kf, cf, phys.wet_factor, saturation, pos, vel,
                                             h, slack_slope, t, u, along, across);
                break;
            case Law::CLAMPED:
                coefficients<Law::CLAMPED>(n, off, l0, phys.projected, kf, cf, phys.wet_factor, saturation, pos, vel, h,
                                           slack_slope, t, u, along, across);
                break;
            case Law::EXACT:
                coefficients<Law::EXACT>(n, off, l0, phys.projected, kf, cf, phys.wet_factor, saturation, pos, vel, h,
                                         slack_slope, t, u, along, across);
                break;
        }
        add_spring_forces(n, off, t, phys.projected, cf, pos, vel, work.force);
        add_blocks(n, off, along, across, u, work.diagonal_blocks);
        float* single = work.single_blocks + f * 5 * n;
        single_blocks_loop(n - off, u, u + n, u + 2 * n, along, across, single, single + n, single + 2 * n,
                           single + 3 * n, single + 4 * n);
    }
}

// Per family, each spring's product into a scratch row (3, n), then scattered to its ends.
void spring_matvec(const Cloth& cloth, const Work& work, const double* p, double* out, Precision blocks) {
    const Index n = cloth.n;
    if (blocks == Precision::SINGLE && cloth.families > 0) {
        single_families_matvec(cloth, work, p, out);
    } else {
        double* scratch = work.buf;  // (3, n)
        for (Index f = 0; f < cloth.families; ++f) {
            const Index off = cloth.offsets[f];
            const Index m = n - off;
            if (m <= 0) continue;
            const double* u = work.direction + f * 3 * n;
            product_loop(m, u, u + n, u + 2 * n, work.along + f * n, work.across + f * n, p, p + n, p + 2 * n,
                         p + off, p + n + off, p + 2 * n + off, scratch, scratch + n, scratch + 2 * n);
            scatter(n, off, scratch, out);
        }
    }
    if (cloth.pair_count > 0) listed_spring_matvec(cloth, work, p, out);
}

}  // namespace wc
