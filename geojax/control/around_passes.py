"""Burn nodes moved off the tracking passes (Gazzino 2016's orbit-determination periods, during which the thrusters
do not fire).

The QFFC (Li 2022, eq. (31)) puts its two burns at the inclination's nodes, l_2 = atan2(di_y, di_x) and l_1 = l_2 -
pi.  With ``controller.around_passes = true`` it moves both by the least shift Delta (in steps of ``STEP_DEG``, up
to ``MAX_SHIFT_DEG`` either way, the smaller |Delta| first, east before west) that keeps each burn's window, as
``control.burns.fly`` will place it (centred on its node, clipped into the cycle, eq. (13)'s duration), plus an
integration step either side (the loop fires whole steps), clear of every station's passes
(``navigation.schedule.overlaps_pass``).  The durations are those of the plan at the inclination's nodes.  Where
no shift clears the passes (long burns, or passes most of the day), the shift that loses the least of the burns'
time to them (``navigation.schedule.time_in_passes_s``; the loop's ``navigation.burns_during_passes`` decides what
fires in them).

What a shift costs.  Two burns on the line through l_2 + Delta change the inclination vector only along that line:
the planner corrects the deviation's projection on it, |V_N| = 2 V_s |di| cos(Delta) (eq. (30) at Delta = 0), and
leaves |di| sin(Delta) across it for the next cycle; the in-plane parts (eqs. (32)-(36)) are solved at the moved
nodes as at any others.  So the plan stays exact for what it corrects, and the inclination left over is a
cycle's worth of the shift's sine.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from geojax.navigation.schedule import Schedule, overlaps_pass, time_in_passes_s

STEP_DEG = 2.5  # 10 minutes of the orbit
MAX_SHIFT_DEG = 60.0  # 4 h: a pass of 4 h twice a day and a burn of an hour still fit
# 0, +d, -d, +2d, -2d, ...: the first clear candidate is the least shift
SHIFTS_RAD = np.radians(np.concatenate([[0.0], np.stack([np.arange(1, int(MAX_SHIFT_DEG / STEP_DEG) + 1) * STEP_DEG,
                                                         -np.arange(1, int(MAX_SHIFT_DEG / STEP_DEG) + 1) * STEP_DEG],
                                                        -1).ravel()]))


def burn_windows_s(l_rad, l_start_rad, t_start_s, cycle_s, burn_s):
    """(start, stop) [..., 2] of each burn's window, s since the run's start: centred on its node ``l_rad`` [..., 2]
    (the orbit turns 2 pi per cycle from ``l_start_rad``), clipped into the cycle, as ``control.burns.fly`` places
    it."""
    t_mid = jnp.mod(l_rad - l_start_rad, 2 * jnp.pi) / (2 * jnp.pi) * cycle_s
    start = jnp.clip(t_mid - burn_s / 2, 0.0, cycle_s - burn_s)
    return t_start_s + start, t_start_s + start + burn_s


def node_shift_rad(l2_rad, l_start_rad, t_start_s, cycle_s, burn_s, margin_s, stations: Schedule):
    """(Delta, clear): the least node shift of ``SHIFTS_RAD`` whose two burns (durations ``burn_s`` [2]; a burn of
    0 s is not flown and meets nothing) keep ``margin_s`` clear of every pass of ``stations`` (leaves [n, ...]), and
    whether one does (else the shift that leaves the least of the burns in passes)."""
    shifts = jnp.asarray(SHIFTS_RAD)
    l2 = l2_rad + shifts[:, None]
    l_rad = jnp.concatenate([l2 - jnp.pi, l2], axis=-1)  # [n_shifts, 2]: burn 1, burn 2
    start, stop = burn_windows_s(l_rad, l_start_rad, t_start_s, cycle_s, burn_s)
    fired = burn_s > 0
    start, stop = jnp.where(fired, start - margin_s, start), jnp.where(fired, stop + margin_s, start)
    meets = overlaps_pass(start[..., None], stop[..., None], stations)  # [n_shifts, 2, n_stations]
    clear = ~jnp.any(meets, axis=(-1, -2))
    first = jnp.argmax(clear)
    # none clear: the shift that loses the least firing to the passes (the smaller |shift| of equals)
    lost = jnp.sum(jnp.max(time_in_passes_s(start[..., None], stop[..., None], stations), axis=-1), axis=-1)
    return jnp.where(clear[first], shifts[first], shifts[jnp.argmin(lost)]), clear[first]
