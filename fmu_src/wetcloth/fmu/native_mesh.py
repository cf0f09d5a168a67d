"""A scene's cloth from a mesh file, built into the native unit (``native.py``): what depends on the file alone,
computed here once by the Python front end and written into the unit's generated source as arrays, which
the core's ``ClothMesh`` (``model.hpp``, ``cloth_mesh.cpp``) turns, with the unit's parameter values, into
the arrays ``wetcloth.Simulation`` hands the core.

From the file alone: the particles' rest positions, flat rest sheet and areas (``topology._mesh``), the
listed springs' ends, rest lengths, kinds and shapes (``listed_springs``), the triangles and their corners'
shares, the area-weighted centroid that ``place_mesh`` turns about, self-collision's gaps
(``self_collision.make_contact``) and the preconditioner's structure (``preconditioner.make_mesh_plane``: the band order of its coarsest level and
the algebraic multigrid hierarchy's patterns and prolongators, pyamg's).  From the parameters, in C++:
spring constants (``stretch_stiffness``, ``bend_stiffness``, ``bend_rigidity``, ``damping`` times the shapes), masses and
wicking (``areal_density``, ...) and the start (``place_mesh``, ``initial_height``, ``initial_tilt``).

The pins of ``pinned_vertices`` (``pins_source``), on a mesh or the built-in grid: a point attribute's
vertices, or a box, whose particles the core finds at the start positions.

What the structure fixes (``fixed_ranges``): ``bend_stiffness`` 0 or not (the bending springs are listed or
not), ``bend_rigidity`` 0 or not (the hinges' terms are listed or not), on a mesh with an algebraic hierarchy
(more than ``ALGEBRAIC_SIZE`` vertices) ``stretch_stiffness`` (pyamg's aggregation weighs the springs by it),
and on the built-in grid bent by hinges (its quads' springs listed) ``nx``, ``ny``, ``width`` and ``length``;
the unit refuses another value with an error naming it.
"""

from __future__ import annotations

import numpy as np

from wetcloth.topology import HINGE

#: The ClothMesh arrays in the generated source: C++ name, element type, key of ``cloth_arrays``.
CLOTH_ARRAYS = (
    ("CLOTH_REST_POS", "double", "rest_pos"), ("CLOTH_REST_XY", "double", "rest_xy"), ("CLOTH_AREA", "double", "area"),
    ("CLOTH_PAIRS", "Index", "pairs"), ("CLOTH_PAIR_REST", "double", "pair_rest"),
    ("CLOTH_PAIR_SHAPE", "double", "pair_shape"), ("CLOTH_PAIR_KIND", "Index", "pair_kind"),
    ("CLOTH_TRIANGLES", "Index", "triangles"), ("CLOTH_CORNER_SHARES", "double", "corner_shares"),
    ("CLOTH_ORDER", "Index", "order"), ("CLOTH_RANK", "Index", "rank"),
    ("CLOTH_LEVELS", "Index", "levels"), ("CLOTH_A_START", "Index", "a_start"),
    ("CLOTH_A_COLUMN", "Column", "a_column"), ("CLOTH_DIAGONAL", "Index", "diagonal"),
    ("CLOTH_P_START", "Index", "p_start"), ("CLOTH_P_COLUMN", "Column", "p_column"),
    ("CLOTH_P_VALUE", "double", "p_value"), ("CLOTH_R_START", "Index", "r_start"),
    ("CLOTH_R_COLUMN", "Column", "r_column"), ("CLOTH_R_VALUE", "double", "r_value"),
    ("CLOTH_SPRING_ENTRIES", "Index", "spring_entries"),
)
#: The ClothMesh numbers, in the order of the generated source's CLOTH_SCALARS and CLOTH_COUNTS (unit.cpp reads
#: them so).
CLOTH_SCALARS = ("centre_x", "centre_y", "centre_z", "size", "rest_gap", "typical_gap", "least_margin",
                 "hierarchy_stretch_stiffness", "grid_width", "grid_length")
CLOTH_COUNTS = ("n", "pair_tension_count", "kd", "marker_size", "bends", "grid_nx", "grid_ny", "pair_buckling_count",
                "hinged_grid")


#: Why a native unit of the built-in grid built without hinges takes no ``bend_rigidity`` (model.cpp's
#: grid_rigidity_problem says the same).
GRID_RIGIDITY = ("0 N m in this native unit of the built-in grid, built without hinges (it bends by its springs, "
                 "bend_stiffness); for hinges build it from a scene with bend_rigidity > 0 (wetcloth build-fmu --native "
                 "--scene)")


