"""Issue 25's hanging sheet as scene values (no wetcloth import, so that a benchmark can load it into any
wetcloth package): 1 m square, pinned along y_max, released horizontal 2 m up, water and floor far below.
The grid and self-collision are each benchmark's own."""

HANGING = dict(width=1.0, length=1.0, pinned_edge="y_max", initial_tilt=0.0, initial_height=2.0, water_level=-10.0,
               floor_level=-20.0)
