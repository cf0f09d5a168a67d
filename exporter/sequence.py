"""A frame sequence on disk: the directory checks, one file per frame (or one USD), frames.json, the loader.

``open_sequence`` checks the directory at once (before any simulating) and writes ``frames.json``
(marked incomplete) and ``load_in_blender.py`` there; every ``on_frame`` / ``write_frame`` then
writes one file and keeps nothing of it in memory; ``close()`` rewrites ``frames.json`` marked
complete and, for USD, finishes the ``.usd`` file.

Every file appears whole or not at all (``wetcloth.files.whole_file``), and ``frames.json`` stays
true to the frame files on disk: it is rewritten after each frame file, and a frame that it cannot
count (a full disk) is removed again.
"""

from __future__ import annotations

import importlib
import json
import math
import numbers
import pprint
import re
from pathlib import Path
from typing import Any, Callable

import numpy as np

from wetcloth.exporter.blender_options import MAX_FRAME, OPTIONS, blender_options
from wetcloth.exporter.errors import ExportError
from wetcloth.exporter.frame import (COLORMAP, FACES, Frame, check_float32, cloth_faces, make_frame,
                                     quads_from_triangles, wetness_lut)
from wetcloth.files import whole_file
from wetcloth.files import write_text as write_whole_text
from wetcloth.mesh_file import as_text

#: Mesh formats; ``usd`` is one animated file, the others one file per frame.
FORMATS = ("ply", "obj", "usd")
#: Writers of the per-frame formats (USD is always written by usd-core).
WRITERS = ("trimesh", "meshio")


def _imported_when_used(module: str) -> Callable[[Path, Frame], None]:
    """``module.write``, importing the module at the first frame: a USD sequence (written inside
    Blender too) then needs neither trimesh nor meshio."""
    def write(path: Path, frame: Frame) -> None:
        importlib.import_module(module).write(path, frame)
    return write


#: One module per (format, writer), each with ``write(path, frame)``.
FRAME_WRITERS: dict[tuple[str, str], Callable[[Path, Frame], None]] = {
    ("ply", "trimesh"): _imported_when_used("wetcloth.exporter.ply_trimesh"),
    ("ply", "meshio"): _imported_when_used("wetcloth.exporter.ply_meshio"),
    ("obj", "trimesh"): _imported_when_used("wetcloth.exporter.obj_trimesh"),
    ("obj", "meshio"): _imported_when_used("wetcloth.exporter.obj_meshio"),
}
MANIFEST = "frames.json"
LOADER = "load_in_blender.py"
#: Least zero-padding of frame numbers (the public naming: ``cloth_0001.ply``).
MIN_DIGITS = 4
#: A frame is written as ``<name>.<random>.part`` (created new: ``wetcloth.files.whole_file``) and
#: then renamed, so no reader sees half a frame.
PARTIAL = ".part"
#: What follows a file's name in the name of its temporary copy: ``.<random>.part`` for a frame (or
#: ``.part`` of earlier versions); frames.json and the loader are written as hidden
#: ``.<name>.<random>.tmp``.
_PART = r"(?:\.[a-z0-9_]+)?\.part"
#: Files that show a directory already holds a run's frames: any ``name_0001.ply``-like frame (or
#: one an interrupted run left half-written), a USD file, a manifest or a loader.
_FRAME_FILE = re.compile(rf"^.+_\d{{4,}}\.(ply|obj)({_PART})?$")
_PREFIX = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")


def frame_file_name(prefix: str, number: int, fmt: str, digits: int = MIN_DIGITS) -> str:
    """``cloth_0001.ply``: the file of frame ``number``, zero-padded to ``digits`` or more."""
    return f"{prefix}_{number:0{digits}d}.{fmt}"


def previous_run_files(directory: Path) -> list[Path]:
    """Files in ``directory`` that belong to an earlier export (frames, USD, manifest, loader)."""
    if not directory.is_dir():
        return []
    return sorted(
        p for p in directory.iterdir()
        if p.is_file() and (p.name in (MANIFEST, LOADER) or p.suffix == ".usd" or _FRAME_FILE.match(p.name))
    )


