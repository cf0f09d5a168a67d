"""The topology of a cloth from a mesh (docs/model.md section 2.4): the spring rule, areas, the flat rest
sheet, orientation, placement and self-collision's gap, from meshes made here."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from wetcloth.mesh_file import make_mesh, mesh_area, triangle_areas
from wetcloth.scene import Scene
from wetcloth.self_collision import make_contact
from wetcloth.state import initial_state
from wetcloth.topology import (BEND, SHEAR, STRETCH, build_topology, file_grid, flat_coordinates, listed_springs,
                               triangle_edge_shapes, vertex_areas)

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "docs"))
from make_meshes import round_cloth  # noqa: E402


def grid_cells(nx: int, ny: int) -> np.ndarray:
    """The quads (i, i + 1, i + nx + 1, i + nx) of an nx x ny grid, in grid order."""
    col, row = np.tile(np.arange(nx), ny), np.repeat(np.arange(ny), nx)
    a = np.flatnonzero((col < nx - 1) & (row < ny - 1))
    return np.stack([a, a + 1, a + nx + 1, a + nx], axis=1)


def grid_points(scene: Scene) -> np.ndarray:
    """The built-in grid's rest positions (n, 3) m."""
    return build_topology(scene).rest_pos.T


def family_springs(topo) -> np.ndarray:
    """The grid's family springs as rows (first, second, rest, stiffness, damping, shape), sorted."""
    rows = []
    for f, (offset, rest) in enumerate(zip(topo.spring_offset, topo.spring_rest)):
        i = np.flatnonzero(topo.spring_stiffness[f] > 0)
        rows.append(np.column_stack([i, i + offset, np.full(len(i), rest), topo.spring_stiffness[f, i],
                                     topo.spring_damping[f, i], topo.spring_shape[f, i]]))
    rows = np.concatenate(rows)
    return rows[np.lexsort((rows[:, 1], rows[:, 0]))]


def pair_springs(springs: dict) -> np.ndarray:
    rows = np.column_stack([springs["pairs"][0], springs["pairs"][1], springs["pair_rest"],
                            springs["pair_stiffness"], springs["pair_damping"], springs["pair_shape"]])
    return rows[np.lexsort((rows[:, 1], rows[:, 0]))]


@pytest.mark.parametrize("nx, ny, width, length", [(5, 4, 0.4, 0.6), (21, 29, 0.5, 0.7), (3, 3, 1.0, 0.1)])
def test_a_quad_mesh_of_the_rectangle_gives_exactly_the_grids_springs(nx, ny, width, length):
    scene = Scene(nx=nx, ny=ny, width=width, length=length)
    grid = build_topology(scene)
    mesh = make_mesh(grid_points(scene), [grid_cells(nx, ny)])
    springs = listed_springs(mesh, scene)
    expected, got = family_springs(grid), pair_springs(springs)
    assert got.shape == expected.shape
    np.testing.assert_array_equal(got[:, :2], expected[:, :2])  # the same pairs
    # the rest lengths come from coordinates here, from dx, dy there: round-off of a few ulps
    np.testing.assert_allclose(got[:, 2:], expected[:, 2:], rtol=1e-12, atol=0)
    np.testing.assert_allclose(vertex_areas(mesh), grid.area, rtol=1e-12, atol=0)


def test_listed_springs_put_the_tension_only_ones_first():
    scene = Scene(nx=6, ny=5)
    springs = listed_springs(make_mesh(grid_points(scene), [grid_cells(6, 5)]), scene)
    kind, count = springs["pair_kind"], springs["pair_tension_count"]
    assert count == np.count_nonzero(kind != BEND) and (kind[:count] != BEND).all() and (kind[count:] == BEND).all()
    # 5 x 6 + 4 x 6 edges, two diagonals in each of 5 x 4 cells, bends 4 x 5 + 6 x 3
    assert np.bincount(kind).tolist() == [5 * 5 + 6 * 4, 2 * 5 * 4, 4 * 5 + 6 * 3]
    assert (springs["pairs"][0] < springs["pairs"][1]).all()


