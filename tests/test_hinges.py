"""A mesh of triangles, quads or both bent by hinges of rigidity ``bend_rigidity`` (docs/model.md section 2.4): a
plate's bending that converges with refinement, run by the core as linear springs of rest length 0 with the damping
of a Kelvin-Voigt fabric, and refused where it cannot apply."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import spsolve

import wetcloth
from wetcloth.errors import ParameterError
from wetcloth.model import Model
from wetcloth.topology import HINGE, build_topology

RIGIDITY = 0.5  # N m: a 20 cm cantilever of the default fabric then sags about 2 mm (w / L ~ 1 %: linear)
LENGTH = 0.2  # m, the cantilever's free length
GRAVITY = 9.81  # m/s2
HEIGHT = 0.5  # m, the strip's height in its file


def strip_file(tmp_path, columns: int, width: float = LENGTH, clamp: int = 2):
    """A strip of equilateral triangles in a PLY file: ``columns`` + 1 columns of vertices over x in [0, LENGTH]
    (and ``clamp`` more at x < 0, to pin), alternate columns shifted half a spacing along y, about ``width`` wide."""
    sx = LENGTH / columns
    hy = 2.0 * sx / math.sqrt(3.0)
    rows = round(width / hy) + 1
    index = {}
    points = []
    for c in range(-clamp, columns + 1):
        for r in range(rows):
            index[c, r] = len(points)
            points.append([c * sx, r * hy + (0.5 * hy if c % 2 else 0.0) - 0.5 * width, HEIGHT])
    faces = []
    for c in range(-clamp, columns):
        for r in range(rows - 1):
            a, b, d, e = index[c, r], index[c, r + 1], index[c + 1, r], index[c + 1, r + 1]
            faces += [[a, d, b], [b, d, e]] if c % 2 == 0 else [[a, d, e], [a, e, b]]
    path = tmp_path / f"strip{columns}.ply"
    trimesh.Trimesh(np.array(points), faces, process=False).export(path)
    return path


def quad_file(tmp_path, columns: int, rows: int, width: float = LENGTH, jitter: float = 0.0, clamp: int = 2,
              triangles: int = 0):
    """A strip of quads in an OBJ file: ``columns`` + 1 columns of vertices over x in [0, LENGTH] (and ``clamp`` more
    at x < 0, to pin), ``rows`` + 1 rows over y in [-width / 2, width / 2]; the vertices off the strip's border
    moved by up to ``jitter`` of the spacings (seeded), the first ``triangles`` cells split into two triangles."""
    sx, sy = LENGTH / columns, width / rows
    shift = np.random.default_rng(7).uniform(-jitter, jitter, (columns + clamp + 1, rows + 1, 2))
    lines, faces = [], []
    for r in range(rows + 1):  # (x fastest, as the built-in grid)
        for c in range(-clamp, columns + 1):
            inside = -clamp < c < columns and 0 < r < rows
            dx, dy = (float(d) for d in shift[c + clamp, r] * (sx, sy)) if inside else (0.0, 0.0)
            lines.append(f"v {c * sx + dx!r} {r * sy - 0.5 * width + dy!r} {HEIGHT!r}")
    across = columns + clamp + 1
    for r in range(rows):
        for c in range(columns + clamp):
            a, b, d, e = (1 + r * across + c + k for k in (0, 1, across + 1, across))
            faces += [f"f {a} {b} {d}", f"f {a} {d} {e}"] if len(faces) < 2 * triangles else [f"f {a} {b} {d} {e}"]
    path = tmp_path / f"quads{columns}x{rows}_{jitter}_{triangles}.obj"
    path.write_text("\n".join(lines + faces) + "\n")
    return path


def cantilever(tmp_path, columns: int, mesh=None, **settings) -> wetcloth.Scene:
    """The strip (``mesh``, a file; default the equilateral ``strip_file``) clamped along x <= 0 (its vertices there
    pinned), in air without drag, far above floor and water."""
    mesh = strip_file(tmp_path, columns) if mesh is None else mesh
    fields = dict(cloth_mesh=str(mesh), bend_rigidity=RIGIDITY, air_density=0.0,
                  pinned_vertices="box:-1,-1,0,1e-9,1,1", water_level=-0.5, self_collision="off")
    return wetcloth.Scene(**(fields | settings))


def hinge_matrix(topo) -> coo_matrix:
    """The hinges' stiffness matrix (n, n) N/m from their springs of rest length 0 (one per coordinate)."""
    hinge = topo.pair_kind == HINGE
    (i, j), k = topo.pairs[:, hinge], topo.pair_stiffness[hinge]
    return coo_matrix((np.concatenate([k, k, -k, -k]), (np.concatenate([i, j, i, j]), np.concatenate([i, j, j, i]))),
                      shape=(topo.n, topo.n)).tocsr()


