"""``wetcloth build-fmu``: write the co-simulation unit, ``WetCloth.fmu`` (FMI 2.0) or ``WetCloth3.fmu`` (FMI 3.0);
with ``--native`` the unit compiled from the C++ core, ``WetClothNative.fmu`` or ``WetClothNative3.fmu``."""

from __future__ import annotations

from pathlib import Path

from wetcloth.commands.common import check_out_suffix, check_writable_folder, path_argument


def add_parser(sub) -> None:
    from wetcloth.fmu import default_fmu_path
    from wetcloth.fmu.native import native_fmu_path

    p = sub.add_parser("build-fmu", help="build the co-simulation unit WetCloth.fmu (FMI 2.0) or WetCloth3.fmu (FMI 3.0)",
                       description="Build WetCloth.fmu (FMI 2.0 co-simulation, pythonfmu) or, with --fmi 3, "
                                   "WetCloth3.fmu (FMI 3.0 co-simulation with the mesh as array outputs, pythonfmu3) "
                                   "from wetcloth's sources. With --native: the unit compiled from wetcloth's C++ "
                                   "core by the system C++ compiler ($CXX, else g++), which needs no Python "
                                   "(and writes no mesh frames).")
    p.add_argument("--out", type=path_argument, help=f"where to write the FMU, a file name ending in .fmu or a folder "
                                            f"to write it into under its default name (default {default_fmu_path(2)}, "
                                            f"with --fmi 3 {default_fmu_path(3)}; with --native "
                                            f"{native_fmu_path(2)}, {native_fmu_path(3)})")
    p.add_argument("--fmi", type=int, choices=(2, 3), default=2, help="FMI version (default 2)")
    p.add_argument("--scene", help="a scene file (or preset name) whose values become the unit's start values, "
                                   "its colliders' number fields parameters (collider1_radius), their shapes and "
                                   "the keys built in; its mesh files go into the unit's resources (the native "
                                   "unit compiles the cloth's mesh into its binary)")
    p.add_argument("--native", action="store_true",
                   help="compile the unit from the C++ core (no Python in it) instead of packing the Python one")
    p.set_defaults(func=main)


def out_path(out: Path | None, fmi_version: int, native: bool) -> Path:
    """Where the unit goes: ``out``, or in the folder ``out`` (or models/) under the unit's default name;
    a file name not ending in .fmu, or a folder that cannot be written, is refused naming --out."""
    from wetcloth.fmu import default_fmu_path
    from wetcloth.fmu.native import native_fmu_path

    default = (native_fmu_path if native else default_fmu_path)(fmi_version)
    path = default if out is None else out / default.name if out.is_dir() else out
    check_out_suffix(path, ".fmu")
    check_writable_folder(path.parent, "--out", out or path, make=False)  # made by the build, once it works
    return path


def main(args) -> int:
    out = out_path(args.out, args.fmi, getattr(args, "native", False))
    if getattr(args, "native", False):
        from wetcloth.fmu.native import build_native_fmu

        path = build_native_fmu(out, fmi_version=args.fmi, scene=args.scene, progress=True)
    else:
        from wetcloth.fmu.builder import build_fmu

        path = build_fmu(out, fmi_version=args.fmi, scene=args.scene)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")
    return 0
