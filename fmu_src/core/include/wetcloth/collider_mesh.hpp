// Mesh colliders (docs/model.md section 6.3): a rigid triangle mesh, a solid if it is closed, else a
// shell (a bucket's wall) whose two sides both keep the cloth off.  Distances go to the nearest triangle
// within reach, found through a uniform grid of cells over the mesh (built with the scene, Python's
// wetcloth.collider_meshes), so a far collider costs a box test.
#pragma once
#include <utility>
#include <vector>

#include "wetcloth/core.hpp"

namespace wc {

//: Columns of ColliderMeshes::headers: the mesh's first cell in cell_start; its grid's origin (m), cell
//: side (m) and cells along x, y, z; 1 for a closed mesh (a solid), 0 for a shell; its bounding box.
enum MeshColumn : Index {
    M_FIRST_CELL = 0, M_ORIGIN_X, M_ORIGIN_Y, M_ORIGIN_Z, M_CELL, M_CELLS_X, M_CELLS_Y, M_CELLS_Z, M_SOLID,
    M_LO_X, M_LO_Y, M_LO_Z, M_HI_X, M_HI_Y, M_HI_Z, MESH_COLUMNS
};

//: Distance (m) from point p (3) to mesh `mesh`'s nearest triangle, if one is within reach (m), with the
//: unit normal from the surface towards p (normal, 3); reach itself if none is.  Negative inside a solid
//: (its outward normal then), from the pseudo-normal of the nearest feature (face, edge or vertex).
double mesh_distance(const ColliderMeshes& meshes, Index mesh, const double* p, double reach, double* normal);

//: Whether the segment from a to b (3 each) crosses a triangle of mesh `mesh`: the first crossing's point
//: (hit, 3) and the unit normal of its face towards a (normal, 3).
bool mesh_crossing(const ColliderMeshes& meshes, Index mesh, const double* a, const double* b, double* hit,
                   double* normal);

//: Appends to `out` the triangles of mesh `mesh` listed in the cells that the box [lo, hi] (3 each, m)
//: overlaps (a triangle in several cells more than once).
void mesh_triangles_in(const ColliderMeshes& meshes, Index mesh, const double* lo, const double* hi,
                       std::vector<Index>& out);

//: Whether a cell of mesh `mesh` that the box [lo, hi] (3 each, m) overlaps lists a triangle (whether
//: mesh_triangles_in would append any), by one look at each row of cells.
bool mesh_lists_triangles_in(const ColliderMeshes& meshes, Index mesh, const double* lo, const double* hi);

//: Mesh `mesh`'s vertices (those of its triangles) as (cell, vertex) in `out`, by cell: the cell of its grid
//: that holds each (the nearest, for rounding at the grid's edge).
void mesh_vertex_cells(const ColliderMeshes& meshes, Index mesh, std::vector<std::pair<Index, Index>>& out);

//: Appends to `out` the vertices of mesh `mesh` in the cells that the box [lo, hi] (3 each, m) overlaps, each
//: once, from `cells` (mesh_vertex_cells's): every one of its vertices inside the box, and some near it.
void mesh_vertices_in(const ColliderMeshes& meshes, Index mesh, const std::vector<std::pair<Index, Index>>& cells,
                      const double* lo, const double* hi, std::vector<Index>& out);

}  // namespace wc
