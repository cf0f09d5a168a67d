// Small operations on 3-vectors held as three doubles, shared by the force families.
#pragma once

namespace wc {

//: out (3) = a x b.
inline void cross(const double* a, const double* b, double* out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

}  // namespace wc
