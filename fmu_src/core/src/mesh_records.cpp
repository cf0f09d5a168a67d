// A mesh's per-particle records (wetcloth/mesh_records.hpp).
#include "wetcloth/mesh_records.hpp"

#include <cstdint>

namespace wc {

MeshRecords fill_records(Index n, double* cells, bool blocks_wanted, const double* pos, const double* vel,
                         const double* saturation, const double* submerged, const double* force) {
    const std::uintptr_t address = reinterpret_cast<std::uintptr_t>(cells);
    double* state = cells + ((64 - address % 64) % 64) / sizeof(double);  // cells is 8-byte aligned
    MeshRecords r{state, state + STATE_SLOTS * n, blocks_wanted ? SUM_SLOTS : SUM_FORCE_SLOTS};
    for (Index i = 0; i < n; ++i) {
        double* s = state + STATE_SLOTS * i;
        double* sum = r.sums + r.stride * i;
        for (Index c = 0; c < 3; ++c) {
            s[STATE_X + c] = pos[c * n + i];
            s[STATE_V + c] = vel[c * n + i];
            sum[SUM_FORCE + c] = force[c * n + i];
        }
        s[STATE_SATURATION] = saturation[i];
        s[STATE_SUBMERGED] = submerged[i];
        for (Index e = SUM_FORCE + 3; e < r.stride; ++e) sum[e] = 0.0;
    }
    return r;
}

void store_sums(Index n, const MeshRecords& records, double* force, double* diagonal_blocks, double* blocks) {
    const Index stride = records.stride;
    for (Index i = 0; i < n; ++i) {
        const double* s = records.sums + stride * i;
        for (Index c = 0; c < 3; ++c) force[c * n + i] = s[SUM_FORCE + c];
    }
    if (stride != SUM_SLOTS) return;
    for (Index i = 0; i < n; ++i) {
        const double* s = records.sums + stride * i;
        for (Index c = 0; c < 6; ++c) {
            diagonal_blocks[c * n + i] = s[SUM_DIAGONAL + c];
            blocks[c * n + i] = s[SUM_BLOCKS + c];
        }
    }
}

}  // namespace wc
