"""Uncontrolled propagation of a scenario (``geojax propagate``, the demo): mean elements per cycle and a drift summary.

The run is the closed loop with the null controller (``control.none``), cut
into at most 20 blocks of cycles so a progress bar can be drawn; every block
reuses one compiled function.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import NamedTuple

import jax
import numpy as np

from geojax.physics.constants import SECONDS_PER_DAY, SIDEREAL_DAY_S
from geojax.control import none
from geojax.compilation import Compilations
from geojax.runner.setup import cycle_count, params_of
from geojax.loop.simulate import Shared, simulate
from geojax.progress import TICK_S, Progress
from geojax.physics.propagate import DYNAMICS, CycleMeans, environment_grid, steps_per_cycle
from geojax.scenario import Scenario


class PropagationResult(NamedTuple):
    """An uncontrolled run: one-cycle means (``propagated_cycles`` of them), and its file, summary and figure.

    The file (``kind = "propagate"``): ``/cycles`` (``cycles_table``, the run's ``cycle_count(days)`` cycles),
    attributes ``scenario``, ``epoch_tt_s`` and ``step_s`` beside ``store.write_h5``'s.
    """

    cycles: CycleMeans  # numpy leaves [n_cycles]
    step_s: float  # the step actually used
    wall_s: float
    scenario: Scenario | None = None

    def table(self) -> dict[str, np.ndarray]:
        """The ``/cycles`` datasets: the first ``cycle_count(days)`` cycle means in edge units."""
        from geojax.runner.setup import cycle_count

        return cycles_table(self.cycles, cycle_count(self._scenario().days))

    def save(self, path) -> Path:
        """Write the file ``geojax propagate --out`` writes; returns its path."""
        from geojax import store
        from geojax.scenario import to_toml

        sc = self._scenario()
        return store.write_h5(path, {"cycles": self.table()}, to_toml(sc.config), self.wall_s,
                              attrs={"kind": "propagate", "scenario": sc.name, "epoch_tt_s": sc.epoch_tt_s,
                                     "step_s": self.step_s})

    def summary(self) -> list[str]:
        """The lines ``geojax propagate`` prints: the run, and what it did to the mean elements over its days."""
        from geojax.runner.setup import cycle_count

        sc = self._scenario()
        drift = drift_summary(self.cycles, sc.days)
        return [f"{sc.name}: {sc.days:g} days, {cycle_count(sc.days)} sidereal-day cycles, step {self.step_s:.2f} s, "
                f"{sc.dynamics.upper()} RK4, {self.wall_s:.1f} s wall",
                f"  mean inclination       {drift.i_start_deg:.4f} deg -> {drift.i_end_deg:.4f} deg",
                f"  inclination-vector change  {drift.di_deg:.4f} deg towards {drift.di_direction_deg:.1f} deg "
                f"over {drift.elapsed_days:.1f} days",
                f"  mean longitude drift   {drift.dlon_deg:+.4f} deg",
                f"  largest |e - e0|       {drift.de_max:.3e}"]

    def plot(self, folder, title: str | None = None) -> list[Path]:
        """The mean elements per cycle, ``FOLDER/NAME-uncontrolled.png``; returns its path in a list."""
        from geojax.runner.report import draw

        sc = self._scenario()
        title = f"{sc.name}, no control, {sc.days:g} days" if title is None else title
        return draw({"cycles": self.table()}, sc.config["station"]["box_half_width_deg"],
                    Path(folder) / f"{sc.name}-uncontrolled", title)

    def save_oem(self, path, **options) -> list[Path]:
        """The free drift's OEM (``free_drift``'s ``Result.save_oem``, its options), as ``geojax propagate --oem``."""
        return free_drift(self._scenario()).save_oem(path, **options)

    def save_maneuvers(self, path, **options) -> Path:
        """The free drift's OPM: the initial state and no maneuver block (``Result.save_maneuvers``)."""
        return free_drift(self._scenario()).save_maneuvers(path, **options)

    def _scenario(self) -> Scenario:
        if self.scenario is None:
            raise ValueError("scenario: this result does not carry its scenario; make it with propagate_scenario")
        return self.scenario


def free_drift(scenario: Scenario):
    """The scenario flown without control (``without_control``) through the closed loop, every step's true state
    kept (``Result.ephemeris``): the same loop and steps as ``propagate_scenario``'s (the null controller's,
    docs/design.md), over the run's ``cycle_count(days)`` cycles, for its CCSDS files."""
    from geojax.runner.rollout import simulate as closed_loop

    return closed_loop(without_control(scenario), 0, ephemeris=True)


def without_control(scenario: Scenario) -> Scenario:
    """``scenario`` with controller "none" and no recovery law: what ``propagate_scenario`` flies."""
    import tomllib

    from geojax.scenario import from_dict
    from geojax.scenario_toml import to_toml

    return from_dict({**tomllib.loads(to_toml(scenario.config)), "controller": {"kind": "none"}})


def propagated_cycles(days: float) -> int:
    """Cycles propagated for a run of ``days`` solar days.

    A run of ``days`` is ``runner.setup.cycle_count(days)`` cycles (365.25 days -> 366), in ``propagate`` as
    in ``simulate``; that many are written and drawn.  Cycle means refer to mid-cycle times, so the first
    and last means are ``n - 1`` cycles apart; the propagation goes on to n = ceil(days / sidereal day) + 1
    (365.25 days -> 368) so that span covers ``days`` and the change over exactly ``days`` is read off by
    interpolation (``drift_summary``), not extrapolated.
    """
    return max(1, math.ceil(days * SECONDS_PER_DAY / SIDEREAL_DAY_S - 1e-9) + 1)


