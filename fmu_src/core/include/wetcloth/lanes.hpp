// Loops over values in interleaved lanes, for running maxima, sums and the like that would otherwise wait on
// each other: value k of the whole rounds in lane k % LANES, the rest in lanes 0, 1, ... in order.  The lanes'
// results are combined by the caller; for extremes that is the same value as one pass in order, sums round
// otherwise (in a fixed order: the same on every CPU).
#pragma once

#include "wetcloth/core.hpp"

namespace wc {

//: f(lane, k) for k = 0 .. count - 1, in rounds of LANES.
template <Index LANES, class F>
inline void in_lanes(Index count, F&& f) {
    const Index whole = count - count % LANES;
    for (Index k = 0; k < whole; k += LANES)
        for (Index l = 0; l < LANES; ++l) f(l, k + l);
    for (Index k = whole; k < count; ++k) f(k - whole, k);
}

//: The sum of LANES partial sums (as in_lanes leaves them), added pairwise: ((0 + 1) + (2 + 3)) + ... .
template <Index LANES>
inline double sum_of_lanes(const double* lanes) {
    if constexpr (LANES == 1) {
        return lanes[0];
    } else {
        return sum_of_lanes<LANES / 2>(lanes) + sum_of_lanes<LANES / 2>(lanes + LANES / 2);
    }
}

}  // namespace wc