def test_a_quad_spreads_three_times_its_area_over_its_tension_springs():
    points, triangles = round_cloth(rings=6)
    mixed = make_mesh(np.vstack([points, [[0.9, 0.0, 0.0], [0.9, 0.2, 0.0]]]),
                      [triangles, [[len(points) - 1, len(points), len(points) + 1, _rim_neighbour(points)]]])
    springs = listed_springs(mixed, Scene())
    tension = np.arange(springs["pair_tension_count"])  # the quad's 3 edges not on a triangle and 2 diagonals
    strips = springs["pair_shape"] * springs["pair_rest"] ** 2
    quad_area = mesh_area(mixed) - mesh_area(make_mesh(points, [triangles]))
    shared = np.flatnonzero((np.sort(springs["pairs"], axis=0).T == sorted((len(points) - 1, _rim_neighbour(points))))
                            .all(axis=1))
    assert len(tension) == 5 and len(shared) == 1 and shared[0] >= len(tension)  # its edge on a triangle buckles
    assert strips[tension].sum() + 0.5 * quad_area == pytest.approx(3.0 * quad_area, rel=1e-12)


def test_a_triangles_edge_springs_stand_for_an_isotropic_membrane():
    """A triangle's three springs give, under a uniform strain e of it, the energy A sum_e x_e (n_e . e . n_e)^2 / 2
    (x_e = k_e l_e^2 / A): a fully symmetric stiffness tensor, which is isotropic for an equilateral triangle
    with equal springs, k = E A / l^2 (Poisson's ratio 1/3), the fit's exact answer there; any other triangle
    gets the nearest such tensor with k >= 0, whatever its size and place (the shape is scale-free)."""
    rng = np.random.default_rng(3)
    turn = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    equilateral = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, math.sqrt(3) / 2, 0.0]])
    np.testing.assert_allclose(triangle_edge_shapes(0.03 * equilateral @ turn + 1.0, np.array([[0, 1, 2]])),
                               np.full((1, 3), math.sqrt(3) / 4), rtol=1e-12)
    triangle = rng.uniform(size=(3, 3))
    shapes = triangle_edge_shapes(triangle, np.array([[0, 1, 2]]))
    assert (shapes >= 0.0).all()
    np.testing.assert_allclose(triangle_edge_shapes(0.1 * triangle @ turn - 2.0, np.array([[0, 1, 2]])), shapes,
                               rtol=1e-10)
    # a mesh of triangles lists its edges after the tension-only springs (none here), then its bending springs
    points, triangles = round_cloth(rings=6)
    springs = listed_springs(make_mesh(points, [triangles]), Scene())
    kind, buckling = springs["pair_kind"], springs["pair_buckling_count"]
    assert springs["pair_tension_count"] == 0 and (kind[:buckling] == STRETCH).all() and (kind[buckling:] == BEND).all()


def _rim_neighbour(points: np.ndarray) -> int:
    """The rim vertex of the disc next after the last one (a quad hangs on their rim edge)."""
    rim = np.flatnonzero(np.isclose(np.hypot(points[:, 0], points[:, 1]), np.hypot(*points[-1, :2])))
    angle = np.arctan2(points[rim, 1], points[rim, 0])
    last = math.atan2(points[-1, 1], points[-1, 0])
    ahead = np.mod(angle - last, 2 * math.pi)
    ahead[rim == len(points) - 1] = np.inf
    return int(rim[np.argmin(ahead)])