def propagate_scenario(scenario: Scenario, progress: bool | None = None) -> PropagationResult:
    """Propagate a scenario without control; one-cycle mean elements per sidereal day.

    The run is cut into at most 20 equal blocks of cycles so a progress bar
    can be drawn; every block reuses one compiled function.
    """
    start = time.perf_counter()
    n_steps = steps_per_cycle(scenario.step_s)
    step_s = SIDEREAL_DAY_S / n_steps
    n_cycles = propagated_cycles(scenario.days)
    block = math.ceil(n_cycles / min(20, n_cycles))
    n_blocks = math.ceil(n_cycles / block)
    dynamics = DYNAMICS[scenario.dynamics]
    params = params_of(scenario, none.CONTROLLER)
    key = jax.random.key(0)  # the null controller draws nothing; the fix it is given is not used
    pieces = []
    # The bar counts the run's cycles (365.25 days: 366), as the file and summary do: the cycles integrated beyond
    # them, to interpolate the end, are part of the last block.
    with Progress(cycle_count(scenario.days), "cycles", enabled=progress, tick_s=TICK_S) as bar, Compilations() as log:
        bar.phase(f"compiling or loading from the cache, and running, the first {block} cycle{'s' * (block != 1)}")
        for b in range(n_blocks):
            block_epoch = scenario.epoch_tt_s + b * block * SIDEREAL_DAY_S
            env = environment_grid(block_epoch, scenario.epoch_tt_s, scenario.tt_minus_ut1_s, step_s, block, n_steps,
                                   scenario.config["forces"]["ephemeris"])
            state, records = _block(params, Shared(env, None), key, step_s=step_s, dynamics=dynamics)
            params = params._replace(initial=state)
            means = records.cycles.means._replace(t_s=records.cycles.means.t_s + b * block * SIDEREAL_DAY_S)
            pieces.append(jax.tree_util.tree_map(np.asarray, means))
            bar.update(min(block, n_cycles - b * block))
            if b == 0:  # the first block compiled the step: the rate and the ETA start after it
                bar.restart(f"{log.made()} and ran the first {block} cycle{'s' * (block != 1)} in {time.perf_counter() - start:.1f} s")
    cycles = jax.tree_util.tree_map(lambda *xs: np.concatenate(xs)[:n_cycles], *pieces)
    return PropagationResult(cycles, step_s, time.perf_counter() - start, scenario)


def cycles_table(cycles: CycleMeans, n_cycles: int | None = None) -> dict[str, np.ndarray]:
    """The ``/cycles`` datasets of ``geojax propagate`` in their edge units (degrees, days): the first
    ``n_cycles`` (default all)."""
    cycles = jax.tree_util.tree_map(lambda x: np.asarray(x)[:n_cycles], cycles)
    return {
        "t_s": cycles.t_s,
        "lon_deg": np.degrees(cycles.lon_rad),
        "drift_deg_per_day": np.degrees(cycles.drift_rad_s) * SECONDS_PER_DAY,
        "ex": cycles.ex,
        "ey": cycles.ey,
        "ix": cycles.ix,
        "iy": cycles.iy,
        "a_m": cycles.a_m,
    }


class DriftSummary(NamedTuple):
    """What a year without control does to the mean elements (first to last cycle)."""

    di_deg: float  # |change of the inclination vector i (cos Omega, sin Omega)|
    di_direction_deg: float  # direction of that change, atan2(d i_y, d i_x)
    i_start_deg: float
    i_end_deg: float
    de_max: float  # largest |e - e_start| over the run
    dlon_deg: float  # mean longitude change, last cycle minus first
    elapsed_days: float


def inclination_vector_deg(ix, iy):
    """Inclination vector i (cos Omega, sin Omega) in degrees from MEE (h, k) = tan(i/2) (cos, sin)."""
    tan_half = np.hypot(ix, iy)
    scale = np.degrees(2 * np.arctan(tan_half)) / np.where(tan_half > 0, tan_half, 1.0)
    return np.stack([ix * scale, iy * scale], -1)


def drift_summary(cycles: CycleMeans, span_days: float | None = None) -> DriftSummary:
    """Changes of the mean elements from the first cycle mean to ``span_days`` later.

    The end values are interpolated linearly between the two cycle means that
    bracket the end time (mean elements vary little within a day); without
    ``span_days`` the last cycle is the end.
    """
    t = np.asarray(cycles.t_s)
    t_end = t[-1] if span_days is None else t[0] + span_days * SECONDS_PER_DAY
    if t_end > t[-1] + 1e-6:
        raise ValueError(f"span_days: the run covers {(t[-1] - t[0]) / SECONDS_PER_DAY:.2f} days, not {span_days}")
    ivec = inclination_vector_deg(np.asarray(cycles.ix), np.asarray(cycles.iy))
    i_end = np.array([np.interp(t_end, t, ivec[:, j]) for j in range(2)])
    di = i_end - ivec[0]
    lon = np.degrees(np.unwrap(cycles.lon_rad))
    within = t <= t_end + 1e-6
    de = np.hypot(cycles.ex[within] - cycles.ex[0], cycles.ey[within] - cycles.ey[0])
    return DriftSummary(
        di_deg=float(np.hypot(*di)),
        di_direction_deg=float(np.degrees(np.arctan2(di[1], di[0]))),
        i_start_deg=float(np.hypot(*ivec[0])),
        i_end_deg=float(np.hypot(*i_end)),
        de_max=float(de.max()),
        dlon_deg=float(np.interp(t_end, t, lon) - lon[0]),
        elapsed_days=float((t_end - t[0]) / SECONDS_PER_DAY),
    )



_block = jax.jit(lambda params, shared, key, step_s, dynamics: simulate(none.CONTROLLER, params, shared, key,
                                                                       step_s=step_s, dynamics=dynamics),
                 static_argnames=("step_s", "dynamics"))