def static_sag(topo, load: np.ndarray) -> np.ndarray:
    """The hinges' linear static deflection (n,) m of the unpinned particles under a vertical ``load`` (n,) N."""
    free = ~topo.pinned
    sag = np.zeros(topo.n)
    sag[free] = spsolve(hinge_matrix(topo)[free][:, free].tocsc(), load[free])
    return sag


def tip_sag_errors(tmp_path, meshes) -> list[float]:
    """The relative errors of the hinges' linear static sag at the tip of the clamped strips ``meshes`` (files),
    loaded by their weight, against the plate's q L^4 / (8 D) (Euler-Bernoulli, per unit width; inextensible, so
    no anticlastic bend)."""
    analytic = wetcloth.Scene().areal_density * GRAVITY * LENGTH**4 / (8.0 * RIGIDITY)
    errors = []
    for mesh in meshes:
        topo = build_topology(cantilever(tmp_path, 0, mesh))
        sag = static_sag(topo, -wetcloth.Scene().areal_density * GRAVITY * topo.area)
        tip = np.isclose(topo.rest_pos[0], LENGTH)
        errors.append(abs(-sag[tip].mean() / analytic - 1.0))
    return errors


def test_a_cantilever_plate_sags_as_its_rigidity_says_ever_closer_with_refinement(tmp_path):
    """A plate of rigidity D clamped along one edge and loaded by its weight sags at its tip as q L^4 / (8 D).
    The hinges' linear static solution comes closer at each halving of the triangles, first order in their size
    (the free edges' half cells carry load but no hinge: 26 %, 15 %, 9 % at 10, 20, 40 columns), where bending
    springs would stiffen as h^-4 (docs/model.md section 2.4)."""
    errors = tip_sag_errors(tmp_path, [strip_file(tmp_path, columns) for columns in (10, 20, 40)])
    assert errors[1] < 0.7 * errors[0] and errors[2] < 0.7 * errors[1], errors
    assert errors[2] < 0.1, errors


@pytest.mark.parametrize("jitter", [0.0, 0.1])
def test_a_cantilever_of_quads_sags_as_its_rigidity_says_ever_closer_with_refinement(tmp_path, jitter):
    """The same plate as a strip of square quads, regular or each inner vertex moved by up to a tenth of the
    spacing: first order again (regular 21 %, 10 %, 5.1 % at 10, 20, 40 columns; moved 20 %, 8.8 %, 3.5 %)."""
    errors = tip_sag_errors(tmp_path, [quad_file(tmp_path, columns, columns, jitter=jitter) for columns in (10, 20, 40)])
    assert errors[1] < 0.7 * errors[0] and errors[2] < 0.7 * errors[1], errors
    assert errors[2] < 0.06, errors


def test_quads_store_a_plates_bending_whichever_way_they_bend(tmp_path):
    """On a grid of rectangular quads (dx != dy) bent to z = x^T H x / 2, the hinges store a plate's D |H|^2 / 2 per
    area (Poisson's ratio 0) for bends along x, y, a diagonal, and twist alike, but for the strips of half a cell
    along the border that no hinge across x (or y) covers: D / 2 (H_xx^2 (1 - 1/N_x) + H_yy^2 (1 - 1/N_y)
    + 2 H_xy^2) W L, to round-off (every term is exact for a quadratic on rectangles)."""
    columns, rows, width = 12, 7, 0.13
    topo = build_topology(cantilever(tmp_path, 0, quad_file(tmp_path, columns, rows, width=width, clamp=0),
                                     pinned_vertices=""))
    stiffness = hinge_matrix(topo)
    x, y = topo.rest_pos[0], topo.rest_pos[1]
    for angle in (0.0, 30.0, 45.0, 90.0, 120.0, None):
        if angle is None:
            hessian = np.array([[0.0, 1.0], [1.0, 0.0]])  # twist
        else:
            n = np.array([math.cos(math.radians(angle)), math.sin(math.radians(angle))])
            hessian = np.outer(n, n)
        z = 0.5 * (hessian[0, 0] * x * x + 2.0 * hessian[0, 1] * x * y + hessian[1, 1] * y * y)
        stored = 0.5 * z @ (stiffness @ z)
        plate = 0.5 * RIGIDITY * LENGTH * width * (hessian[0, 0] ** 2 * (1.0 - 1.0 / columns)
                                                   + hessian[1, 1] ** 2 * (1.0 - 1.0 / rows) + 2.0 * hessian[0, 1] ** 2)
        assert stored == pytest.approx(plate, rel=1e-9), angle


