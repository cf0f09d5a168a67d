"""``wetcloth build-fmu``: write the FMI 2.0 co-simulation unit ``WetCloth.fmu``."""

from __future__ import annotations

from pathlib import Path


def add_parser(sub) -> None:
    p = sub.add_parser("build-fmu", help="build the FMI 2.0 co-simulation unit WetCloth.fmu",
                       description="Build WetCloth.fmu (FMI 2.0 co-simulation, pythonfmu) from wetcloth's sources.")
    p.add_argument("--out", type=Path, default=Path("models/WetCloth.fmu"),
                   help="where to write the FMU (default models/WetCloth.fmu)")
    p.set_defaults(func=main)


def main(args) -> int:
    from wetcloth.fmu.builder import build_fmu

    path = build_fmu(args.out)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")
    return 0
