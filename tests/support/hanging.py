"""The hanging sheet (issue 25's test case) as scene values, shared by the tests and the benchmarks: 1 m
square, pinned along its y_max edge, released horizontal 2 m up, water and floor far below.  The grid,
self-collision and stepping are each user's own.  No wetcloth import, so that a benchmark can load the
values into another wetcloth package (bench/core_against_numba.py)."""

HANGING = dict(width=1.0, length=1.0, pinned_edge="y_max", initial_tilt=0.0, initial_height=2.0, water_level=-10.0,
               floor_level=-20.0)
