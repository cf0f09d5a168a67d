"""One cloth's bake, frame by frame: a wetcloth Simulation written into a USD sequence (no bpy).

The sequence is ``DIR/<prefix>.usd`` (with frames.json and load_in_blender.py beside it, as every
wetcloth export): time code = Blender frame, timeCodesPerSecond = the scene's fps, the points in
the cloth object's own (local) coordinates and in its vertex order, with its faces (the grid's quads,
a mesh cloth's own polygons), so a Mesh Sequence Cache modifier on that object plays it and the
object keeps its topology.  ``step()`` computes and writes one frame; ``close(complete)``
finishes the file (a bake cancelled midway keeps the frames written so far).
"""

from __future__ import annotations

import numpy as np

from wetcloth.exporter import open_sequence, sheet_uv
from wetcloth.exporter.blender_extension.geometry import GridCloth, MeshCloth
from wetcloth.scene import Scene
from wetcloth.simulation import Simulation


class ClothBake:
    """Bake ``scene`` (its cloth ``cloth``: the plane's grid or the mesh) over ``frame_count`` frames from
    ``frame_start`` at ``fps``.  ``to_local``: the 4 x 4 matrix from world to the object's coordinates;
    ``water_levels``: the water level (m) over each frame interval (index k: from frame k to k + 1),
    or None for the scene's constant ``water_level``."""

    def __init__(self, scene: Scene, cloth: GridCloth | MeshCloth, directory, prefix: str, fps: float, frame_start: int,
                 frame_count: int, to_local=None, water_levels=None):
        if frame_count < 1:
            raise ValueError(f"a bake needs at least one frame, got {frame_count}")
        self.sim = Simulation(scene)
        self.cloth = cloth
        self.order = np.asarray(cloth.order)
        topology = self.sim.model.topology
        position_of = np.empty_like(self.order)  # Blender vertex of each particle
        position_of[self.order] = np.arange(len(self.order))
        matrix = np.eye(4) if to_local is None else np.asarray(to_local, dtype=np.float64)
        self._linear, self._offset = matrix[:3, :3], matrix[:3, 3]
        self.times = np.arange(frame_count) / float(fps)
        self.water_levels = None if water_levels is None else [float(level) for level in water_levels]
        self.sequence = open_sequence(directory, fmt="usd", fps=fps, scene=scene, triangles=position_of[topology.triangles],
                                      uv=sheet_uv(topology.rest_xy)[self.order], prefix=prefix,
                                      faces=cloth.faces, polygons=cloth.polygons, first_frame=int(frame_start),
                                      overwrite=True)
        self.done = 0
        self.largest_error = 0.0  # m: the largest error a step estimated for itself, over the frames baked

    @property
    def frame_count(self) -> int:
        return len(self.times)

    @property
    def finished(self) -> bool:
        return self.done == len(self.times)

    def step(self) -> None:
        """Simulate up to the next frame and write it (the first call writes the state at t = 0)."""
        k = self.done
        if k > 0:
            if self.water_levels is not None:
                self.sim.set_inputs(water_level=self.water_levels[k - 1])
            self.sim.sample(self.times[k:k + 1])
            self.largest_error = max(self.largest_error, float(self.sim.sample_errors[0]))
        world = self.sim.positions + self.cloth.shift
        positions = (world @ self._linear.T + self._offset)[self.order]
        velocities = (self.sim.velocities @ self._linear.T)[self.order]
        self.sequence.write_frame(positions, self.sim.wetness[self.order], time=self.sim.time, velocities=velocities)
        self.done += 1

    def close(self) -> None:
        """Finish the USD file; frames.json says whether every frame was baked."""
        self.sequence.close(complete=self.finished)