def test_hinges_hold_a_flat_or_rigidly_moved_sheet_with_no_force_and_damp_bending_by_their_matrix(tmp_path):
    """The core's forces on the flat strip, turned and moved as a whole, are its weight alone (the hinges store
    nothing there); a velocity across the flat sheet adds the damping -(damping / stretch_stiffness) K v of a
    Kelvin-Voigt fabric, K the hinges' (positive semidefinite) matrix, so bending motion only loses energy;
    round-off bounds, scaled by the hinges' stiffest term."""
    scene = cantilever(tmp_path, 10, pinned_vertices="")
    topo = build_topology(scene)
    model = Model(scene)
    turn = np.array([[math.cos(0.3), -math.sin(0.3), 0.0], [math.sin(0.3), math.cos(0.3), 0.0], [0.0, 0.0, 1.0]])
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(0.7), -math.sin(0.7)], [0.0, math.sin(0.7), math.cos(0.7)]])
    pos = tilt @ turn @ topo.rest_pos + np.array([[0.1], [-0.2], [0.3]])
    water = np.zeros(topo.n)
    still = model.forces(pos, np.zeros_like(pos), water).copy()
    weight = model.cloth.dry_mass * GRAVITY
    scale = np.abs(topo.pair_stiffness[topo.pair_kind == HINGE]).max() * LENGTH
    assert np.abs(still[:2]).max() < 1e-12 * scale and np.abs(still[2] + weight).max() < 1e-12 * scale
    vel = np.zeros_like(pos)
    vel[2] = np.random.default_rng(3).normal(size=topo.n)
    flat = model.forces(topo.rest_pos, np.zeros_like(pos), water).copy()
    damped = model.forces(topo.rest_pos, vel, water).copy() - flat
    expected = -(scene.damping / scene.stretch_stiffness) * (hinge_matrix(topo) @ vel[2])
    assert np.abs(damped[2] - expected).max() < 1e-12 * scale * np.abs(vel).max()
    assert vel[2] @ damped[2] < 0.0


def test_the_core_rests_the_cantilever_on_its_hinges_static_solution(tmp_path):
    """Run to rest (implicit Euler at 1 ms, the fabric's bending damped with a 10 ms time constant), the
    core's strip hangs where the hinges' linear statics put it, within the geometric nonlinearity ((w / L)^2
    ~ 1e-4 of the sag) and the membrane's stretch (q L / stretch_stiffness ~ 1e-4 m: nearly inextensible)."""
    scene = cantilever(tmp_path, 10, damping=20.0, integrator="implicit_euler", tolerance=0.0, max_step=1e-3)
    sim = wetcloth.Simulation(scene)
    sim.advance(0.5)
    topo = sim.model.topology
    sag = static_sag(topo, -sim.model.cloth.dry_mass * GRAVITY)
    assert np.abs(sim.positions[:, 2] - HEIGHT - sag).max() < 2e-3 * np.abs(sag).max()


def test_bend_rigidity_is_refused_where_no_hinge_can_carry_it(tmp_path):
    """A mesh whose faces share no edge has nowhere to bend: bend_rigidity > 0 there is a ParameterError naming
    it and what is allowed."""
    apart = tmp_path / "apart.obj"
    apart.write_text("v 0 0 1\nv 0.1 0 1\nv 0.1 0.1 1\nv 0 0.1 1\nv 0.2 0.1 1\nv 0.2 0.2 1\nf 1 2 3 4\nf 3 5 6\n")
    with pytest.raises(ParameterError, match="bend_rigidity.*has none; allowed: 0 N m"):
        build_topology(wetcloth.Scene(cloth_mesh=str(apart), bend_rigidity=1e-4))


