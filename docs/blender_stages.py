"""The two stages of a docs render script (``render_motion_blur.py``, ``render_folded_towel.py``).

In the project's Python the script simulates and exports a sequence into a temporary folder, then
runs itself again in Blender's Python (``.venv-blender``, bpy), which renders the PNG.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
BLENDER_PYTHON = ROOT / ".venv-blender" / "bin" / "python"


def main(script: str, description: str, default_out: Path, export: Callable[[Path], None],
         render: Callable[[Path, Path, int], None], argv=None) -> int:
    """The command line of a render ``script`` (its ``__file__``): ``export(sequence folder)`` in this
    Python, then ``render(sequence folder, out PNG, samples)`` in Blender's."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--out", type=Path, default=default_out, help="PNG to write")
    parser.add_argument("--samples", type=int, default=32, help="Cycles samples per pixel (default 32)")
    parser.add_argument("--in-blender", type=Path, metavar="SEQUENCE", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.in_blender is not None:  # second stage, inside Blender's Python
        render(args.in_blender, args.out.resolve(), args.samples)
        return 0
    if not BLENDER_PYTHON.exists():
        print(f"{BLENDER_PYTHON} is missing: make .venv-blender/.installed", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        sequence = Path(tmp) / "towel"
        export(sequence)
        subprocess.run([str(BLENDER_PYTHON), script, "--in-blender", str(sequence), "--out", str(args.out.resolve()),
                        "--samples", str(args.samples)], check=True)
    print(f"wrote {args.out}")
    return 0
