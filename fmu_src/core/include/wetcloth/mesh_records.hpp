// A mesh's per-particle records (docs/core.md): its listed springs and face drag reach their ends and
// corners by index, and from the (3, n) rows each end cost up to 16 scattered cache lines (its x, v,
// saturation and submerged fraction read, its force and blocks added to).  In records of each
// particle's slots side by side it costs one line read and two written.  The records live in Work::cells
// (a mesh's cells_length); every force evaluation fills the state and starts the sums from gravity, sums
// the springs and the face drag into them and stores them in the rows (assembly.cpp).
#pragma once
#include "wetcloth/core.hpp"

namespace wc {

//: Slots of a particle's state record: position (3, m), velocity (3, m/s), saturation, submerged fraction.
enum StateSlot : Index { STATE_X = 0, STATE_V = 3, STATE_SATURATION = 6, STATE_SUBMERGED = 7, STATE_SLOTS = 8 };

//: Slots of a particle's sums: force (3, N), the springs' diagonal blocks (6, as Work::diagonal_blocks)
//: and the drag's blocks (6, as Work::blocks); with SUM_FORCE_SLOTS (forces alone) the force only.
enum SumSlot : Index { SUM_FORCE = 0, SUM_DIAGONAL = 3, SUM_BLOCKS = 9, SUM_SLOTS = 16, SUM_FORCE_SLOTS = 4 };
static_assert(STATE_SLOTS + SUM_SLOTS + 8 <= MESH_RECORD_SLOTS, "Work::cells holds the records and their alignment");

//: The records of n particles: state (n, STATE_SLOTS) and sums (n, stride), each record on a 64-byte line.
struct MeshRecords {
    double* state;
    double* sums;
    Index stride;  // SUM_SLOTS, or SUM_FORCE_SLOTS for the forces alone
};

//: The records in a mesh's Work::cells for n particles (stride: blocks_wanted ? SUM_SLOTS : SUM_FORCE_SLOTS),
//: the state filled from pos, vel (3, n) and saturation, submerged (n), the sums' force from force (3, n)
//: and their blocks zeroed.
MeshRecords fill_records(Index n, double* cells, bool blocks_wanted, const double* pos, const double* vel,
                         const double* saturation, const double* submerged, const double* force);

//: The records' sums (filled since fill_records) into force (3, n) and, with the blocks, diagonal_blocks
//: and blocks (6, n).
void store_sums(Index n, const MeshRecords& records, double* force, double* diagonal_blocks, double* blocks);

}  // namespace wc
