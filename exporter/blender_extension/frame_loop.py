"""The bake's frame loop (no bpy): one frame (``advance``) and one timer tick of the modal bake (``tick``),
as ``bpy.ops.wetcloth.bake`` runs them on its ``operators.Baking`` (anything with ``step()``, ``done``,
``total`` and ``finished``)."""

from __future__ import annotations

import time

from wetcloth.errors import BlowUpError

#: The events a modal bake handles; it passes the others on.
BAKE_EVENTS = ("TIMER", "ESC")


def advance(baking, cancel_after: int = 0) -> str | None:
    """Bake one frame; None, or why the bake stops: 'cancelled' once ``cancel_after`` frames are baked
    (0: never) and more are left, or 'error: ...' (the frame was not baked)."""
    try:
        baking.step()
    except (BlowUpError, ValueError, OSError) as exc:
        return f"error: {exc}"
    if cancel_after and baking.done >= cancel_after and not baking.finished:
        return "cancelled"
    return None


def tick(baking, event_type: str, budget: float, cancel_after: int = 0, clock=time.perf_counter) \
        -> tuple[str | None, str | None]:
    """One of BAKE_EVENTS: on a timer tick, frame after frame while ``clock`` (s) is less than ``budget`` s
    past the tick's start; Esc stops the bake.  (stopped, status): why the bake stopped (as ``advance`` says; 'cancelled' for Esc;
    None if it finished or goes on) and the status bar's text while it goes on, None once it is over."""
    stopped = "cancelled" if event_type == "ESC" else None
    until = clock() + budget
    while stopped is None and not baking.finished and clock() < until:
        stopped = advance(baking, cancel_after)
    if stopped is None and not baking.finished:
        return None, f"Wet Cloth: frame {baking.done} of {baking.total} (Esc cancels, keeping the frames baked)"
    return stopped, None
