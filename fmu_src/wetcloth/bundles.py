"""The arrays the compiled core works on, bundled as named tuples (``wetcloth._core`` views them by
field name: ``fmu_src/core/include/wetcloth/core.hpp`` mirrors each bundle field by field).

Python allocates every array (NumPy) and owns it; the core reads and writes them in place, so a
snapshot of the arrays that carry over between steps is a snapshot of the run.  Arrays of per-particle
vectors are (3, n): rows x, y, z, each contiguous.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from wetcloth import _core
from wetcloth._core import SOLVER_COUNTERS

#: The fixed cloth: grid size, spring families (offset, rest length m, tension only, stiffness N/m,
#: damping N s/m per spring), 1 for moving particles, dry mass kg, envelope volume m3, Stokes
#: coefficient 6 pi a eta (N s/m), water capacity kg, wicking links (offsets, conductance kg/s).  A
#: mesh (grid_x = grid_y = 0, no families) lists its springs instead: ``pairs`` (2, S) int64 their
#: ends, ``pair_rest`` m, ``pair_stiffness`` N/m, ``pair_damping`` N s/m (S), the first
#: ``pair_tension_count`` tension-only, the next ``pair_buckling_count`` buckling (a triangle's edges: they push
#: back a little, spring_law.hpp), the rest both ways, of them the last ``pair_hinge_count`` hinges' terms (rest
#: length 0, damped by c (v_i - v_j) under either damping model); its wicking links ``wick_pairs`` (2, L) with
#: ``wick_pair_conductance`` (L) kg/s; ``triangles`` (m, 3) int64 for its face drag, shared among their
#: corners as ``corner_shares`` (m, 3) say.
Cloth = namedtuple("Cloth", "grid_x grid_y offsets rest tension_only stiffness damping free dry_mass volume "
                            "stokes_coefficient capacity wick_offsets wick_conductance pairs pair_rest pair_stiffness "
                            "pair_damping pair_tension_count wick_pairs wick_pair_conductance triangles corner_shares "
                            "pair_buckling_count pair_hinge_count", defaults=(0, 0))
#: Scene parameters as the core uses them (SI units; flags as bools).  ``wet_factor`` is 0 unless
#: wetness-dependent stiffness is active; ``air_density`` 0 switches the drag in air off; ``floor_z``
#: is the lowest particle centre; ``colliders`` (k, 13) the colliders' rows (colliders.hpp), ``meshes`` the
#: mesh colliders' triangles (wetcloth.collider_meshes.ColliderMeshes); the grip (grip.hpp): ``grip_x``,
#: ``grip_y``, ``grip_z`` (m, inputs), ``grip_keys`` (k, 4) rows time s, x, y, z m, ``grip_origin`` (3, n) m
#: the particles at t = 0 (empty: no pinned particles); the colliders' keys (collider_motion.hpp):
#: ``collider_keys`` (c, 8) rows collider (from 0), time s, x, y, z m, rx, ry, rz rad by collider and time,
#: ``collider_motion`` (k, MOTION_COLUMNS) the step loop's scratch (empty without keys).
Physics = namedtuple("Physics", "projected wet_factor water_level water_density thickness smooth stokes "
                                "drag_normal drag_tangential drag_linear current_x current_y air_density "
                                "wind_x wind_y wind_z floor_z "
                                "floor_friction absorption_capacity absorption_rate drying_rate wicking_rate "
                                "wick_step_limit skip_idle colliders meshes grip_x grip_y grip_z grip_keys grip_origin "
                                "collider_keys collider_motion")
#: Scratch and results: ``force`` (3, n) N; ``submerged`` (n) the submerged fraction of each
#: particle; ``saturation`` (n); ``blocks`` (6, n) per-particle symmetric 3x3 blocks (xx, yy, zz,
#: xy, xz, yz) of the system matrix; ``diagonal_blocks`` (6, n) the springs' part of its diagonal
#: blocks; ``direction`` (F, 3, n), ``along``, ``across`` (F, n) each spring's block; ``buf`` (4, n);
#: ``cells`` (DRAG_CELL_ROWS, n + nx + 1) a grid's face-drag rows (a mesh's: its particles' records,
#: mesh_records.hpp); ``wick_buffer`` (6, n); ``pair_direction`` (3, S), ``pair_along``, ``pair_across`` (S) the listed springs' blocks;
#: ``single_blocks`` (F, 5, n) float32: each spring's block for CG's products (ux, uy, uz, across, along - across);
#: ``single_buf`` (6, n) float32 those products' scratch.
Work = namedtuple("Work", "force submerged saturation blocks diagonal_blocks direction along across buf cells "
                          "wick_buffer pair_direction pair_along pair_across single_blocks single_buf")
#: Integrator and controller settings: ``integrator`` (code: ``wetcloth.integrators.INTEGRATORS``),
#: ``tolerance`` (-), ``allowed`` local position error per step (m, 0 = fixed steps of ``max_step``
#: s); ``newton_tolerance`` (m); ``cg_tolerance`` (-, BDF2's linear solves, relative to the
#: correction; adaptive steps with overdamped springs tighten it: ``adaptive_cg_tolerance`` in
#: implicit.hpp); the explicit schemes' stability data: ``omega_squared`` (1/s2, Gershgorin bound of
#: the springs), ``buoyancy_omega_squared`` (1/s2), ``damping_rate`` (1/s), ``spring_limit`` (s,
#: explicit Euler), drag rate ``drag_rate_offset + drag_rate_slope * speed`` (1/s); step limits and
#: factors; the blow-up speed (m/s); the sleep rule: ``sleep_distance`` (m) for ``sleep_after`` s.
Control = namedtuple("Control", "integrator tolerance allowed max_step newton_tolerance cg_tolerance "
                                "omega_squared buoyancy_omega_squared damping_rate spring_limit drag_rate_offset "
                                "drag_rate_slope smallest_step growth shrink blow_up_speed sleep_distance sleep_after")
#: State buffers: current and trial (pos, vel (3, n), water (n)), BDF2 history (the state before the
#: last step, and the acceleration (3, n) m/s^2 the last step implied at its end), sleep anchor, and
#: ``held`` (n): 1 for the particles the floor holds during the current step (scratch).
Buffers = namedtuple("Buffers", "pos vel water trial_pos trial_vel trial_water prev_pos prev_vel prev_water acceleration "
                                "anchor held")
#: Scratch of the implicit steps, each (3, n) unless noted: ``mass`` (n) kg; ``rhs``, ``dv``,
#: ``r``, ``z``, ``p``, ``ap`` of the linear solves; ``hat_pos``, ``hat_vel`` the BDF2 history
#: terms; ``predicted`` the extrapolated positions; ``step_acceleration`` (3, n) m/s^2 the
#: acceleration the last BDF2 step implies at its end; ``counters`` (int64: Newton iterations, CG
#: iterations, factorisations, unconverged solves).
Solver = namedtuple("Solver", "mass rhs dv r z p ap hat_pos hat_vel predicted step_acceleration counters")


def make_work(n: int, families: int, grid_x: int, pairs: int = 0) -> Work:
    """Zeroed scratch for n particles, ``families`` spring families and rows of ``grid_x`` particles (0:
    a mesh, with ``pairs`` listed springs)."""
    rows = _core.DRAG_CELL_ROWS
    cells = n + grid_x + 1 if grid_x > 0 else -(-_core.MESH_RECORD_SLOTS * (n + 1) // rows)  # the core's cells_length
    return Work(force=np.zeros((3, n)), submerged=np.zeros(n), saturation=np.zeros(n), blocks=np.zeros((6, n)),
                diagonal_blocks=np.zeros((6, n)), direction=np.zeros((families, 3, n)),
                along=np.zeros((families, n)), across=np.zeros((families, n)),
                buf=np.zeros((4, n)), cells=np.zeros((rows, cells)), wick_buffer=np.zeros((6, n)),
                pair_direction=np.zeros((3, pairs)), pair_along=np.zeros(pairs), pair_across=np.zeros(pairs),
                single_blocks=np.zeros((families, 5, n), dtype=np.float32),
                single_buf=np.zeros((6, n), dtype=np.float32))


def make_solver(n: int) -> Solver:
    """Zeroed scratch of the implicit steps for n particles."""
    vectors = {name: np.zeros((3, n)) for name in ("rhs", "dv", "r", "z", "p", "ap", "hat_pos", "hat_vel",
                                                   "predicted", "step_acceleration")}
    return Solver(mass=np.zeros(n), counters=np.zeros(SOLVER_COUNTERS, dtype=np.int64), **vectors)