def test_a_triangle_mesh_bends_across_each_interior_edge():
    points, triangles = round_cloth(rings=5)
    mesh = make_mesh(points, [triangles])
    springs = listed_springs(mesh, Scene())
    edges, counts = np.unique(np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]],
                                                      triangles[:, [2, 0]]]), axis=1), axis=0, return_counts=True)
    kind = springs["pair_kind"]
    assert np.count_nonzero(kind == STRETCH) == len(edges)
    assert np.count_nonzero(kind == SHEAR) == 0
    assert np.count_nonzero(kind == BEND) == np.count_nonzero(counts == 2)
    # a bending spring's strip is its two triangles' area: over all of them, each triangle counted once
    # per interior edge it has
    bend = kind == BEND
    strips = springs["pair_shape"][bend] * springs["pair_rest"][bend] ** 2
    area = triangle_areas(points, triangles)
    interior = {tuple(e) for e in edges[counts == 2]}
    per_triangle = [sum(tuple(sorted((t[k], t[(k + 1) % 3]))) in interior for k in range(3)) for t in triangles]
    assert strips.sum() == pytest.approx(float(area @ np.array(per_triangle)), rel=1e-12)
    assert listed_springs(mesh, Scene(bend_stiffness=0.0))["pair_kind"].max() == STRETCH


def test_vertex_areas_sum_to_the_mesh_area():
    points, triangles = round_cloth(rings=8)
    mesh = make_mesh(points, [triangles])
    assert vertex_areas(mesh).sum() == pytest.approx(mesh_area(mesh), rel=1e-12)
    # the disc of radius R with its rim on the circle: the inscribed polygons' area, a little below pi R^2
    assert mesh_area(mesh) == pytest.approx(math.pi * 0.7**2, rel=2 * (1 - math.sin(2 * math.pi / 50) / (2 * math.pi / 50)))


def test_the_rest_sheet_of_a_flat_mesh_keeps_its_x_and_y_and_of_a_tilted_one_its_distances():
    points, triangles = round_cloth(rings=6)
    points = points + [0.3, -0.2, 0.0]
    area = vertex_areas(make_mesh(points, [triangles]))
    flat = flat_coordinates(points, area, triangles)
    centre = area @ points / area.sum()
    np.testing.assert_allclose(flat.T, points[:, :2] - centre[:2], atol=1e-14)
    turn = math.radians(35.0)
    tilted = points @ np.array([[1, 0, 0], [0, math.cos(turn), math.sin(turn)], [0, -math.sin(turn), math.cos(turn)]])
    sheet = flat_coordinates(tilted, area, triangles)
    pairs = np.array([[0, 5], [3, 40], [10, 70]])
    for a, b in pairs:
        assert np.hypot(*(sheet[:, a] - sheet[:, b])) == pytest.approx(np.linalg.norm(points[a] - points[b]), rel=1e-12)


def test_triangles_are_oriented_consistently():
    points, triangles = round_cloth(rings=4)
    turned = triangles.copy()
    turned[1::3] = turned[1::3][:, [0, 2, 1]]
    mesh = make_mesh(points, [turned])
    p = points[mesh.triangles]
    normal_z = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])[:, 2]
    assert (normal_z > 0).all()  # all as the first one, which the generator made counter-clockwise


def test_a_file_that_forms_the_grid_gets_the_grids_topology_and_its_own_faces(tmp_path):
    import meshio

    scene = Scene(nx=7, ny=5, width=0.6, length=0.4)
    grid = build_topology(scene)
    path = tmp_path / "grid.obj"
    cells = grid_cells(7, 5)[:, [0, 3, 2, 1]]  # the other way round: the same cells
    meshio.write(path, meshio.Mesh(grid.rest_pos.T + [0.0, 0.0, 0.25], [("quad", cells)]))
    from_file = build_topology(scene.replace(cloth_mesh=str(path), nx=2, ny=2, width=9.0))
    assert file_grid(make_mesh(grid.rest_pos.T, [cells])) == (7, 5, pytest.approx(0.6), pytest.approx(0.4))
    assert from_file.spring_family_names == grid.spring_family_names and from_file.pairs.shape == (2, 0)
    np.testing.assert_allclose(from_file.spring_stiffness, grid.spring_stiffness, rtol=1e-12)
    np.testing.assert_array_equal(from_file.triangles, grid.triangles)
    np.testing.assert_array_equal(from_file.mesh.faces, cells)
    np.testing.assert_allclose(from_file.rest_pos[2], 0.25)
    assert not from_file.is_grid and grid.is_grid
    irregular = grid.rest_pos.T.copy()
    irregular[8, 0] += 1e-3
    assert file_grid(make_mesh(irregular, [cells])) is None


