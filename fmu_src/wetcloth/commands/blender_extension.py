"""``wetcloth blender-extension``: build the Blender extension ``wetcloth-VERSION.zip`` (docs/blender.md section 8)."""

from __future__ import annotations

import re
import zipfile
from pathlib import Path

from wetcloth.commands.common import check_writable_folder, path_argument

#: A wetcloth wheel's metadata, as pip writes it: wetcloth-VERSION.dist-info/METADATA.
WHEEL_METADATA = re.compile(r"wetcloth-[^/]+\.dist-info/METADATA")


def add_parser(sub) -> None:
    p = sub.add_parser("blender-extension", help="build the Blender extension wetcloth-VERSION.zip",
                       description="Build the Blender (4.2 or newer) extension wetcloth-VERSION.zip: the Wet Cloth "
                                   "panel, bpy.ops.wetcloth.bake(), and wetcloth's compiled core as a wheel for "
                                   "each Python given (Blender 4.2 to 5.0: 3.11, 5.1 and later: 3.13). Install it with "
                                   "'blender --command extension install-file -r user_default -e wetcloth-VERSION.zip' "
                                   "or from Preferences > Get Extensions > Install from Disk.")
    p.add_argument("--out", type=path_argument, help="folder to write the zip into (default: the current one)")
    p.add_argument("--python", dest="pythons", action="append", default=[], type=path_argument, metavar="PYTHON",
                   help="build a wheel with this interpreter (repeatable; default: the running Python). Blender "
                        "4.2 to 5.0 run Python 3.11, 5.1 and later Python 3.13: give both for every Blender")
    p.add_argument("--wheel", dest="wheels", action="append", default=[], type=path_argument, metavar="WHEEL",
                   help="a wetcloth wheel to bundle as it is (repeatable)")
    p.set_defaults(func=main)


def check_wheel_contents(wheel: Path) -> None:
    """Refuse a --wheel that is not a wheel of wetcloth inside (a zip holding wetcloth's dist-info METADATA),
    whatever its name says."""
    if not wheel.is_file():
        raise ValueError(f"--wheel {wheel}: no such file")
    try:
        with zipfile.ZipFile(wheel) as archive:
            names = archive.namelist()
    except (OSError, zipfile.BadZipFile) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else "not a zip file"
        raise ValueError(f"--wheel {wheel}: not a wheel ({why})") from None
    if not any(WHEEL_METADATA.fullmatch(name) for name in names):
        raise ValueError(f"--wheel {wheel}: not a wetcloth wheel (no wetcloth-VERSION.dist-info/METADATA in it)")


def main(args) -> int:
    from wetcloth.exporter.blender_extension.build import build_extension, check_wheel

    for wheel in args.wheels:
        check_wheel(wheel)  # its name first: the project, version and Python it says
        check_wheel_contents(wheel)
    check_writable_folder(args.out or Path("."), "--out", make=False)  # made once the Pythons are checked
    path = build_extension(args.out, args.wheels, args.pythons)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")
    return 0
