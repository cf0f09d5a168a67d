// What a native unit is built with, declared for unit.cpp: the scene's colliders and keys, a cloth from a mesh
// file, the pins and the FMI 3.0 constant outputs.  They are defined, with the variable table, in the source
// wetcloth.fmu.native generates for each unit (wetcloth_fmu_variables.cpp), so that unit.cpp, fmi2.cpp and
// fmi3.cpp compile once for every unit and a unit's build compiles that one source.  Each array NAME has its
// length NAME_SIZE (the array itself holds a trailing 0 more: C++ has no empty arrays).
#pragma once

#include <cstddef>

#include "wetcloth/model.hpp"

#define WETCLOTH_UNIT_ARRAY(Element, NAME) \
    extern const std::size_t NAME##_SIZE;  \
    extern const Element NAME[]

namespace wc::fmu {

// The scene's colliders (their rows, collider_meshes' arrays of the mesh colliders) and keys (fixtures_header).
WETCLOTH_UNIT_ARRAY(double, SCENE_COLLIDERS);
WETCLOTH_UNIT_ARRAY(double, SCENE_MESH_HEADERS);
WETCLOTH_UNIT_ARRAY(double, SCENE_MESH_VERTICES);
WETCLOTH_UNIT_ARRAY(double, SCENE_FACE_NORMALS);
WETCLOTH_UNIT_ARRAY(double, SCENE_EDGE_NORMALS);
WETCLOTH_UNIT_ARRAY(double, SCENE_VERTEX_NORMALS);
WETCLOTH_UNIT_ARRAY(Index, SCENE_MESH_TRIANGLES);
WETCLOTH_UNIT_ARRAY(Index, SCENE_CELL_START);
WETCLOTH_UNIT_ARRAY(Index, SCENE_CELL_ITEMS);
WETCLOTH_UNIT_ARRAY(double, SCENE_GRIP_KEYS);
WETCLOTH_UNIT_ARRAY(double, SCENE_COLLIDER_KEYS);
WETCLOTH_UNIT_ARRAY(Index, SCENE_COLLIDER_KEY_NUMBERS);  // each key row's k in the scene (collider_key<k>)

// A cloth from a mesh file (native_mesh.cloth_header; CLOTH_MESH false: the nx x ny grid, every array empty).
extern const bool CLOTH_MESH;
WETCLOTH_UNIT_ARRAY(double, CLOTH_REST_POS);
WETCLOTH_UNIT_ARRAY(double, CLOTH_REST_XY);
WETCLOTH_UNIT_ARRAY(double, CLOTH_AREA);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_PAIRS);
WETCLOTH_UNIT_ARRAY(double, CLOTH_PAIR_REST);
WETCLOTH_UNIT_ARRAY(double, CLOTH_PAIR_SHAPE);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_PAIR_KIND);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_TRIANGLES);
WETCLOTH_UNIT_ARRAY(double, CLOTH_CORNER_SHARES);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_ORDER);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_RANK);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_LEVELS);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_A_START);
WETCLOTH_UNIT_ARRAY(Column, CLOTH_A_COLUMN);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_DIAGONAL);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_P_START);
WETCLOTH_UNIT_ARRAY(Column, CLOTH_P_COLUMN);
WETCLOTH_UNIT_ARRAY(double, CLOTH_P_VALUE);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_R_START);
WETCLOTH_UNIT_ARRAY(Column, CLOTH_R_COLUMN);
WETCLOTH_UNIT_ARRAY(double, CLOTH_R_VALUE);
WETCLOTH_UNIT_ARRAY(Index, CLOTH_SPRING_ENTRIES);
extern const double CLOTH_SCALARS[];  // native_mesh.CLOTH_SCALARS, in that order
extern const Index CLOTH_COUNTS[];    // native_mesh.CLOTH_COUNTS, in that order
extern const char* const CLOTH_SOURCE;

// The pins of pinned_vertices (native_mesh.pins_header; PINS false: none).
extern const bool PINS;
extern const bool PIN_BOX;
extern const double PIN_CORNERS[];  // x0, y0, z0, x1, y1, z1 (m)
WETCLOTH_UNIT_ARRAY(Index, PIN_ATTRIBUTE);
extern const char* const PIN_TEXTS[];  // the value as set, and what is allowed

// The FMI 3.0 constant array outputs: a mesh cloth's faces and UVs.
WETCLOTH_UNIT_ARRAY(Index, CONSTANT_FACES);
WETCLOTH_UNIT_ARRAY(double, CONSTANT_UV);

}  // namespace wc::fmu

#undef WETCLOTH_UNIT_ARRAY
