"""``wetcloth build-fmu``: write the co-simulation unit, ``WetCloth.fmu`` (FMI 2.0) or ``WetCloth3.fmu`` (FMI 3.0);
with ``--native`` the unit compiled from the C++ core, ``WetClothNative.fmu`` or ``WetClothNative3.fmu``."""

from __future__ import annotations

from wetcloth.commands.common import path_argument


def add_parser(sub) -> None:
    from wetcloth.fmu import default_fmu_path
    from wetcloth.fmu.native import native_fmu_path

    p = sub.add_parser("build-fmu", help="build the co-simulation unit WetCloth.fmu (FMI 2.0) or WetCloth3.fmu (FMI 3.0)",
                       description="Build WetCloth.fmu (FMI 2.0 co-simulation, pythonfmu) or, with --fmi 3, "
                                   "WetCloth3.fmu (FMI 3.0 co-simulation with the mesh as array outputs, pythonfmu3) "
                                   "from wetcloth's sources. With --native: the unit compiled from wetcloth's C++ "
                                   "core by the system C++ compiler ($CXX, else g++), which needs no Python "
                                   "(and writes no mesh frames).")
    p.add_argument("--out", type=path_argument, help=f"where to write the FMU (default {default_fmu_path(2)}, "
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


def main(args) -> int:
    if getattr(args, "native", False):
        from wetcloth.fmu.native import build_native_fmu

        path = build_native_fmu(args.out, fmi_version=args.fmi, scene=args.scene, progress=True)
    else:
        from wetcloth.fmu.builder import build_fmu

        path = build_fmu(args.out, fmi_version=args.fmi, scene=args.scene)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")
    return 0