def test_a_placed_mesh_starts_as_the_built_in_grid(tmp_path):
    import meshio

    scene = Scene(nx=9, ny=11, initial_tilt=25.0, initial_height=0.3)
    grid = build_topology(scene)
    path = tmp_path / "grid.ply"
    meshio.write(path, meshio.Mesh(grid.rest_pos.T, [("quad", grid_cells(9, 11).astype(np.int32))]))
    placed = scene.replace(cloth_mesh=str(path), place_mesh="on")
    np.testing.assert_allclose(initial_state(placed, build_topology(placed)).pos, initial_state(scene, grid).pos,
                               rtol=0, atol=1e-15)
    as_is = initial_state(scene.replace(cloth_mesh=str(path)), build_topology(placed)).pos
    np.testing.assert_array_equal(as_is, grid.rest_pos)


def test_placing_a_mesh_turns_it_about_its_centroid_and_raises_the_centroid(tmp_path):
    points, triangles = round_cloth(rings=6)
    points = points + [0.1, 0.2, 0.5]
    path = tmp_path / "disc.obj"
    import meshio

    meshio.write(path, meshio.Mesh(points, [("triangle", triangles)]))
    scene = Scene(cloth_mesh=str(path), place_mesh="on", initial_tilt=40.0, initial_height=1.5)
    topo = build_topology(scene)
    pos = initial_state(scene, topo).pos
    centre = pos @ topo.area / topo.area.sum()
    rest_centre = topo.rest_pos @ topo.area / topo.area.sum()
    np.testing.assert_allclose(centre, [rest_centre[0], rest_centre[1], 1.5], atol=1e-14)
    first, second = topo.pairs  # a rigid motion: every spring at its rest length
    np.testing.assert_allclose(np.linalg.norm(pos[:, first] - pos[:, second], axis=0), topo.pair_rest, rtol=1e-12)
    normal = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])  # the sheet's plane turned by 40 degrees
    assert abs(normal[0]) < 1e-12 and math.degrees(math.atan2(abs(normal[1]), abs(normal[2]))) == pytest.approx(40.0)


def test_self_collision_gap_of_a_mesh_is_its_smallest_triangle_altitude():
    points, triangles = round_cloth(rings=6)
    mesh = make_mesh(points, [triangles])
    from wetcloth.topology import MeshFaces, _mesh

    topo = _mesh(Scene(), mesh, MeshFaces(mesh.faces, None, "disc"))
    contact = make_contact(topo, True, 0.4)
    p = points[triangles]
    altitudes = [2 * triangle_areas(points, triangles) / np.linalg.norm(p[:, (k + 1) % 3] - p[:, k], axis=1)
                 for k in range(3)]
    assert contact.rest_gap == pytest.approx(np.min(altitudes), rel=1e-12)
    assert contact.least_margin == pytest.approx(0.05 * contact.rest_gap, rel=1e-15)
    grid = build_topology(Scene())
    assert make_contact(grid, True, 0.4).rest_gap == pytest.approx(grid.dx * grid.dy / math.hypot(grid.dx, grid.dy))


def test_per_particle_pair_sum_adds_onto_both_ends():
    points, triangles = round_cloth(rings=4)
    mesh = make_mesh(points, [triangles])
    from wetcloth.topology import MeshFaces, _mesh

    topo = _mesh(Scene(), mesh, MeshFaces(mesh.faces, None, "disc"))
    values = np.arange(topo.pairs.shape[1], dtype=float)
    expected = np.zeros(topo.n)
    for (a, b), v, kind in zip(topo.pairs.T, values, topo.pair_kind):
        if kind == STRETCH:
            expected[a] += v
            expected[b] += v
    np.testing.assert_array_equal(topo.per_particle_pair_sum(values, kinds=[STRETCH]), expected)
    assert topo.spring_count == topo.pairs.shape[1] and topo.nx == topo.n and topo.ny == 1
    assert topo.spring_stiffness.shape == (0, topo.n)