def _read_manifest(directory: Path) -> dict | None:
    """The ``frames.json`` in ``directory`` if this exporter wrote it (a JSON object naming the
    generator, a valid prefix and format), else None."""
    try:
        manifest = json.loads((directory / MANIFEST).read_text())
    except (OSError, ValueError):
        return None
    if not (isinstance(manifest, dict) and manifest.get("generator") == "wetcloth.exporter"
            and manifest.get("format") in FORMATS and isinstance(manifest.get("prefix"), str)
            and _PREFIX.match(manifest["prefix"])):
        return None
    return manifest


def _own_file_pattern(prefix: str, fmt: str) -> re.Pattern:
    """Names of the files a sequence of ``prefix`` and ``fmt`` writes: its frames (or its USD file),
    a frame left half-written (``.part``), ``frames.json``, the loader and their temporary copies."""
    media = re.escape(f"{prefix}.usd") if fmt == "usd" else rf"{re.escape(prefix)}_\d{{{MIN_DIGITS},}}\.{fmt}"
    side = "|".join(re.escape(name) for name in (MANIFEST, LOADER))
    return re.compile(rf"^(?:(?:{media})(?:{_PART})?|(?:{side})(?:\.tmp)?|\.(?:{side})\.[a-z0-9_]+\.tmp)$")


def sequence_files(directory: str | Path) -> list[Path]:
    """The files of the sequence that ``directory``'s own ``frames.json`` describes (frames, USD,
    manifest, loader, half-written leftovers); empty if no frames.json of this exporter is there."""
    directory = Path(directory)
    manifest = _read_manifest(directory)
    if manifest is None:
        return []
    own = _own_file_pattern(manifest["prefix"], manifest["format"])
    return sorted(p for p in directory.iterdir() if p.is_file() and own.match(p.name))


def _listing(paths: list[Path]) -> str:
    return ", ".join(p.name for p in paths[:3]) + (f" and {len(paths) - 3} more" if len(paths) > 3 else "")


#: How ``check_directory``'s refusal names the overwrite flag (the command line names its option instead).
OVERWRITE = "overwrite=True"


def check_directory(directory: str | Path, overwrite: bool = False, exclusive: bool = False) -> list[Path]:
    """May a new sequence be written into ``directory``?  Returns the files it would replace; changes nothing.

    ExportError if the path is a file, or if the directory holds another run's frames (frame-like
    files ``*_0001.ply``, a ``.usd``, ``frames.json`` or ``load_in_blender.py``) and ``overwrite``
    is off.  With ``overwrite``, only the sequence that the directory's own ``frames.json``
    describes is replaced: any other frame-like file (another tool's, or frames of another
    prefix or format) is refused, never deleted.  ``exclusive`` refuses every file that is not
    part of that sequence (the FMU's ``mesh_output_dir``: a folder that belongs to the unit).
    """
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise ExportError(f"export directory {directory} is an existing file, not a directory")
    try:
        taken = previous_run_files(directory)
        own = sequence_files(directory) if directory.is_dir() else []
        present = sorted(directory.iterdir()) if exclusive and directory.is_dir() else taken
    except OSError as exc:
        raise ExportError(f"cannot read export directory {directory}: {exc.strerror or exc}") from None
    if taken and not overwrite:
        frames = [p for p in taken if p.name not in (MANIFEST, LOADER)] or taken  # the frames, else what shows a run
        raise ExportError(f"export directory {directory} already holds another run's frames ({_listing(frames)}); "
                          f"choose a new directory, delete them first or pass {OVERWRITE} to replace that run")
    foreign = [p for p in present if p not in own]
    if foreign:
        whose = ("files that are not part of the frame sequence its frames.json describes" if own
                 else "files this exporter did not write (no frames.json of wetcloth's describes them)")
        raise ExportError(f"export directory {directory} holds {whose} ({_listing(foreign)}); it replaces only "
                          "its own sequence: choose a new directory or move them first")
    return own


def _make_directory(directory: Path) -> None:
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ExportError(f"cannot create export directory {directory}: {exc.strerror or exc}") from None


