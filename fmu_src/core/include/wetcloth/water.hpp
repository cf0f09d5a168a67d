// Water forces (docs/model.md section 4): submerged fraction, buoyancy, Stokes drag and face drag, the
// face drag serving both fluids, the water and the air above it (section 4.4) (port of
// bf41571:fmu_src/wetcloth/kernels/water.py).
//
// On a grid, face drag works per grid cell, each split into two triangles (i, i+1, i+nx+1) and (i, i+nx+1, i+nx),
// the split of Topology.triangles.  Per-triangle values go into rows of length n + nx + 1 (cell i at
// slot i + nx + 1; slots of non-cells stay zero), and each particle gathers its share of its six
// triangles' values with the weights of its area: the right-angle corner 1/2, the other two 1/4 each.
// A corner takes its share of a triangle's drag at its own velocity (docs/model.md 4.3): the triangles'
// shapes (normal, area, submerged fraction) are computed once, then the drag rows for each corner of the
// triangles, at that corner's velocities, and gathered into it.
#pragma once
#include "wetcloth/core.hpp"
#include "wetcloth/mesh_records.hpp"

namespace wc {

//: Write each of the n particles' submerged fraction (0..1) from heights z (m) into s; return the largest.
//: smooth: the fraction of a slab of `thickness` (m) about the particle below water_level (m); else 0 or 1.
double submerged_fractions(Index n, const double* z, double water_level, double thickness, bool smooth, double* s);

//: Add Archimedes' upward force rho g V s (eq. 3.4, corrected) to row z of force (3, n): density kg/m3,
//: gravity m/s2, volume (n) m3.
void buoyancy(Index n, const double* s, const double* volume, double density, double gravity, double* force);

//: Add -6 pi a eta s (v - v_water) (eq. 3.5) to force (3, n); coefficient (n) is 6 pi a eta (N s/m),
//: current (m/s) the water's velocity, vel (3, n) m/s.
void stokes_drag(Index n, const double* s, const double* coefficient, double current_x, double current_y,
                 const double* vel, double* force);

//: A fluid the face drag acts in: its density (kg/m3), drag coefficients C_n, C_t (-) and c_lin (N s/m3),
//: its velocity (m/s), and which part of each triangle it covers: the submerged fraction s_t of the
//: triangle (the water) or, above the water (the air), 1 - s_t.
struct Fluid {
    double density = 0, c_normal = 0, c_tangential = 0, c_linear = 0;
    double flow_x = 0, flow_y = 0, flow_z = 0;
    bool above = false;
};

//: The water of a scene (docs/model.md section 4.3): flowing with the current, drag_linear its own.
inline Fluid water_fluid(const Physics& p) {
    return {p.water_density, p.drag_normal, p.drag_tangential, p.drag_linear, p.current_x, p.current_y, 0.0, false};
}

//: The air above the water (section 4.4): the same plate coefficients, no linear term, blowing with the wind.
inline Fluid air_fluid(const Physics& p) {
    return {p.air_density, p.drag_normal, p.drag_tangential, 0.0, p.wind_x, p.wind_y, p.wind_z, true};
}

//: Add the face-model drag (docs/model.md section 4.3) of the fluid on the nx x ny grid to force (3, n);
//: s (n) the particles' submerged fractions; cells (DRAG_CELL_ROWS, n + nx + 1) scratch.
void face_drag(Index nx, Index ny, const double* pos, const double* vel, const double* s, const Fluid& fluid,
               double* force, double* cells, bool skip_dry_rows = true);

//: Face drag as face_drag, plus h (s) times its velocity Jacobian added to blocks (6, n: xx, yy, zz, xy, xz,
//: yz): each particle's share of its triangles' drag depends on its own velocity alone, so these blocks are
//: the whole of it.
void face_drag_and_blocks(Index nx, Index ny, const double* pos, const double* vel, const double* s,
                          const Fluid& fluid, double h, double* force, double* blocks, double* cells,
                          bool skip_dry_rows = true);

//: Fluids a mesh's face drag takes in one pass over its triangles: the water and the air above it.
inline constexpr Index MESH_FLUIDS = 2;

//: The face drag of fluid_count (at most MESH_FLUIDS) fluids on a mesh's triangles (m, 3) added to the
//: force sums of its particles' records (from their state), each triangle's shared by its corners as
//: `shares` (m, 3) says; with the records' blocks, h (s) times its velocity Jacobian added to their
//: drag blocks likewise (each corner's share at its own velocity).  With skip_idle, triangles with no corner in
//: any of the fluids are skipped.
void mesh_face_drag(Index triangle_count, const Index* triangles, const double* shares, const Fluid* fluids,
                    Index fluid_count, double h, const MeshRecords& records, bool skip_idle);

}  // namespace wc
