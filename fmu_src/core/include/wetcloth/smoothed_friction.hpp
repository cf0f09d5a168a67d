// IPC's smoothed Coulomb friction (Li et al. 2020, "Incremental Potential Contact"), on a slip velocity u
// (3, m/s) across a contact's normal n: the force -mu N f1(|u|) u / |u|, f1(y) = 2 y / eps - y^2 / eps^2 below
// the slip speed eps, 1 above it.  Below eps it acts as a stiff viscous stick, so that friction never
// reverses a slip within a step, however long: the moving meshes' supports (collider_supports.hpp) and, at
// fixed steps, the particles sliding on the floor or a collider (sliding.hpp).
#pragma once

#include "wetcloth/core.hpp"

namespace wc {

//: The slip speed eps (m/s) below which friction acts as a stick (coefficient 2 mu N / eps, N s/m) rather than
//: Coulomb's constant mu N: IPC's default.  A cloth held so creeps at most this fast.  (The cloth's pairs with
//: itself have their own: collider_supports.hpp's SELF_SLIP_SPEED.)
inline constexpr double SLIP_SPEED = 1e-3;

//: f1(y) / y (1/(m/s)) at slip speed y (m/s): 2 / eps - y / eps^2 below eps (m/s), else 1 / y.
inline double slip_factor(double y, double eps = SLIP_SPEED) {
    return y < eps ? 2.0 / eps - y / (eps * eps) : 1.0 / y;
}

//: f0(y) (m/s), the smoothed |u|: y^2 / eps - y^3 / (3 eps^2) + eps / 3 below eps (m/s), else y (f0' = f1).
inline double smoothed_speed(double y, double eps = SLIP_SPEED) {
    return y < eps ? y * y / eps - y * y * y / (3.0 * eps * eps) + eps / 3.0 : y;
}

//: The friction's stiffness in the slip velocity u (3, m/s, |u| = y, across the unit normal nn (3)), for a
//: normal force of mu_n = mu N (N): H = mu N (f1/y (I - n n^T) - b t t^T), t = u / y, with b = 1 / y at or above
//: eps (the cone's radial part has no stiffness), y / eps^2 below (f1' = f1/y - b); at y = 0 no direction.
//: Into out (6: xx yy zz xy xz yz, N s/m).
inline void slip_stiffness(double mu_n, double y, const double* u, const double* nn, double* out,
                           double eps = SLIP_SPEED) {
    const double a = slip_factor(y, eps);
    const double b = y >= eps ? 1.0 / y : y / (eps * eps);
    double tt[3] = {0.0, 0.0, 0.0};
    if (y > 0.0) {
        for (int c = 0; c < 3; ++c) tt[c] = u[c] / y;
    }
    const int row[6] = {0, 1, 2, 0, 0, 1}, column[6] = {0, 1, 2, 1, 2, 2};
    for (int e = 0; e < 6; ++e) {
        const int r = row[e], c = column[e];
        out[e] = mu_n * (a * ((r == c ? 1.0 : 0.0) - nn[r] * nn[c]) - b * tt[r] * tt[c]);
    }
}

}  // namespace wc
