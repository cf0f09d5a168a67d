"""``wetcloth blender-extension``: build the Blender extension ``wetcloth-VERSION.zip`` (docs/blender.md section 7)."""

from __future__ import annotations

from wetcloth.commands.common import path_argument


def add_parser(sub) -> None:
    p = sub.add_parser("blender-extension", help="build the Blender extension wetcloth-VERSION.zip",
                       description="Build the Blender (4.2 or newer) extension wetcloth-VERSION.zip: the Wet Cloth "
                                   "panel, bpy.ops.wetcloth.bake(), and wetcloth's compiled core as a wheel for "
                                   "Blender's Python 3.11. Install it with "
                                   "'blender --command extension install-file -r user_default wetcloth-VERSION.zip' "
                                   "or from Preferences > Get Extensions > Install from Disk.")
    p.add_argument("--out", type=path_argument, help="folder to write the zip into (default: the current one)")
    p.add_argument("--wheel", type=path_argument,
                   help="a wetcloth wheel to bundle (default: built now from the source tree with pip wheel)")
    p.set_defaults(func=main)


def main(args) -> int:
    from wetcloth.exporter.blender_extension.build import build_extension

    path = build_extension(args.out, args.wheel)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")
    return 0
