"""``wetcloth blender-extension``: build the Blender extension ``wetcloth-VERSION.zip`` (docs/blender.md section 8)."""

from __future__ import annotations

from wetcloth.commands.common import path_argument


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


def main(args) -> int:
    from wetcloth.exporter.blender_extension.build import build_extension

    path = build_extension(args.out, args.wheels, args.pythons)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")
    return 0
