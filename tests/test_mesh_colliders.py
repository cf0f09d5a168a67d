"""Mesh colliders (docs/model.md section 6.3): a closed triangle mesh is a solid, an open one a shell kept
off on both sides; distances to the nearest triangle through a grid of cells (collider_mesh.cpp)."""

import numpy as np
import pytest
import trimesh

from wetcloth import _core, load_scene
from wetcloth.collider_meshes import is_closed, pack
from wetcloth.model import Model

CENTRE = np.array([0.1, 0.2, 0.5])
RADIUS = 0.3


def physics_with(meshes):
    """A scene's physics bundle whose colliders are the given meshes (points, triangles), in order."""
    rows = np.zeros((len(meshes), _core.COLLIDER_COLUMNS))
    rows[:, 0] = 4  # MESH
    rows[:, 4] = np.arange(len(meshes))  # each one's index among the meshes
    return Model(load_scene()).physics._replace(colliders=rows, meshes=pack(meshes))


def distances(phys, k, points, reach):
    points = np.ascontiguousarray(points)
    d, normal = np.zeros(points.shape[1]), np.zeros_like(points)
    _core.collider_distance(phys, k, points, reach, d, normal)
    return d, normal


def sphere_points(count, spread, seed=0):
    """Points (3, count) at random directions q (3, count), radii RADIUS +- spread about CENTRE."""
    rng = np.random.default_rng(seed)
    q = rng.standard_normal((3, count))
    q /= np.linalg.norm(q, axis=0)
    r = RADIUS + spread * rng.standard_normal(count)
    return q * r + CENTRE[:, None], q, r


def test_a_closed_mesh_is_a_solid_whose_signed_distance_is_the_spheres_it_approximates():
    """An icosphere inscribed in a sphere: its signed distance differs from the sphere's by at most the
    mesh's sagitta (the largest gap between the sphere and a face, R minus a face's distance from the
    centre), inside and out; the normals point out."""
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=RADIUS)
    points, faces = np.asarray(sphere.vertices) + CENTRE, np.asarray(sphere.faces)
    assert is_closed(faces)
    face_distance = np.abs(np.einsum("ij,ij->i", sphere.face_normals, sphere.triangles_center))
    sagitta = RADIUS - face_distance.min()
    phys = physics_with([(points, faces)])
    p, q, r = sphere_points(3000, 0.02)
    d, normal = distances(phys, 0, p, 0.2)
    assert np.abs(d - (r - RADIUS)).max() <= sagitta * (1 + 1e-9)
    assert (d[r < RADIUS - sagitta] < 0).all() and (d[r > RADIUS] > 0).all()
    assert (np.einsum("ij,ij->j", normal, q) > 0.9).all()


def test_turned_faces_of_a_closed_mesh_are_turned_out():
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=RADIUS)
    faces = np.asarray(sphere.faces)[:, ::-1]  # every face turned inwards
    phys = physics_with([(np.asarray(sphere.vertices) + CENTRE, faces)])
    d, _ = distances(phys, 0, CENTRE[:, None] + [[0.0], [0.0], [0.5 * RADIUS]], 1.0)
    assert d[0] < 0  # inside


def test_an_open_mesh_is_a_shell_with_distance_on_both_sides():
    """The upper half of the icosphere: points inside and outside it are both at positive distance, that of
    the sphere within the sagitta; no point is 'inside' a shell."""
    sphere = trimesh.creation.icosphere(subdivisions=4, radius=RADIUS)
    upper = sphere.triangles_center[:, 2] > 0.05
    shell = sphere.submesh([np.flatnonzero(upper)], append=True)
    assert not is_closed(np.asarray(shell.faces))
    phys = physics_with([(np.asarray(shell.vertices) + CENTRE, np.asarray(shell.faces))])
    p, q, r = sphere_points(3000, 0.02)
    above = q[2] > 0.5  # well inside the shell's cap
    d, normal = distances(phys, 0, p[:, above], 0.2)
    face_distance = np.abs(np.einsum("ij,ij->i", shell.face_normals, shell.triangles_center))
    sagitta = RADIUS - face_distance.min()
    assert (d > 0).all()
    assert np.abs(d - np.abs(r[above] - RADIUS)).max() <= sagitta * (1 + 1e-9)
    towards = np.einsum("ij,ij->j", normal, q[:, above]) * np.sign(r[above] - RADIUS)
    assert (towards[np.abs(r[above] - RADIUS) > sagitta] > 0.9).all()  # from the surface towards the point


@pytest.mark.parametrize("reach", [0.01, 0.05])
def test_no_triangle_within_reach_gives_reach(reach):
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=RADIUS)
    phys = physics_with([(np.asarray(sphere.vertices) + CENTRE, np.asarray(sphere.faces))])
    far = CENTRE[:, None] + np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 5.0], [0.5, -0.8, 0.0, 0.0]])
    d, _ = distances(phys, 0, far, reach)
    assert (d == reach).all()
