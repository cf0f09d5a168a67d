// Bindings of the band factorisation and solves (band.cpp) under the names of bf41571:fmu_src/wetcloth/kernels/lapack.py.
#include "convert.hpp"
#include "wetcloth/band.hpp"

namespace {
namespace nb = nanobind;
using Band = nb::ndarray<double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using Bands = nb::ndarray<double, nb::ndim<3>, nb::c_contig, nb::device::cpu>;
}  // namespace

WETCLOTH_BINDINGS(m) {
    m.def("band_factor", [](Band band, Band rows) {
        const wc::Index n = band.shape(0), kd = band.shape(1) - 1;
        if (rows.shape(0) != band.shape(0) || rows.shape(1) != band.shape(1))
            throw nb::value_error("band_factor: rows must have the shape of band");
        return wc::band_factor(band.data(), rows.data(), n, kd);
    }, nb::arg("band"), nb::arg("rows"));
    m.def("band_solve_two", [](Bands bands, Bands rows, Band b) {
        const wc::Index n = bands.shape(1), kd = bands.shape(2) - 1;
        if (bands.shape(0) != 2 || rows.shape(0) != 2 || rows.shape(1) != bands.shape(1) ||
            rows.shape(2) != bands.shape(2) || b.shape(0) != 2 || static_cast<wc::Index>(b.shape(1)) != n)
            throw nb::value_error("band_solve_two: expected bands, rows (2, n, kd + 1) and b (2, n)");
        wc::band_solve_two(bands.data(), rows.data(), b.data(), n, kd);
    });
}
