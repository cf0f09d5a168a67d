"""wetcloth.exporter: Blender-ready mesh sequences (PLY, OBJ, USD) of a simulated cloth.

    from wetcloth.exporter import open_sequence
    sequence = open_sequence("out/frames", fmt="ply", writer="trimesh", fps=30, scene=scene)
    run(scene, duration, fps, on_frame=sequence.on_frame)    # cloth_0001.ply, cloth_0002.ply, ...
    sequence.close()                                         # frames.json; finishes a .usd

One module per format and writer (``ply_trimesh``, ``ply_meshio``, ``obj_trimesh``, ``obj_meshio``,
``usd``) behind ``open_sequence``; all write the same :class:`Frame`, with quads (one per grid cell)
or triangles (a cloth from a mesh file: its file's faces and UVs).  Beside the frames go ``frames.json`` (fps, frame count, units, scene parameters, the
Blender import options) and ``load_in_blender.py``.
"""

from wetcloth.exporter.errors import ExportError
from wetcloth.exporter.frame import (
    COLORMAP,
    FACES,
    Frame,
    cloth_faces,
    make_frame,
    quads_from_triangles,
    sheet_uv,
    wetness_colors,
    wetness_lut,
)
from wetcloth.exporter.sequence import (
    FORMATS,
    LOADER,
    MANIFEST,
    WRITERS,
    FrameSequence,
    check_directory,
    frame_file_name,
    open_sequence,
    previous_run_files,
    resume_sequence,
    sequence_files,
)

__all__ = [
    "COLORMAP", "ExportError", "FORMATS", "Frame", "FrameSequence", "LOADER", "MANIFEST", "WRITERS",
    "check_directory", "cloth_faces", "frame_file_name", "make_frame", "open_sequence", "previous_run_files", "resume_sequence",
    "sequence_files", "sheet_uv", "wetness_colors", "wetness_lut",
]