def _frame_number(name: str) -> int:
    """The frame number in a frame file name such as ``cloth_0012.ply`` (or ``.ply.<random>.part``)."""
    return int(re.search(rf"_(\d+)\.[a-z]+(?:{_PART})?$", name).group(1))


def _remove(paths: list[Path]) -> None:
    for path in paths:
        try:
            path.unlink(missing_ok=True)
        except OSError as exc:
            raise ExportError(f"cannot remove the old frame {path}: {exc.strerror or exc}") from None


def _write_text(path: Path, text: str) -> None:
    """Write a small text file whole or not at all; ExportError with the operating system's reason."""
    try:
        write_whole_text(path, text)
    except OSError as exc:
        raise ExportError(f"cannot write {path.name} in export directory {path.parent}: {exc.strerror or exc}") from None


def loader_source(settings: dict[str, Any]) -> str:
    """The Blender loader script with ``settings`` filled in (see ``blender_loader.py``)."""
    template = Path(__file__).with_name("blender_loader.py").read_text()
    marker = "SETTINGS: dict = {}  # filled in by the exporter\n"
    if marker not in template:
        raise RuntimeError("blender_loader.py lost its SETTINGS marker line")
    filled = "SETTINGS: dict = " + pprint.pformat(settings, width=110, compact=True, sort_dicts=False) + "\n"
    return template.replace(marker, filled, 1)


