// The elements of candidate pairs (particles, edges, triangles): their particles, boxes and distances, and a
// pair's record while a list is searched (broad_phase.cpp's hash and far_pairs.cpp's cells share them).
#pragma once

#include <cstring>
#include <limits>

#include "wetcloth/core.hpp"
#include "wetcloth/self_contact/geometry.hpp"

namespace wc::self_contact {

//: Axis-aligned boxes (3, count) of `count` elements: lo[c * count + e], hi likewise (m).
struct Boxes {
    const double* lo;
    const double* hi;
    Index count;
    double low(int c, Index e) const { return lo[c * count + e]; }
    double high(int c, Index e) const { return hi[c * count + e]; }
};

//: Each element's (`width` particles, rows of `elements`) box at positions x (3, n).
inline void boxes(const double* x, Index n, const Index* elements, Index count, int width, double* lo, double* hi) {
    constexpr double INF = std::numeric_limits<double>::infinity();
    for (Index e = 0; e < count; ++e) {
        for (int c = 0; c < 3; ++c) {
            const double* row = x + c * n;
            double a = INF;
            double b = -INF;
            for (int k = 0; k < width; ++k) {
                const double v = row[elements[e * width + k]];
                a = py_min(a, v);
                b = py_max(b, v);
            }
            lo[c * count + e] = a;
            hi[c * count + e] = b;
        }
    }
}

//: Whether box a of p and box b of q are within `pad` (m) of each other along every axis.
inline bool boxes_overlap(const Boxes& p, Index a, const Boxes& q, Index b, double pad) {
    return p.low(0, a) <= q.high(0, b) + pad && q.low(0, b) - pad <= p.high(0, a) && p.low(1, a) <= q.high(1, b) + pad &&
           q.low(1, b) - pad <= p.high(1, a) && p.low(2, a) <= q.high(2, b) + pad && q.low(2, b) - pad <= p.high(2, a);
}

//: A pair's record while a list is searched: first, second element, bits of its distance (m).
inline Index gap_bits(double gap) {
    Index bits;
    std::memcpy(&bits, &gap, sizeof bits);
    return bits;
}
inline double gap_of(Index bits) {
    double gap;
    std::memcpy(&gap, &bits, sizeof gap);
    return gap;
}

//: The four particles (a | b, c, d) of point a and triangle t, or (a, b | c, d) of edges a and e.
template <int KIND>
inline void particles(const Contact& contact, Index a, Index e, Index idx[4]) {
    if (KIND == POINT_TRIANGLE) {
        idx[0] = a;
        for (int j = 0; j < 3; ++j) idx[1 + j] = contact.triangles[3 * e + j];
    } else {
        idx[0] = contact.edges[2 * a], idx[1] = contact.edges[2 * a + 1];
        idx[2] = contact.edges[2 * e], idx[3] = contact.edges[2 * e + 1];
    }
}

//: Whether element a (a particle or an edge) and element e (a triangle or an edge) share a particle.
template <int KIND>
inline bool share_a_particle(const Contact& contact, Index a, Index e) {
    if (KIND == POINT_TRIANGLE) {
        for (int j = 0; j < 3; ++j)
            if (a == contact.triangles[3 * e + j]) return true;
        return false;
    }
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            if (contact.edges[2 * a + i] == contact.edges[2 * e + j]) return true;
    return false;
}

//: The distance (m) at x of the pair's particles if it is a candidate: within `reach` (m), and not already
//: closer than `thickness` (m) in the flat rest sheet (such neighbours are the fabric itself, not two
//: layers); infinity if it is not.
template <int KIND>
inline double candidate_distance(const double* x, const double* rest, Index n, const Index idx[4], double reach,
                                 double thickness) {
    const double gap = distance(KIND, point(x, n, idx[0]), point(x, n, idx[1]), point(x, n, idx[2]),
                                point(x, n, idx[3]));
    if (gap >= reach || distance(KIND, point(rest, n, idx[0]), point(rest, n, idx[1]), point(rest, n, idx[2]),
                                 point(rest, n, idx[3])) < thickness)
        return std::numeric_limits<double>::infinity();
    return gap;
}

}  // namespace wc::self_contact
