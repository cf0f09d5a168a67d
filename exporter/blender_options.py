"""What ``load_in_blender.py`` builds by default: the render-ready import options, in one table.

The exporter checks the options given to ``open_sequence(..., blender={...})``, records them in
``frames.json`` (key ``blender``) and in the loader; the loader applies them, and takes changes from
its command line (``blender --python load_in_blender.py -- --subdivision 2``) or its ``load(...)``
keywords, checked against the same table (it is copied into the loader with the settings).
"""

from __future__ import annotations

import math
from typing import Any

from wetcloth.exporter.errors import ExportError

#: Blender's frame numbers lie within +-1048574 (MAXFRAME).
MAX_FRAME = 1048574

#: name -> kind ('float', 'int', 'bool' or 'choice'), default, allowed range or choices, help text.
#: A default of None for first_frame means the sequence's own first frame.
OPTIONS: dict[str, dict[str, Any]] = {
    "solidify": {
        "kind": "float", "default": 1.0, "min": 0.0, "max": 100.0,
        "help": "Solidify modifier as thick as the cloth (frames.json: scene.thickness) times this; 0: none",
    },
    "subdivision": {
        "kind": "int", "default": 1, "min": 0, "max": 6,
        "help": "Subdivision Surface levels (viewport and render); 0: none",
    },
    "smooth": {"kind": "bool", "default": True, "help": "smooth shading"},
    "material": {
        "kind": "bool", "default": True,
        "help": "the 'wetcloth wetness' material: darker and glossier where the wetness attribute is higher",
    },
    "first_frame": {
        "kind": "int", "default": None, "min": -MAX_FRAME, "max": MAX_FRAME,
        "help": "scene frame at which the sequence starts (default: the sequence's first frame)",
    },
    "timeline": {
        "kind": "choice", "default": "auto", "choices": ["auto", "set", "keep"],
        "help": "the scene's fps and frame range: 'set' them to the sequence's, 'keep' them, or 'auto': "
                "set them in a new, unsaved file and keep them in a saved one",
    },
}


def check_option(name: str, value: Any) -> Any:
    """``value`` as option ``name`` takes it, or ExportError naming the option and what it allows."""
    spec = OPTIONS.get(name)
    if spec is None:
        raise ExportError(f"unknown Blender import option {name!r}; the options are {', '.join(OPTIONS)}")
    kind = spec["kind"]
    if kind == "bool":
        if not isinstance(value, bool):
            raise ExportError(f"Blender import option {name} must be true or false, got {value!r}")
        return value
    if kind == "choice":
        if value not in spec["choices"]:
            raise ExportError(f"Blender import option {name} must be one of {', '.join(spec['choices'])}, got {value!r}")
        return value
    number_types = (int,) if kind == "int" else (int, float)
    if isinstance(value, bool) or not isinstance(value, number_types) or not math.isfinite(value) \
            or not spec["min"] <= value <= spec["max"]:
        whole = "a whole number" if kind == "int" else "a number"
        raise ExportError(f"Blender import option {name} must be {whole} from {spec['min']:g} to {spec['max']:g}, "
                          f"got {value!r}")
    return value if kind == "int" else float(value)


def blender_options(given: dict[str, Any] | None, first_frame: int) -> dict[str, Any]:
    """Every option, the given ones checked and the others at their defaults (first_frame: the sequence's)."""
    given = dict(given or {})
    values = {name: spec["default"] for name, spec in OPTIONS.items()}
    values["first_frame"] = first_frame
    for name, value in given.items():
        values[name] = check_option(name, value)
    return values