class FrameSequence:
    """Frames of one run written into one directory.  Use ``open_sequence`` to make one.

    ``on_frame(index, sim)`` is the runner's callback (index 0, the state at t = 0, becomes
    ``<prefix>_0001``, or the file of ``first_frame``); ``write_frame(positions, wetness)`` is the
    same for arrays.  ``close()`` finishes the sequence.  Also a context manager.
    """

    def __init__(self, directory: Path, fmt: str, writer: str, fps: float, scene=None,
                 triangles=None, uv=None, prefix: str = "cloth", digits: int = MIN_DIGITS,
                 faces: str = "quads", first_frame: int = 1, blender: dict | None = None, polygons=None):
        self.directory = directory
        self.format = fmt
        self.writer = "usd-core" if fmt == "usd" else writer
        self.fps = float(fps)
        self.scene = scene
        self.prefix = prefix
        self.digits = digits
        self.faces = faces
        self.first_frame = first_frame
        self.blender = blender_options(blender, first_frame)
        self.frame_count = 0
        self.closed = False
        self.replaced: list[str] = []  # files of an earlier sequence that open_sequence replaced
        self._triangles = None if triangles is None else np.asarray(triangles)
        self._uv = None if uv is None else np.asarray(uv, dtype=np.float32)
        self._faces: np.ndarray | None = None  # what is written: the triangles, their quads or the file's faces
        self._file_faces: np.ndarray | None = None  # a mesh cloth's faces as in its file
        self._first_time: float | None = None
        self._last_time: float | None = None
        self._shape: tuple[int, int] | None = None
        self._usd = None
        if fmt == "usd":
            from wetcloth.exporter.usd import UsdSequence

            self._usd = UsdSequence(self.usd_path, self.fps, name=prefix, metadata=self._usd_metadata(),
                                    polygons=polygons)

    # ------------------------------------------------------------------ names
    @property
    def usd_path(self) -> Path:
        """The USD file (format ``usd`` only)."""
        return self.directory / f"{self.prefix}.usd"

    def frame_path(self, number: int) -> Path:
        """File of frame ``number`` (``first_frame`` is the first); for USD, the one USD file."""
        if self.format == "usd":
            return self.usd_path
        return self.directory / frame_file_name(self.prefix, number, self.format, self.digits)

    # ------------------------------------------------------------------ writing
    def resume_after(self, frames_written: int) -> None:
        """Continue a run restored to an earlier (or later) point (an FMU rollback): the next frame
        written is ``first_frame + frames_written``.  Frame files after it belong to the abandoned
        branch and are removed, so the folder and frames.json keep describing one run."""
        if not (isinstance(frames_written, int) and not isinstance(frames_written, bool) and frames_written >= 0):
            raise ExportError(f"frames_written must be a whole number >= 0, got {frames_written!r}")
        if self.format != "usd":
            _remove([p for p in self._frame_files() if _frame_number(p.name) >= self.first_frame + frames_written])
        self.frame_count = frames_written
        self._last_time = None  # the next frame's time is checked against those written after this point only
        if frames_written == 0:
            self._first_time = None

    def _frame_files(self) -> list[Path]:
        """This sequence's frame files on disk (and half-written ones)."""
        own = _own_file_pattern(self.prefix, self.format)
        return [p for p in self.directory.iterdir() if own.match(p.name) and p.name not in (MANIFEST, LOADER)
                and not p.name.endswith(".tmp")]

    def on_frame(self, index: int, sim) -> None:
        """Runner callback: write ``sim``'s cloth as frame ``first_frame + index`` (index 0 is t = 0)."""
        if index != self.frame_count:
            raise ExportError(
                f"frame index {index} arrived but {self.frame_count} was expected next: frames are "
                f"written in order, one per call, starting at 0 (export directory {self.directory})"
            )
        if self._triangles is None:
            self._triangles, self._uv, self._file_faces = cloth_faces(sim.model.topology)
        self.write_frame(sim.positions, sim.wetness, time=sim.time, velocities=sim.velocities)

    def _topology(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The triangles, the faces to write (the triangles, or by default their quads or a mesh cloth's
        faces as in its file) and the UVs."""
        if self._triangles is None:
            if self.scene is None:
                raise ExportError("write_frame needs the cloth's triangles: pass scene= or triangles= and uv=")
            from wetcloth.topology import build_topology

            self._triangles, self._uv, self._file_faces = cloth_faces(build_topology(self.scene))
        if self._uv is None:
            raise ExportError("write_frame needs UVs with the triangles: pass uv= (n, 2) in 0..1")
        if self._faces is None:
            self._faces = (self._file_faces if self.faces == "quads" and self._file_faces is not None
                           else quads_from_triangles(self._triangles, self._uv) if self.faces == "quads"
                           else self._triangles)
        return self._triangles, self._faces, self._uv

    def write_frame(self, positions, wetness, time: float | None = None, velocities=None) -> Path:
        """Write the next frame: positions (n, 3) m, wetness (n,) 0..1, at ``time`` s, with the
        velocities (n, 3) m/s if given (the USD file keeps them for motion blur); returns its file."""
        if self.closed:
            raise ExportError(f"the frame sequence in {self.directory} is closed")
        triangles, faces, uv = self._topology()
        count = len(np.asarray(positions))
        if count != len(uv):
            raise ExportError(f"frame {self.frame_count + 1} has {count} vertices, the cloth {len(uv)}: "
                              "the topology is fixed")
        frame = make_frame(positions, wetness, triangles, uv, faces=faces, velocities=velocities)
        time = self._checked_time(time)
        self._shape = (frame.vertex_count, len(frame.faces))
        number = self.first_frame + self.frame_count
        path = self.frame_path(number)
        if self._usd is not None:
            self._usd.write(number, frame)
        else:
            try:
                with whole_file(path, PARTIAL) as partial:
                    FRAME_WRITERS[(self.format, self.writer)](partial, frame)
            except OSError as exc:
                raise ExportError(f"cannot write frame {path}: {exc.strerror or exc}") from None
        before = (self.frame_count, self._first_time, self._last_time)
        self.frame_count += 1
        if self._first_time is None:
            self._first_time = time
        self._last_time = time
        if self._usd is None:
            try:
                self.write_manifest(complete=False)
            except ExportError as exc:  # frames.json cannot count this frame: take the frame back
                path.unlink(missing_ok=True)
                self.frame_count, self._first_time, self._last_time = before
                raise ExportError(f"cannot write frame {path}: {MANIFEST} could not count it ({exc}); "
                                  f"removed it, {MANIFEST} counts the {self.frame_count} frames before") from None
        return path

    def _checked_time(self, time) -> float:
        """The next frame's time, s (None: its frame number over fps): a finite number after the last frame's."""
        if time is None:
            time = self.frame_count / self.fps
        if isinstance(time, bool) or not isinstance(time, numbers.Real) or not math.isfinite(time):
            raise ExportError(f"time must be a finite number of seconds, got {time!r}; the frame is not written")
        if self._last_time is not None and time <= self._last_time:
            raise ExportError(f"time {float(time):g} s is not after the last frame's {self._last_time:g} s: frames "
                              "come in time order; the frame is not written")
        return float(time)

    # ------------------------------------------------------------------ side files
    def _usd_metadata(self) -> dict:
        return {"fps": self.fps, "units": "m", "colormap": COLORMAP}

    def manifest(self, complete: bool) -> dict[str, Any]:
        """The contents of ``frames.json``."""
        vertices, faces = self._shape if self._shape else (None, None)
        files = (self.usd_path.name if self.format == "usd"
                 else f"{self.prefix}_{{frame:0{self.digits}d}}.{self.format}")
        return {
            "generator": "wetcloth.exporter",
            "format": self.format,
            "writer": self.writer,
            "files": files,
            "prefix": self.prefix,
            "first_frame": self.first_frame,
            "frame_count": self.frame_count,
            "complete": complete,
            "fps": self.fps,
            "first_time": self._first_time,
            "last_time": self._last_time,
            "vertex_count": vertices,
            "faces": self.faces,
            "face_count": faces,
            "units": {"length": "m", "time": "s", "wetness": "1 (absorbed water over capacity, 0 to 1)"},
            "up_axis": "Z",
            "attributes": {
                "wetness": "float per vertex: PLY property and USD primvar; OBJ has it only as the colour",
                "color": f"RGBA 8-bit sRGB: matplotlib '{COLORMAP}' colour map of wetness",
                "normals": "unit vertex normals of each frame",
                "uv": "rest-sheet coordinates scaled to 0..1",
                "velocities": "USD only: the points' velocities in m/s, time-sampled (for motion blur)",
            },
            "colormap": COLORMAP,
            "blender": self.blender,
            "scene": None if self.scene is None else {name: as_text(v) for name, v in self.scene.to_dict().items()},
        }

    def write_manifest(self, complete: bool) -> Path:
        path = self.directory / MANIFEST
        _write_text(path, json.dumps(self.manifest(complete), indent=1) + "\n")
        return path

    def loader_settings(self) -> dict[str, Any]:
        return {
            "format": self.format,
            "prefix": self.prefix,
            "fps": self.fps,
            "first_frame": self.first_frame,
            "options": self.blender,
            "option_table": OPTIONS,
            "directory": str(self.directory.resolve()),
            "manifest": MANIFEST,
            "usd_file": self.usd_path.name,
            "colormap": COLORMAP,
            "lut": wetness_lut()[:, :3].tolist(),
        }

    def write_loader(self) -> Path:
        path = self.directory / LOADER
        _write_text(path, loader_source(self.loader_settings()))
        return path

    # ------------------------------------------------------------------ closing
    def close(self, complete: bool = True) -> None:
        """Finish: the USD file (if any) and ``frames.json`` with the frame count.  Idempotent.

        ``complete=False`` (a run stopped early) keeps the manifest marked incomplete."""
        if self.closed:
            return
        self.closed = True
        failure = None  # the USD file's, reported before the manifest's
        if self._usd is not None:
            try:
                self._usd.close()
            except Exception as exc:
                failure = exc
        try:
            self.write_manifest(complete=complete)
        except ExportError:
            if failure is None:
                raise
        if failure is not None:
            raise failure

    def __enter__(self) -> "FrameSequence":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(complete=exc_type is None)


def _checked_polygons(polygons, fmt: str) -> tuple[np.ndarray, np.ndarray]:
    """``polygons`` (counts, indices) as int arrays; ExportError unless fmt is usd, every count is 3 or more
    and the counts add up to the indices (which write_frame's vertex count bounds)."""
    if fmt != "usd":
        raise ExportError(f"polygons apply to usd only, not {fmt!r}")
    counts, indices = (np.asarray(a) for a in polygons)
    if (counts.ndim != 1 or indices.ndim != 1 or not np.issubdtype(counts.dtype, np.integer)
            or not np.issubdtype(indices.dtype, np.integer) or (counts < 3).any() or counts.sum() != len(indices)
            or (len(indices) and indices.min() < 0)):
        raise ExportError("polygons must be (corner counts, each 3 or more, and as many vertex indices >= 0 as the "
                          "counts add up to)")
    return counts.astype(np.int64), indices.astype(np.int64)


def _check_uv(uv) -> None:
    """ExportError unless ``uv`` is (n, 2) finite numbers within float32's range."""
    try:
        uv = np.asarray(uv, dtype=np.float64)
    except (TypeError, ValueError):
        raise ExportError(f"uv must be numbers of shape (n, 2), got {uv!r:.80}") from None
    if uv.ndim != 2 or uv.shape[1] != 2:
        raise ExportError(f"uv must have shape (n, 2), got {uv.shape}")
    check_float32("uv", uv)


def open_sequence(directory, fmt: str = "ply", writer: str = "trimesh", fps: float = 30.0, scene=None, *,
                  triangles=None, uv=None, prefix: str = "cloth", digits: int = MIN_DIGITS,
                  overwrite: bool = False, exclusive: bool = False, faces: str = "quads", first_frame: int = 1,
                  blender: dict | None = None, polygons=None, frame_count: int | None = None) -> FrameSequence:
    """Start a frame sequence in ``directory``, checked now: ExportError if it cannot be used.

    fmt: ``ply`` (binary, default), ``obj`` or ``usd``; writer: ``trimesh`` or ``meshio`` (ply and
    obj; usd is always written by usd-core); fps: frames per second of the sequence (1/s);
    scene: the Scene, recorded in frames.json and used for the triangles and UVs when frames come
    from ``write_frame`` rather than ``on_frame``; triangles (m, 3) and uv (n, 2) in 0..1: the
    same without a scene; prefix: file names ``<prefix>_0001.<fmt>``; digits: least zero-padding (4 to 12);
    overwrite: replace the earlier sequence that the directory's own frames.json describes instead
    of refusing it (never other files); exclusive: refuse a directory holding any file that is not
    part of that sequence (``sequence.replaced`` lists the files replaced);
    faces: ``quads`` (default: one per grid cell, made of its two triangles; a cloth from a mesh file: the
    file's faces) or ``triangles``;
    first_frame: number of the first frame (file ``<prefix>_0001``, USD time code 1 by default);
    blender: options of ``load_in_blender.py`` (see ``blender_options.OPTIONS``: solidify,
    subdivision, smooth, material, first_frame, timeline), recorded in frames.json;
    polygons: ``usd`` only, (corner counts (k,), vertex indices) of faces of any corner count to write
    instead of ``faces`` (a Blender object's own, so that its Mesh Sequence Cache keeps them).
    frame_count: how many frames will come, when known: the last one's number must stay within Blender's
    frames (at most ``MAX_FRAME``) too.

    The directory is created if missing.  Refused up front (see ``check_directory``): a path that
    is a file, a directory that cannot be created or written, and one that already holds frames
    (``*_0001.ply``-like files, a ``.usd``, ``frames.json`` or ``load_in_blender.py``) unless
    ``overwrite`` and they are the sequence its frames.json describes.  Each frame file appears
    whole (written under a new ``.<random>.part`` name, then renamed): a run stopped midway leaves
    only complete frames.
    """
    if fmt not in FORMATS:
        raise ExportError(f"unknown mesh format {fmt!r}; choose one of {', '.join(FORMATS)}")
    if writer not in WRITERS:
        raise ExportError(f"unknown mesh writer {writer!r}; choose one of {', '.join(WRITERS)}")
    if fmt == "usd" and writer != "trimesh":
        raise ExportError(f"writer {writer!r} does not apply to usd: usd-core writes USD files (the writer "
                          "chooses the library for ply and obj)")
    if isinstance(fps, bool) or not (isinstance(fps, numbers.Real) and math.isfinite(fps) and fps > 0):
        raise ExportError(f"fps must be a finite number > 0, got {fps!r}")
    if not _PREFIX.match(prefix):
        raise ExportError(f"file prefix {prefix!r} must be letters, digits, '.', '_' or '-' (no path)")
    if not (isinstance(digits, numbers.Integral) and not isinstance(digits, bool) and MIN_DIGITS <= digits <= 12):
        raise ExportError(f"digits must be a whole number from {MIN_DIGITS} to 12, got {digits!r}")
    if faces not in FACES:
        raise ExportError(f"unknown faces {faces!r}; choose one of {', '.join(FACES)}")
    if not (isinstance(first_frame, numbers.Integral) and not isinstance(first_frame, bool)
            and 0 <= first_frame <= MAX_FRAME):
        raise ExportError(f"first_frame must be a whole number from 0 to {MAX_FRAME}, got {first_frame!r}")
    if frame_count is not None and first_frame + frame_count - 1 > MAX_FRAME:
        raise ExportError(f"first_frame {first_frame} with {frame_count} frames ends at frame "
                          f"{first_frame + frame_count - 1}, beyond Blender's last frame {MAX_FRAME}; allowed: a "
                          f"first_frame up to {MAX_FRAME - frame_count + 1}")
    first_frame, digits = int(first_frame), int(digits)  # NumPy's integers too, stored as Python's
    if frame_count is not None:  # every frame's name as long: name order stays frame order
        digits = max(digits, len(str(first_frame + frame_count - 1)))
    if uv is not None:
        _check_uv(uv)
    blender_options(blender, first_frame)  # checked before the directory is touched
    if polygons is not None:
        polygons = _checked_polygons(polygons, fmt)
    if directory is None or str(directory) == "":
        raise ExportError("no export directory given")
    directory = Path(directory)
    replaced = check_directory(directory, overwrite, exclusive)
    _make_directory(directory)
    _remove(replaced)
    sequence = FrameSequence(directory, fmt, writer, fps, scene=scene, triangles=triangles, uv=uv,
                             prefix=prefix, digits=digits, faces=faces, first_frame=first_frame, blender=blender,
                             polygons=polygons)
    sequence.replaced = [p.name for p in replaced]
    sequence.write_manifest(complete=False)  # also proves the directory is writable
    sequence.write_loader()
    return sequence


def resume_sequence(directory, frames_written: int, fmt: str = "ply", writer: str = "trimesh", fps: float = 30.0,
                    scene=None, *, prefix: str = "cloth", digits: int = MIN_DIGITS, faces: str = "quads",
                    first_frame: int = 1, blender: dict | None = None) -> FrameSequence:
    """Continue, in a new process, the sequence in ``directory`` after ``frames_written`` frames
    (an FMU state restored from bytes): the next frame is ``first_frame + frames_written``.

    The directory's own frames.json must describe a sequence of this ``prefix`` and ``fmt`` whose
    first ``frames_written`` frames are on disk; frames after them are removed (the abandoned
    branch).  The other arguments are those ``open_sequence`` took.  ExportError otherwise.
    """
    directory = Path(directory)
    manifest = _read_manifest(directory) if directory.is_dir() else None
    if manifest is None or (manifest["prefix"], manifest["format"]) != (prefix, fmt):
        raise ExportError(f"cannot resume frames in {directory}: no frames.json of a {fmt} sequence "
                          f"'{prefix}_*' written by this exporter is there")
    sequence = FrameSequence(directory, fmt, writer, fps, scene=scene, prefix=prefix, digits=digits, faces=faces,
                             first_frame=first_frame, blender=blender)
    missing = [path.name for path in map(sequence.frame_path, range(first_frame, first_frame + frames_written))
               if not path.is_file()]
    if missing:
        raise ExportError(f"cannot resume frames in {directory} after {frames_written} frames: "
                          f"{_listing([Path(name) for name in missing])} missing")
    sequence.resume_after(frames_written)
    first_time = manifest.get("first_time")
    sequence._first_time = float(first_time) if isinstance(first_time, (int, float)) and frames_written else None
    sequence.write_manifest(complete=False)
    return sequence
