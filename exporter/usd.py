"""One animated USD file through usd-core: time-sampled points, velocities and a ``wetness`` primvar.

The stage (``DIR/<prefix>.usd``, binary crate) holds a mesh ``/wetcloth/<prefix>`` whose topology
(quads or triangles, or given polygons of any corner count) and UVs (``primvars:st``) are written
once, and whose ``points``, ``velocities``, ``normals``, ``extent``, ``primvars:wetness`` (float,
vertex) and ``primvars:displayColor`` (linear RGB of the wetness colour map) are time-sampled, one
sample per frame at time code = frame number (first frame 1 unless chosen otherwise), with
``timeCodesPerSecond = fps``.  Units: metres (``metersPerUnit = 1``), z up; ``velocities`` in
metres per second, as USD defines them (stage units per second, whatever timeCodesPerSecond is),
which renderers use for motion blur.

Streaming: the layer is saved every ``SAVE_EVERY`` frames.  A crate file appends on save and then
reads the saved samples back from disk on demand, so memory stays flat however many frames come.
Blender's USD importer plays the points through a Mesh Sequence Cache modifier and reads the
primvars as attributes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, Vt

from wetcloth.exporter.errors import ExportError
from wetcloth.exporter.frame import Frame

#: Frames between two saves of the layer (bounds the memory the unsaved samples take).
SAVE_EVERY = 16


def srgb_to_linear(colors: np.ndarray) -> np.ndarray:
    """Linear RGB (n, 3) float32 of 8-bit sRGB colours (n, >=3), the colour space USD assumes."""
    s = colors[:, :3].astype(np.float64) / 255.0
    return np.where(s <= 0.04045, s / 12.92, ((s + 0.055) / 1.055) ** 2.4).astype(np.float32)


class UsdSequence:
    """Writes frames as time samples of one mesh in one USD file; ``close()`` finishes the file."""

    def __init__(self, path: Path, fps: float, name: str = "cloth", metadata: dict | None = None, polygons=None):
        """``polygons``: (corner counts (k,), vertex indices (sum of counts,)) to write as the faces instead
        of the frames' (a Blender object's own faces: its cache then keeps the object's topology)."""
        self.path = Path(path)
        self.polygons = polygons
        self.fps = float(fps)
        self.name = name
        self.metadata = metadata or {}
        self.stage: Usd.Stage | None = None
        self.mesh: UsdGeom.Mesh | None = None
        self.first_time_code: int | None = None
        self.last_time_code = 0

    def _create(self, time_code: int, frame: Frame) -> None:
        stage = Usd.Stage.CreateNew(str(self.path))
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        stage.SetTimeCodesPerSecond(self.fps)
        stage.SetFramesPerSecond(self.fps)
        stage.SetStartTimeCode(time_code)
        root = UsdGeom.Xform.Define(stage, "/wetcloth")
        stage.SetDefaultPrim(root.GetPrim())
        if self.metadata:
            stage.GetRootLayer().customLayerData = {"wetcloth": self.metadata}
        mesh = UsdGeom.Mesh.Define(stage, f"/wetcloth/{self.name}")
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        mesh.CreateDoubleSidedAttr(True)
        faces = frame.faces
        counts, indices = self.polygons or (np.full(len(faces), faces.shape[1]), faces.reshape(-1))
        if len(indices) and indices.max() >= frame.vertex_count:
            raise ExportError(f"polygons index vertices outside 0..{frame.vertex_count - 1}")
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.asarray(counts, dtype=np.int32)))
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.asarray(indices, dtype=np.int32)))
        mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        primvars = UsdGeom.PrimvarsAPI(mesh)
        st = primvars.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
        st.Set(Vt.Vec2fArray.FromNumpy(np.ascontiguousarray(frame.uv)))
        self._wetness = primvars.CreatePrimvar("wetness", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex)
        self._color = mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.vertex)
        self.stage, self.mesh = stage, mesh
        self.first_time_code = time_code

    def write(self, time_code: int, frame: Frame) -> None:
        """Add ``frame`` as the samples at ``time_code`` (the frame number)."""
        if self.stage is None:
            self._create(time_code, frame)
        mesh = self.mesh
        points = np.ascontiguousarray(frame.positions)
        mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(points), time_code)
        if frame.velocities is not None:
            mesh.GetVelocitiesAttr().Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(frame.velocities)), time_code)
        mesh.GetNormalsAttr().Set(Vt.Vec3fArray.FromNumpy(np.ascontiguousarray(frame.normals)), time_code)
        lo, hi = points.min(axis=0), points.max(axis=0)
        mesh.GetExtentAttr().Set(Vt.Vec3fArray([Gf.Vec3f(*map(float, lo)), Gf.Vec3f(*map(float, hi))]), time_code)
        self._wetness.Set(Vt.FloatArray.FromNumpy(np.ascontiguousarray(frame.wetness)), time_code)
        self._color.Set(Vt.Vec3fArray.FromNumpy(srgb_to_linear(frame.colors)), time_code)
        self.last_time_code = time_code
        if (time_code - self.first_time_code + 1) % SAVE_EVERY == 0:
            self.save()

    def save(self) -> None:
        """Save what has been written so far (end time code = the last frame)."""
        if self.stage is not None:
            self.stage.SetEndTimeCode(max(self.first_time_code, self.last_time_code))
            self.stage.GetRootLayer().Save()

    def close(self) -> None:
        """Finish the file; the writer cannot be used afterwards."""
        self.save()
        self.stage = self.mesh = None
