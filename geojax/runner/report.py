"""The file, the summary and the figures of one closed-loop run: what ``Result.save``, ``Result.summary`` and
``Result.plot`` give (``geojax simulate --out / --plots`` calls them), and the figures ``geojax plot`` draws of a
``simulate`` or ``propagate`` file (``draw``).

The file (``kind = "simulate"``): ``/metrics`` (``loop.metrics.summarize``'s, ``cpu_s_per_orbit`` and
``status``), ``/cycles`` (``loop.metrics.cycle_table``), then where the run kept its steps (a feedback law's, by
default: it has no reference run) the per-step ``/steps`` (``loop.metrics.step_table``), else the uncontrolled
``/reference`` and the station's ``/target`` (``reference_and_target``); attributes ``kind``, ``scenario``,
``epoch_tt_s``, ``seed``, ``compile_s`` and ``status_codes`` beside ``store.write_h5``'s.
"""

from __future__ import annotations

import importlib
import math
from pathlib import Path

import jax
import numpy as np

from geojax.control import none
from geojax.loop.metrics import STATUS_MEANINGS, STATUS_TEXT, YEAR_CYCLES, step_table
from geojax import compilation, traced
from geojax import states as parts
from geojax.runner.setup import (controller_of, cycle_count, environment_cycles, params_of, program_identity,
                               uncontrolled_boundaries)
from geojax.physics.constants import SECONDS_PER_DAY, SIDEREAL_DAY_S
from geojax.physics.propagate import DYNAMICS, environment_grid, for_one_sample, steps_per_cycle
from geojax.scenario import Scenario


# What each per-axis component of a planner's Delta-V is (control.burn_metrics.dv_components_per_year), printed beside it.
DV_COMPONENT_NOTES = {
    "dv_radial_per_year_mps": "radial (RTN R): the arms' cosine loss (thrust lines through the centre of mass)",
    "dv_ew_per_year_mps": "along-track (RTN T): east-west control",
    "dv_ns_per_year_mps": "cross-track (RTN N): north-south control",
}


def groups(result, reference=None) -> dict[str, dict]:
    """The datasets of the run's file, ``{group: {name: value}}``; ``reference``: ``reference_and_target``'s
    result where the caller computed it already (``geojax simulate`` does, while the closed loop compiles)."""
    sc = scenario_of(result)
    out = {"metrics": {**metrics(result), "status": int(result.status)}, "cycles": result.cycles()}
    if result.records.steps is not None:
        out["steps"] = step_table(result.records, result.step_s, float(result.params.station["lon_rad"]))
    else:
        n_cycles = len(result.records.cycles.dv_mps)
        out["reference"], out["target"] = reference_and_target(sc, n_cycles) if reference is None else reference
    return out


def save(result, path: str | Path, reference=None) -> Path:
    """Write the run's file to ``path`` (atomically); returns the path.  ``reference``: as for ``groups``."""
    from geojax import store
    from geojax.scenario import to_toml

    sc = scenario_of(result)
    attrs = {"kind": "simulate", "scenario": sc.name, "epoch_tt_s": sc.epoch_tt_s,
             **({} if result.seed is None else {"seed": result.seed}), "compile_s": result.compile_s, "run_s": result.run_s,
             "status_codes": STATUS_TEXT}
    return store.write_h5(path, groups(result, reference), to_toml(sc.config), result.wall_s, attrs=attrs)


def metrics(result) -> dict[str, float]:
    """The loop's metrics as floats, and ``cpu_s_per_orbit``: wall seconds per cycle after compilation (with it,
    where a result carries no run time of its own, ``Result.run_s``)."""
    n_cycles = len(result.records.cycles.dv_mps)
    return {**{k: float(v) for k, v in result.metrics.items()}, "cpu_s_per_orbit": run_s(result) / n_cycles}


def run_s(result) -> float:
    """Wall seconds of the compiled run alone where it was timed (``Result.run_s``), else of the whole call."""
    return result.run_s if math.isfinite(result.run_s) else result.wall_s


