"""``wetcloth params``: every scene parameter and run setting with its unit, range, default and meaning."""

from __future__ import annotations

import json
import shutil
import textwrap

from wetcloth import run_settings
from wetcloth.scene import (COLLIDER_FIELDS, COLLIDER_KEY_FIELDS, GRIP_KEY_FIELDS, PARAMETERS, RESERVED_KEYS,
                            collider_key_name, collider_name, describe_range, grip_key_name, load_scene,
                            parameter_field, read_scene_file)


def add_parser(sub) -> None:
    p = sub.add_parser("params", help="list the parameters: unit, range, default, meaning",
                       description="List every scene parameter and [run] setting: its value in SCENE (default: "
                                   "the towel), default, unit, allowed range and meaning. The names are the same "
                                   "in scene files, --set, Python, the FMU and batch studies.")
    p.add_argument("scene", nargs="?", default=None, help="scene TOML file or preset name (default: towel)")
    p.add_argument("--json", action="store_true", help="print JSON (a list of objects) for scripts")
    p.set_defaults(func=main)


def rows(scene: str | None) -> list[dict]:
    """One dict per parameter, then per [run] setting: name, table, value, default, unit, range, min,
    max, choices, fmu (causality in the FMU) and doc."""
    data = read_scene_file(scene)
    values = {k: v for k, v in data.items() if k not in RESERVED_KEYS}
    out = []
    for name, f in PARAMETERS.items():
        md = f.metadata
        out.append(dict(name=name, table="", value=values.get(name, f.default), default=f.default, unit=md["unit"],
                        range=describe_range(f), min=md["lo"], min_exclusive=bool(md["lo_open"]), max=md["hi"],
                        choices=list(md["choices"]) or None, fmu=md["fmu"], doc=md["doc"]))
    for table, fields, flat in (("collider", COLLIDER_FIELDS, collider_name), ("grip_key", GRIP_KEY_FIELDS, grip_key_name),
                                ("collider_key", COLLIDER_KEY_FIELDS, collider_key_name)):
        count = max((flat(n)[0] for n in values if flat(n)), default=0)  # the scene's [[collider]]s, [[grip_key]]s, ...
        for name in (f"{table}{k}_{field}" for k in range(1, count + 1) for field in fields):
            f = parameter_field(name)
            md = f.metadata
            out.append(dict(name=name, table="", value=values.get(name, f.default), default=f.default, unit=md["unit"],
                            range=describe_range(f, name), min=md["lo"], min_exclusive=bool(md["lo_open"]),
                            max=md["hi"], choices=list(md["choices"]) or None, fmu=None,
                            doc=table.replace("_", " ") + ": " + md["doc"]))
    run_table = run_settings.resolve(data.get("run"))
    for name, s in run_settings.SETTINGS.items():
        out.append(dict(name=name, table="run", value=getattr(run_table, name), default=s.default, unit=s.unit,
                        range=run_settings.describe(s), min=s.lo, min_exclusive=True, max=s.hi, choices=None,
                        fmu=None, doc=s.doc))
    return out


COLUMN_MOST = 24  # characters of a column but the last: a longer value runs past it, the row going on below


def main(args) -> int:
    load_scene(args.scene)  # a scene that run refuses (a missing mesh file, a value out of range) is refused here too
    table = rows(args.scene)
    if args.json:
        print(json.dumps(table, indent=1))
        return 0
    heads = ("name", "value", "default", "unit", "meaning; allowed values")
    cells = [(("[run] " if r["table"] else "") + r["name"], _text(r["value"]), _text(r["default"]), r["unit"],
              f"{r['doc']}; {r['range']}") for r in table]
    widths = [min(COLUMN_MOST, max(len(h), *(len(c[i]) for c in cells))) for i, h in enumerate(heads[:-1])]
    indent = sum(widths) + 2 * len(widths)
    room = max(shutil.get_terminal_size((120, 24)).columns - indent, 30)
    for cell in [heads, *cells]:
        meaning = textwrap.wrap(cell[-1], room) or [""]
        print("\n".join(_row_lines([*cell[:-1], meaning[0]], widths)))
        for more in meaning[1:]:
            print(" " * indent + more)
    return 0


def _row_lines(cells, widths) -> list[str]:
    """A table row's lines: each cell at its column's start (widths: all but the last column's, two spaces
    apart); a cell that leaves less than those two spaces before the next column (a mesh file's path) goes
    on alone, and the row continues on the next line."""
    lines, line, start = [], "", 0
    for k, cell in enumerate(cells):
        if line and len(line) + 2 > start:
            lines.append(line)
            line = ""
        line = line.ljust(start) + cell
        if k < len(widths):
            start += widths[k] + 2
    return [*lines, line]
    return 0


def _text(value) -> str:
    if value is None:  # a field without a default (a grip key's time)
        return "-"
    return repr(value) if isinstance(value, str) else f"{value:g}"
