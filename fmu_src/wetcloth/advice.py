"""What to change in a scene when a run would take long (a blow-up's likely cause and advice are the core's,
``_core.blow_up_text`` and its kin, which the native units' messages share).

Advice names only settings that differ from what the scene already has (no 'use implicit_euler'
on implicit_euler), each with its current value.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from wetcloth.scene import PARAMETERS, Scene

if TYPE_CHECKING:
    from wetcloth.progress import Sample

#: A run estimated to take longer than this (s of wall-clock time) is warned about.
WARN_AFTER = 300.0
IMPLICIT = "implicit_euler"


def _default(name: str):
    return PARAMETERS[name].default


@dataclass(frozen=True)
class Cost:
    """A run's estimated cost: ``seconds`` of wall-clock time still to go, in about ``steps``
    internal steps of ``step`` s of simulated time, ``per_step`` s of wall-clock time each
    (``exact`` False: lower bounds, the run took no step in its sample)."""

    seconds: float
    steps: float
    step: float
    per_step: float
    exact: bool = True


def estimate_cost(scene: Scene, duration: float, sample: Sample, stable_step: float) -> Cost:
    """The cost of the rest of a run (to ``duration`` s) from a timed ``sample`` of it.

    With progress in the sample, the rest takes as long per simulated second as the sample did.
    Without (not one step, or not one step ended, in the sample), the steps can be no larger than
    ``stable_step`` (the integrator's stability limit, s) and ``max_step``, and each takes at least
    the sample's time: a lower bound.
    """
    left = max(duration - sample.time, 0.0)
    if sample.simulated > 0.0 and sample.steps > 0:
        step = sample.simulated / sample.steps
        per_step = sample.elapsed / sample.steps
        return Cost(left * sample.elapsed / sample.simulated, left / step, step, per_step)
    step = scene.max_step if scene.tolerance == 0.0 else min(scene.max_step, stable_step)
    steps = max(left / step, 1.0)
    return Cost(steps * sample.elapsed, steps, step, sample.elapsed, exact=False)


def cheaper_settings(scene: Scene, cost: Cost, duration: float, stable_step: float) -> list[str]:
    """The settings of ``scene`` that make the run expensive, and what would be cheaper."""
    options = []
    particles, default_particles = scene.nx * scene.ny, _default("nx") * _default("ny")
    if particles > 4 * default_particles:
        options.append(f"fewer particles (nx x ny = {scene.nx} x {scene.ny} = {particles:.3g}; the towel has "
                       f"{_default('nx')} x {_default('ny')}): each step costs in proportion, and finer grids need "
                       "smaller steps")
    stability_bound = scene.integrator != IMPLICIT and stable_step < 0.5 * scene.max_step and cost.step < 2 * stable_step
    if stability_bound:
        causes = []
        if scene.areal_density < 0.1 * _default("areal_density"):
            causes.append(f"areal_density = {scene.areal_density:g} kg/m2")
        if scene.stretch_stiffness > 10 * _default("stretch_stiffness"):
            causes.append(f"stretch_stiffness = {scene.stretch_stiffness:g} N/m")
        why = f" ({', '.join(causes)})" if causes else ""
        options.append(f"integrator '{IMPLICIT}': {scene.integrator} is stable here only for steps below "
                       f"{stable_step:.2g} s{why}; implicit_euler is stable at any step")
        if causes:
            options.append("a less extreme " + " or ".join(c.split(" = ")[0] for c in causes))
    if scene.max_step < 1e-3 and cost.step >= 0.5 * scene.max_step and not stability_bound:
        bound = "is every step (tolerance = 0: fixed steps)" if scene.tolerance == 0.0 else "bounds every step"
        options.append(f"a larger max_step (max_step = {scene.max_step:g} s {bound}, and so makes the run this long)")
    if scene.tolerance > 0.0 and cost.exact and cost.step < 0.1 * min(scene.max_step, stable_step):
        options.append(f"a larger tolerance (now {scene.tolerance:g}; steps of {cost.step:.2g} s keep the error within it)")
    options.append(f"a shorter duration (now {duration:g} s)")
    return options


def cost_warning(scene: Scene, duration: float, sample: Sample, stable_step: float) -> str | None:
    """A one-line warning if the rest of the run would take longer than ``WARN_AFTER``, else None."""
    cost = estimate_cost(scene, duration, sample, stable_step)
    if cost.seconds <= WARN_AFTER:
        return None
    return (f"this run will take {about(cost.seconds, cost.exact)} ({cost.steps:.2g} steps of {cost.step:.2g} s, "
            f"{format_duration(cost.per_step)} each); cheaper: " + "; ".join(cheaper_settings(scene, cost, duration, stable_step)))


_UNITS = (("years", 3.15e7), ("days", 86400.0), ("h", 3600.0), ("min", 60.0), ("s", 1.0), ("ms", 1e-3), ("µs", 1e-6))
#: s: durations beyond this are said as 'more than 1000 years' (the figure itself means nothing then).
LONGEST_SAID = 1000 * _UNITS[0][1]


def format_duration(seconds: float) -> str:
    """'3.2 h', '174 days', '45 s', '150 µs'; 'more than 1000 years' beyond LONGEST_SAID."""
    if seconds > LONGEST_SAID:
        return "more than 1000 years"
    unit, size = next(((u, size) for u, size in _UNITS if seconds >= size), _UNITS[-1])
    value = seconds / size
    return f"{value:.0f} {unit}" if value >= 10 else f"{value:.2g} {unit}"


def about(seconds: float, exact: bool = True) -> str:
    """'about 3.2 h' of an estimate ('at least 3.2 h' of a lower bound, not ``exact``); 'more than 1000 years'
    beyond LONGEST_SAID."""
    said = format_duration(seconds)
    return said if seconds > LONGEST_SAID else f"{'about' if exact else 'at least'} {said}"