def summary(result, paper: bool = True) -> list[str]:
    """What ``geojax simulate`` prints after the run: its length, time and status, then every metric with its
    unit, beside the published number of a shipped scenario's paper (``geojax.papers``) with ``paper``, and
    notes (``row_notes``): what is extrapolated, what is n/a, what ``cpu_s_per_orbit`` times, and where this
    run differs from the paper's."""
    from geojax import papers, scenario
    from geojax.results import units_of

    sc = scenario_of(result)
    values = metrics(result)
    code = int(result.status)
    n_cycles = len(result.records.cycles.dv_mps)
    lines = [f"{sc.name}: {sc.controller}, {n_cycles} cycles in {run_s(result):.1f} s {timed(result)}, "
             f"status {code} ({STATUS_MEANINGS[code]})"]
    published, source = papers.published(sc.name, sc.config) if paper else ({}, "")
    changed = []
    if published:
        shipped = scenario.load(sc.name).config if sc.name in scenario.available() else None
        changed = papers.departures(sc.config, result.seed or 0, shipped)
    if changed:
        source = f"{source} (its own run)"
    notes = row_notes(values, n_cycles, result)
    lines.append(f"  {'metric':32s} {'unit':>7s} {'geojax':>12s}  {source}")
    lines += [f"  {name:32s} {units_of(name) or '1':>7s} {value:12.5g}  {published.get(name, ''):8s}  "
              f"{notes.get(name, '')}".rstrip() for name, value in values.items()]
    lines += [f"  {name:32s} {units_of(name):>7s} {'n/a':>12s}  {'':8s}  {text}"
              for name, text in notes.items() if name not in values]
    if DV_COMPONENT_NOTES.keys() <= values.keys():
        lines.append("  note: dv_radial, dv_ew and dv_ns are each burn's Delta-V per RTN axis, components and not a "
                     "partition: they add up to more than dv_per_year_mps where a burn is not along one axis")
    if published and sc.name in papers.DIFFERS_FROM_PAPER:
        lines.append(f"  note: {papers.DIFFERS_FROM_PAPER[sc.name]}")
    if changed:
        lines.append(f"  note: {source.split(' (')[0]}'s numbers are for its own run; this one differs in "
                     f"{', '.join(changed)}, so they are shown for orientation only")
    return lines


def timed(result) -> str:
    """What a run's time (``run_s``) includes."""
    if math.isfinite(result.run_s):
        return "compiled (the compiled loop and metrics alone)"
    return "with set-up and compilation"


def row_notes(values: dict, n_cycles: int, result) -> dict[str, str]:
    """{metric: note} of the printed summary: a per-year figure of a run shorter than a year (``YEAR_CYCLES``
    cycles) is extrapolated from its length; a planner's Delta-V components say which axis each is
    (``DV_COMPONENT_NOTES``: the radial part is the arms' cosine loss), and are n/a (a row of its own) for a
    controller without burns; ``cpu_s_per_orbit`` says what it times (Li 2022's 0.09 s beside it is its Fortran
    per orbit, one sample)."""
    notes = {name: text for name, text in DV_COMPONENT_NOTES.items() if name in values}
    if n_cycles < YEAR_CYCLES:
        days = n_cycles * SIDEREAL_DAY_S / SECONDS_PER_DAY
        notes.update({name: "; ".join(filter(None, (notes.get(name), f"extrapolated from {days:.4g} days "
                                                                    f"({n_cycles} cycles)")))
                      for name in values if name.endswith("_per_year_mps")})
    notes.update({name: "n/a: this controller flies no burns to split" for name in DV_COMPONENT_NOTES
                  if name not in values})
    notes["cpu_s_per_orbit"] = f"wall s per cycle, {timed(result)}"
    return notes


def plot(result, folder: str | Path, reference=None) -> list[Path]:
    """The run's figures in ``folder``, named after the scenario: from its steps (a feedback law's), the ground
    track and thrust (``NAME-ground-track.png``, ``NAME-thrust.png``), else its cycles and station keeping
    (``NAME.png``, ``NAME-station-keeping.png``); then each carried part's (``part_figures``).  ``reference``: as
    for ``groups``."""
    sc = scenario_of(result)
    drawn = draw(groups(result, reference), sc.config["station"]["box_half_width_deg"], Path(folder) / sc.name,
                 run_title(sc))
    return drawn + part_figures(result, folder)


def part_figures(run, folder: str | Path) -> list[Path]:
    """The figures every part the run carried declares (``states.base.Part.figures``), in the loop's order:
    ``run`` a single run's ``Result`` or a results file read back (``geojax.figures.FileRun``)."""
    carried = getattr(run, "parts", ()) or parts.parts_of(run.states)
    return [path for part in carried if part.figures is not None
            for path in _resolved(part.figures)(run, Path(folder))]


def _resolved(figures):
    """A part's figures function, imported where the part names it by its path (``"module:function"``)."""
    if callable(figures):
        return figures
    module, _, name = figures.partition(":")
    return getattr(importlib.import_module(module), name)


def run_title(sc: Scenario) -> str:
    """A run's figure title: the scenario's name, then its controller (a Katz 2025 law's thrust mode) where the
    name does not already say it ("li2022-qffc", "li2022, fompc", "katz2025-constant")."""
    mode = sc.config["controller"].get("thrust_mode")  # Katz 2025's laws name theirs
    what = f"{mode} thrust" if mode else sc.controller
    return sc.name if (mode or sc.controller) in sc.name else f"{sc.name}, {what}"