def cloth_arrays(scene) -> dict | None:
    """The ClothMesh of ``scene`` (a ``wetcloth.Scene`` whose cloth comes from a mesh file) as arrays and
    numbers (keys of CLOTH_ARRAYS, CLOTH_SCALARS, CLOTH_COUNTS, and the file's name ``source``); None for the
    built-in grid.  A file whose vertices form the built-in grid (``topology.file_grid``) runs with the grid's
    springs, as in Python: it carries only its start (rest_pos and the centroid) and the grid's numbers.  The
    built-in grid with ``bend_rigidity`` lists its springs and hinges (``topology._hinged_grid``), as a mesh
    would, with ``hinged_grid`` and the grid's numbers: the unit starts and pins it as the grid."""
    from wetcloth.mesh_file import is_mesh
    from wetcloth.preconditioner import plane_for
    from wetcloth.self_collision import make_contact
    from wetcloth.topology import build_topology, corner_shares

    if not is_mesh(scene.cloth_mesh) and scene.bend_rigidity == 0.0:
        return None
    topo = build_topology(scene)
    if not topo.listed:
        return _grid_file_arrays(scene, topo)
    plane = plane_for(topo, fixed_steps=scene.tolerance == 0.0)
    contact = make_contact(topo, True, 0.0)
    h = plane.algebraic
    centre = topo.rest_pos @ topo.area / topo.area.sum()  # topology.placed's
    arrays = dict(
        rest_pos=topo.rest_pos, rest_xy=topo.rest_xy, area=topo.area, pairs=topo.pairs, pair_rest=topo.pair_rest,
        pair_shape=topo.pair_shape, pair_kind=topo.pair_kind, triangles=topo.triangles,
        corner_shares=corner_shares(topo.rest_pos, topo.triangles),
        order=plane.order, rank=plane.rank, levels=h.levels, a_start=h.a_start, a_column=h.a_column,
        diagonal=h.diagonal, p_start=h.p_start, p_column=h.p_column, p_value=h.p_value, r_start=h.r_start,
        r_column=h.r_column, r_value=h.r_value, spring_entries=h.spring_entries,
    )
    arrays.update(centre_x=centre[0], centre_y=centre[1], centre_z=centre[2], size=topo.size,
                  rest_gap=contact.rest_gap, typical_gap=contact.typical_gap, least_margin=contact.least_margin,
                  hierarchy_stretch_stiffness=scene.stretch_stiffness)
    arrays.update(n=topo.n, pair_tension_count=topo.pair_tension_count, pair_buckling_count=topo.pair_buckling_count,
                  kd=plane.bands.shape[2] - 1,
                  marker_size=len(h.marker), bends=int(scene.bend_stiffness != 0.0 and scene.bend_rigidity == 0.0),
                  source=str(topo.mesh.source) if topo.mesh is not None else "the nx x ny rectangle",
                  grid_width=0.0, grid_length=0.0, grid_nx=0, grid_ny=0, hinged_grid=int(topo.mesh is None))
    if topo.mesh is None:  # the built-in grid: what its listed springs were built for
        arrays.update(grid_width=scene.width, grid_length=scene.length, grid_nx=scene.nx, grid_ny=scene.ny)
    return arrays


def _grid_file_arrays(scene, topo) -> dict:
    """``cloth_arrays`` of a file that forms the built-in grid (``topo``: its topology, the grid's): the file's
    coordinates and the centroid ``topology.placed`` turns them about (by the grid's areas, as Python's
    start), the grid's nx, ny, width and length; every other array empty."""
    from wetcloth.mesh_file import read_mesh_file
    from wetcloth.topology import file_grid

    nx, ny, width, length = file_grid(read_mesh_file(scene.cloth_mesh))
    arrays = {key: np.zeros(0) for _, _, key in CLOTH_ARRAYS}
    centre = topo.rest_pos @ topo.area / topo.area.sum()  # topology.placed's
    arrays.update(rest_pos=topo.rest_pos, centre_x=centre[0], centre_y=centre[1], centre_z=centre[2], size=topo.size,
                  rest_gap=0.0, typical_gap=0.0, least_margin=0.0, hierarchy_stretch_stiffness=0.0,
                  grid_width=width, grid_length=length, n=topo.n, pair_tension_count=0, pair_buckling_count=0, kd=0, marker_size=0, bends=0,
                  grid_nx=nx, grid_ny=ny, hinged_grid=0, source=str(topo.mesh.source))
    return arrays