def test_the_built_in_grid_bends_by_hinges_as_a_mesh_file_of_it_does(tmp_path):
    """With bend_rigidity the built-in rectangle lists the springs and hinges of a mesh file of its quads: the same
    springs, areas and pins as that file (its points the grid's, placed at the same height), so the same motion
    bit for bit; it pins and exports as the grid (pinned_edge, no mesh faces)."""
    import meshio

    nx, ny, width, length = 9, 7, 0.4, 0.3
    grid = wetcloth.load_scene(nx=nx, ny=ny, width=width, length=length, bend_rigidity=2e-5, pinned_edge="y_max",
                               initial_tilt=0.0, initial_height=0.5)
    topo = build_topology(grid)
    assert topo.listed and topo.hinge_count > 0 and topo.mesh is None and topo.pinned.sum() == nx
    row = np.repeat(np.arange(ny), nx)
    points = topo.rest_pos.T  # (the grid's own arithmetic)
    cells = np.array([[r * nx + c, r * nx + c + 1, (r + 1) * nx + c + 1, (r + 1) * nx + c]
                      for r in range(ny - 1) for c in range(nx - 1)], dtype=np.int32)
    meshio.write(tmp_path / "rectangle.ply", meshio.Mesh(points, [("quad", cells)],
                                                        point_data={"held": (row == ny - 1).astype(np.float64)}))
    fromfile = grid.replace(cloth_mesh=str(tmp_path / "rectangle.ply"), place_mesh="on", pinned_edge="none",
                            pinned_vertices="held")
    listed = build_topology(fromfile)
    for field in ("pairs", "pair_shape", "pair_kind", "area", "triangles", "pinned"):
        np.testing.assert_array_equal(getattr(listed, field), getattr(topo, field), field)
    runs = []
    for scene in (grid, fromfile):
        sim = wetcloth.Simulation(scene)
        sim.advance(0.3)
        runs.append(sim.positions)
    np.testing.assert_array_equal(runs[0], runs[1])
    assert np.ptp(runs[0][:, 2]) > 0.01  # it hangs from its pinned edge and bends


def test_every_face_of_a_mixed_or_distorted_mesh_bends_by_hinges_that_hold_it_flat_at_rest(tmp_path):
    """With bend_rigidity every face bends by hinges and nothing by bending springs (bend_stiffness unused): on a
    strip of quads whose inner vertices moved by up to 0.35 of the spacing (some then darts), and one of quads and
    triangles moved by up to 0.2,
    the hinges' forces on the flat strip, or on any affine map of it, vanish to round-off; and a file of quads
    that forms the built-in grid bends by hinges too (its listed springs, in Python and in a native unit's
    arrays), where without bend_rigidity it takes the grid's springs."""
    from wetcloth.fmu.native_mesh import cloth_arrays
    from wetcloth.mesh_file import read_mesh_file
    from wetcloth.topology import BEND

    for jitter, triangles in ((0.35, 0), (0.2, 400)):
        path = quad_file(tmp_path, 40, 40, jitter=jitter, triangles=triangles)
        if triangles == 0:
            quads = read_mesh_file(path).blocks[0]
            points = read_mesh_file(path).points
            turns = np.array([np.cross(*(points[quads[:, (m + k) % 4]] - points[quads[:, m]] for k in (1, 3)))[:, 2]
                              for m in range(4)])
            assert (np.sign(turns) != np.sign(turns[0])).any()  # a dart among the quads
        topo = build_topology(cantilever(tmp_path, 0, path, pinned_vertices=""))
        assert topo.hinge_count > 0 and not (topo.pair_kind == BEND).any()
        stiffness = hinge_matrix(topo)
        scale = abs(stiffness).max() * LENGTH
        affine = np.array([[0.3, -1.2, 0.5], [2.0, 0.1, -0.7], [0.4, 0.9, 1.1]]) @ topo.rest_pos + 0.2
        for coordinate in (*topo.rest_pos, *affine):
            assert np.abs(stiffness @ coordinate).max() < 1e-12 * scale, (jitter, triangles)
    grid = quad_file(tmp_path, 6, 4, clamp=0)
    assert not build_topology(cantilever(tmp_path, 0, grid, bend_rigidity=0.0)).listed
    scene = cantilever(tmp_path, 0, grid)
    assert build_topology(scene).hinge_count > 0
    arrays = cloth_arrays(scene)
    assert arrays["grid_nx"] == 0 and (arrays["pair_kind"] == HINGE).any()