def draw(groups: dict, box_half_width_deg: float, stem: Path, title: str, fmt: str = "png",
         dpi: int = 150) -> list[Path]:
    """The figures of a single run's datasets, written as ``STEM[-what].FMT``: per step (``/steps``: ground
    track and thrust), else per cycle (``/cycles``), with the station keeping where ``/reference`` and
    ``/target`` are there."""
    from geojax import plots

    if "steps" in groups:
        return plots.plot_feedback(groups["steps"], box_half_width_deg, stem, title=title, dpi=dpi, fmt=fmt)
    figures = [plots.plot_cycles(groups["cycles"], stem.parent / f"{stem.name}.{fmt}", title=title, dpi=dpi)]
    if {"reference", "target"} <= set(groups):
        figures.append(plots.plot_station_keeping(groups["cycles"], groups["reference"], groups["target"],
                                                  stem.parent / f"{stem.name}-station-keeping.{fmt}", title=title,
                                                  box_half_width_deg=box_half_width_deg, dpi=dpi))
    return figures


def reference_and_target(scenario: Scenario, n_cycles: int) -> tuple[dict, dict]:
    """The uncontrolled run from the initial state (not re-started: the path the satellite would take without
    control), its mean elements at the first ``n_cycles + 1`` cycle boundaries (``/reference``: t_s, lon_deg, ex,
    ey, ix, iy), and the station's targets (``/target``), for figures beside a closed loop.

    One sample's program, compiled for start-up (``compilation.ONE_SAMPLE_OPTIONS``): it draws a figure.  Its
    environment is the first cycles of the grid the closed loop's ``prepare`` computed (the same program, no new
    compilation) where that covers them."""
    n_steps = steps_per_cycle(scenario.step_s)
    step_s = SIDEREAL_DAY_S / n_steps
    n_env = max(n_cycles + 1, environment_cycles(n_cycles, controller_of([scenario]).reference_cycles))
    env = environment_grid(scenario.epoch_tt_s, scenario.epoch_tt_s, scenario.tt_minus_ut1_s, step_s, n_env, n_steps,
                           scenario.config["forces"]["ephemeris"])
    identity = program_identity(scenario, "uncontrolled", step_s, n_cycles + 1)
    _, ref = traced.call(_uncontrolled_jit, "uncontrolled", identity, params_of(scenario, none.CONTROLLER), env,
                         compiler_options=compilation.ONE_SAMPLE_OPTIONS, step_s=step_s,
                         dynamics=for_one_sample(DYNAMICS[scenario.dynamics]), n_cycles=n_cycles + 1)
    ref = np.asarray(ref)
    uncontrolled = {"t_s": np.arange(len(ref)) * SIDEREAL_DAY_S, "lon_deg": np.degrees(ref[:, 0]),
                    "ex": ref[:, 3], "ey": ref[:, 4], "ix": ref[:, 5], "iy": ref[:, 6]}
    station = scenario.config["station"]
    goals = {"lon_deg": float(station["lon_deg"]), "drift_deg_per_day": 0.0,
             **{k: float(station[k]) for k in ("ex", "ey", "ix", "iy")}}
    return uncontrolled, goals


def _uncontrolled_cycles(params, env, step_s: float, dynamics, n_cycles: int):
    return uncontrolled_boundaries(params, jax.tree_util.tree_map(lambda x: x[:n_cycles], env), step_s, dynamics)


_uncontrolled_jit = jax.jit(_uncontrolled_cycles, static_argnames=("step_s", "dynamics", "n_cycles"),
                            compiler_options=compilation.ONE_SAMPLE_OPTIONS)


def flown_days(days: float) -> str:
    """``days`` as a run flies them: whole sidereal-day cycles, named when the rounding is more than 2 %."""
    n = cycle_count(days)
    flown = n * SIDEREAL_DAY_S / SECONDS_PER_DAY
    if abs(flown - days) <= 0.02 * days:
        return f"{days:g} days"
    return f"{days:g} days, flown as {n} sidereal-day cycle{'s' * (n != 1)} ({flown:.3f} days)"


def scenario_of(result):
    """The scenario of a single rollout's result; ``ValueError`` for a batch or a result without one."""
    if np.ndim(result.status) != 0:
        raise ValueError(f"a batch of {np.size(result.status)} rollouts (simulate_batch): save, summarise or plot "
                         f"one (geojax.simulate), or write a batch with geojax.run_sweep")
    if result.scenario is None:
        raise ValueError("scenario: this Result does not carry its scenario; make it with geojax.simulate")
    return result.scenario