def pins_source(scene, c_array, c_double, c_string) -> str:
    """The generated source's Pins (model.hpp) of ``scene``'s pinned_vertices (a ``wetcloth.Scene``, or None):
    ``PINS`` (false: none), the box (``PIN_BOX``, ``PIN_CORNERS``), a point attribute's pins (``PIN_ATTRIBUTE``)
    and the texts of the messages."""
    from wetcloth.mesh_file import read_mesh_file
    from wetcloth.scene import PINS_ALLOWED
    from wetcloth.topology import _attribute

    spec = "" if scene is None else scene.pinned_vertices.strip()
    box = spec.startswith("box:")
    corners = [float(v) for v in spec[4:].split(",")] if box else [0.0] * 6
    attribute = (_attribute(spec, read_mesh_file(scene.cloth_mesh)).astype(np.int64) if spec and not box
                 else np.zeros(0, dtype=np.int64))
    return "\n".join([
        f"extern const bool PINS = {'true' if spec else 'false'};",
        f"extern const bool PIN_BOX = {'true' if box else 'false'};",
        f"extern const double PIN_CORNERS[] = {{{', '.join(c_double(v) for v in corners)}}};",
        c_array("PIN_ATTRIBUTE", "Index", attribute),
        f"extern const char* const PIN_TEXTS[] = {{{c_string(repr(spec))}, {c_string(PINS_ALLOWED)}}};"])


def hierarchy_levels(arrays: dict | None) -> int:
    """Levels of the algebraic hierarchy of ``cloth_arrays`` (1: the band factors alone; 0: a grid)."""
    return 0 if arrays is None else len(np.asarray(arrays["levels"]).reshape(-1, 5))


def fixed_ranges(arrays: dict | None) -> dict[str, tuple[float, float, bool, str]]:
    """The parameters the built-in mesh fixes: name -> (lo, hi, lo_open, range text) of the values the unit
    takes (ClothMesh::fixed_problem gives the same verdicts)."""
    if arrays is None or (arrays["grid_nx"] and not arrays["hinged_grid"]):  # the grid's families: no hinges
        return {"bend_rigidity": (0.0, 0.0, False, GRID_RIGIDITY)}
    rebuild = "; rebuild the unit (wetcloth build-fmu --native --scene) for another"
    ranges = {}
    if arrays["hinged_grid"]:  # (ClothMesh::fixed_problem's texts)
        count = f"{arrays['grid_nx']} x {arrays['grid_ny']} particles"
        size = f"{arrays['grid_width']!r} x {arrays['grid_length']!r} m"
        for name, unit, what in (("nx", "", count), ("ny", "", count), ("width", " m", size), ("length", " m", size)):
            value = arrays[f"grid_{name}"]
            ranges[name] = (value, value, False, f"{value!r}{unit} (the hinges of this unit's grid were built for "
                                                 f"{what}{rebuild})")
    hinged = np.any(np.asarray(arrays["pair_kind"]) == HINGE)  # (then every face bends by hinges: any bend_stiffness)
    if arrays["bends"]:
        ranges["bend_stiffness"] = (0.0, 1e8, True, "0 < bend_stiffness <= 1e+08 N/m (this unit's mesh has bending "
                                                    f"springs, built in with bend_stiffness > 0{rebuild})")
    elif not hinged:
        ranges["bend_stiffness"] = (0.0, 0.0, False, f"0 N/m (this unit's mesh has no bending springs{rebuild})")
    if hinged:
        ranges["bend_rigidity"] = (0.0, 100.0, True, "0 < bend_rigidity <= 100 N m (this unit's mesh has hinges, built "
                                                     f"in with bend_rigidity > 0{rebuild})")
    else:
        ranges["bend_rigidity"] = (0.0, 0.0, False, f"0 N m (this unit's mesh has no hinges{rebuild})")
    if hierarchy_levels(arrays) > 1:
        k = float(arrays["hierarchy_stretch_stiffness"])
        ranges["stretch_stiffness"] = (k, k, False, f"{k:g} N/m (the algebraic multigrid hierarchy of this unit's "
                                                    f"mesh of {arrays['n']} vertices was built for it{rebuild})")
    return ranges


def cloth_source(arrays: dict | None, c_array, c_double, c_string) -> str:
    """The generated source's ClothMesh arrays (each ``NAME[]`` with a trailing 0 and ``NAME_SIZE``), numbers
    and texts, and ``CLOTH_MESH`` (false, every array empty, for the built-in grid).  ``c_array``,
    ``c_double``, ``c_string``: native.py's literal writers."""
    lines = [f"extern const bool CLOTH_MESH = {'true' if arrays is not None else 'false'};"]
    lines += [c_array(name, kind, np.zeros(0) if arrays is None else arrays[key]) for name, kind, key in CLOTH_ARRAYS]
    scalars = ", ".join(c_double(0.0 if arrays is None else arrays[k]) for k in CLOTH_SCALARS)
    counts = ", ".join(str(0 if arrays is None else int(arrays[k])) for k in CLOTH_COUNTS)
    source = c_string("" if arrays is None else arrays["source"])
    lines += [f"extern const double CLOTH_SCALARS[] = {{{scalars}}};  // {', '.join(CLOTH_SCALARS)}",
              f"extern const Index CLOTH_COUNTS[] = {{{counts}}};  // {', '.join(CLOTH_COUNTS)}",
              f"extern const char* const CLOTH_SOURCE = {source};"]
    return "\n".join(lines)
