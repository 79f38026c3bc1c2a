"""What a tuning leaves behind: its HDF5 file, the tuned scenario beside it, and its convergence figure.

The file (``geojax tune --out FILE.h5``): ``/iterations/<name>`` [iteration, start] (``theta`` [iteration,
start, parameter], ``constraint`` [iteration, start, box_axis], ``temperature``, ``best_dv_per_year_mps`` and
``wall_s`` [iteration]), ``/starts/theta`` [start, parameter], and, once a feasible point is found, ``/best``
(the controller's keys in their TOML units, and ``theta``) and ``/metrics`` (``dv_per_year_mps``,
``constraint_lon``, ``constraint_lat``, and ``constraint_wheels`` where the scenario carries the wheels: the
capacity's constraint, the third along ``box_axis``); attributes ``kind = "tune"``, ``scenario``, ``parameters``
(the tuned keys), ``status``, ``tune_toml``, ``controller``, ``constraints`` (the names along ``box_axis``).  The tuned scenario, ``FILE-tuned.toml``, is the tuning's
scenario with each tuned key at its best value; ``geojax simulate FILE-tuned.toml`` runs it.
"""

from __future__ import annotations

import copy
import textwrap
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from geojax import scenario as scenario_mod, store
from geojax.params import Params
from geojax.tune.space import reported, reported_entries, toml_value, tuned

# Axis names of a tuning file's datasets (geojax.results).
TUNE_DIMS = {"iterations": ("iteration", "start"), "iterations/theta": ("iteration", "start", "parameter"),
             "iterations/constraint": ("iteration", "start", "box_axis"),
             **{f"iterations/{k}": ("iteration",) for k in ("temperature", "best_dv_per_year_mps", "wall_s")},
             "starts": ("start", "parameter"), "best/theta": ("parameter",)}


def write(out, spec, problem, hist, theta_starts, best, message: str, wall_s: float) -> None:
    """Write the tuning's HDF5 file (atomically) and, once it has ended with a feasible point, the tuned scenario."""
    groups, attrs = contents(spec, problem, hist, theta_starts, best, message)
    store.write_h5(out, groups, scenario_mod.to_toml(spec.scenario.config), wall_s, attrs=attrs, dims=TUNE_DIMS)
    if best["theta"] is not None and message != "running":
        params = problem.params(jnp.asarray(best["theta"]))
        store.atomic_write(tuned_scenario_path(out), tuned_scenario_toml(spec, params, best["dv"]).encode())


def contents(spec, problem, hist, theta_starts, best, message: str) -> tuple[dict, dict]:
    """(groups, attributes) of the tuning's file: the iterations so far, the starts, and the best point found."""
    groups = {"iterations": {k: np.stack(v) for k, v in hist.items()}, "starts": {"theta": np.asarray(theta_starts)}}
    groups["iterations"]["active"] = groups["iterations"]["active"].astype(np.int8)
    if best["theta"] is not None:
        params = problem.params(jnp.asarray(best["theta"]))
        controller_fields = scenario_mod.controller_fields(spec.scenario.config["controller"], spec.controller)
        groups["best"] = {**reported(params, controller_fields), **reported_entries(params, problem.entries),
                          "theta": best["theta"]}
        groups["metrics"] = {"dv_per_year_mps": best["dv"], **{f"constraint_{name}": value for name, value in
                                                                zip(problem.constraint_names, best["g"], strict=True)}}
    attrs = {"kind": "tune", "scenario": spec.scenario.name, "parameters": ",".join(spec.parameters),
             "status": message, "tune_toml": spec.text,
             "controller": spec.scenario.controller, "constraints": ",".join(problem.constraint_names)}
    return groups, attrs


def save(result, path) -> Path:
    """Write the file ``geojax tune --out`` writes (and, where a point kept the box, the tuned scenario beside it,
    ``tuned_scenario_path``); returns the file's path."""
    spec, problem = _made_by_tune(result)
    write(path, spec, problem, result.history, result.starts, _best(result), result.message, result.wall_s)
    return Path(path)


def report_md(path, lines: list[str], result) -> str:
    """Write a study's Markdown report of a tuning to ``path``: ``lines`` (its title, command and table), then what
    ``geojax tune`` printed (``summary``) in a code block; returns the text."""
    text = "\n".join([*lines, "", "What `geojax tune` printed:", "", "```", *summary(result), "```", ""])
    Path(path).write_text(text)
    return text


def summary(result) -> list[str]:
    """What ``geojax tune`` prints after the run: how it ended, and the best point's values and Delta-V."""
    spec, problem = _made_by_tune(result)
    lines = [f"{spec.scenario.name}: {result.message}; {result.wall_s:.1f} s wall"]
    if result.best_params is None:
        return lines + ["  no feasible point: every iterate left the box with the exact law"]
    fields = scenario_mod.controller_fields(spec.scenario.config["controller"], spec.controller)
    lines += [f"  {name:24s} {value:.6g}" for name, value in reported(result.best_params, fields).items()]
    lines += [f"  {name:24s} {value:.6g}" for name, value in reported_entries(result.best_params, problem.entries).items()]
    box_deg = spec.scenario.config["station"]["box_half_width_deg"]
    g = result.best_constraint
    lon_deg, lat_deg = excursion_deg(g[:2], box_deg)
    lines += [f"  ΔV (exact law, full horizon)  {result.best_dv_per_year_mps:.3f} m/s/yr, box kept: largest "
              f"|δλ| {lon_deg:.4f}°, |δφ| {lat_deg:.4f}° of ±{box_deg:g}° "
              f"(constraints (excursion / box)² - 1: lon {g[0]:+.4f}, lat {g[1]:+.4f})"]
    if len(g) > 2:
        capacity = spec.scenario.config["attitude"]["wheel_capacity_nms"]
        lines.append(f"  wheels kept: largest |h| {capacity * np.sqrt(max(g[2] + 1.0, 0.0)):.2f} of {capacity:g} N m s "
                     f"(constraint (|h| / capacity)² - 1: {g[2]:+.4f})")
    return lines


def excursion_deg(constraint, box_half_width_deg: float):
    """The largest excursions (deg) that the box constraints ``constraint`` [..., 2] (lon, lat; (excursion /
    box)² - 1, ``tune.objective``) stand for."""
    return box_half_width_deg * np.sqrt(np.maximum(np.asarray(constraint, float) + 1.0, 0.0)).T


def plot(result, folder) -> list[Path]:
    """The convergence figure ``geojax plot`` draws of the tuning's file, ``FOLDER/NAME-convergence.png``;
    returns its path in a list."""
    spec, problem = _made_by_tune(result)
    groups, attrs = contents(spec, problem, result.history, result.starts, _best(result), result.message)
    attrs["config_toml"] = scenario_mod.to_toml(spec.scenario.config)
    return [figure(groups, attrs, Path(folder) / f"{spec.scenario.name}-convergence.png")]


def _best(result) -> dict:
    return {"theta": result.best_theta, "dv": result.best_dv_per_year_mps, "g": result.best_constraint}


def _made_by_tune(result):
    if result.spec is None or result.problem is None:
        raise ValueError("spec: this TuneResult does not carry its tuning; make it with geojax.tune.tune")
    return result.spec, result.problem


def tuned_scenario_path(out) -> Path:
    """Where ``geojax tune --out FILE.h5`` writes the tuned scenario: ``FILE-tuned.toml`` beside it."""
    out = Path(out)
    return out.with_name(f"{out.stem}-tuned.toml")


def tuned_config(spec, params: Params, dv_per_year_mps: float | None = None) -> dict:
    """The tuning's scenario table with each tuned key set to its value in ``params``, in the key's own unit, and
    a description that says what was tuned, on which scenario, over how long and (given) to what Delta-V."""
    config = copy.deepcopy(spec.scenario.config)
    for entry in tuned(spec.scenario, spec.controller, spec.parameters):
        leaf = entry.leaves_in(params)[entry.field.si]
        config[entry.table][entry.name.rpartition(".")[2]] = toml_value(entry.field, leaf)
    outcome = "" if dv_per_year_mps is None else \
        f": {dv_per_year_mps:.3f} m/s/yr of Delta-V per year with the exact law, box kept"
    config["description"] = (f"{', '.join(spec.parameters)} tuned by geojax tune ({spec.method}, {spec.starts} starts, "
                             f"{spec.iterations} iterations) on scenario {spec.scenario.name} over {spec.days:g} days"
                             f"{outcome}")
    config["name"] = f"{spec.scenario.name}-tuned"
    return config


def tuned_scenario_fault(spec, params: Params) -> str | None:
    """Why ``geojax simulate`` would refuse the tuned scenario (one line), or None.

    The descent moves each tuned key within its own bounds, but a scenario's load checks also tie keys
    together (Ye 2022 eq. (41): a t_max whose burn beats the largest daily drift at the thrust), so a tuned
    thrust or burn limit can leave them."""
    try:  # read back from the TOML that is written, as ``geojax simulate`` reads it
        scenario_mod.from_dict(scenario_mod.tomllib.loads(scenario_mod.to_toml(tuned_config(spec, params))),
                               spec.controller)
    except ValueError as error:
        return str(error)
    return None


def tuned_scenario_toml(spec, params: Params, dv_per_year_mps: float | None = None) -> str:
    """The tuned scenario as TOML (``geojax simulate FILE-tuned.toml`` runs it): the tuning's scenario with
    each tuned key set to its best value, in the key's own unit (``tuned_config``)."""
    header = (f"# {spec.scenario.name} with {', '.join(spec.parameters)} tuned by geojax tune;\n"
              f"# run it with: geojax simulate THIS_FILE\n")
    return header + scenario_mod.to_toml(tuned_config(spec, params, dv_per_year_mps))


def figure(groups: dict, attrs: dict, path, dpi: int = 150) -> Path:
    """The convergence figure of a tuning file (``plots.plot_tuning``), titled by what was tuned (the names as
    the tuning file wrote them), on which scenario and over how long, with the best point's tuned values named
    and in their units as their ``Field``s declare them (``plots.label_for``)."""
    from geojax import plots

    config = scenario_mod.tomllib.loads(str(attrs.get("config_toml", "")))
    keys = [k for k in str(attrs.get("parameters", "")).split(",") if k]
    written = scenario_mod.tomllib.loads(str(attrs.get("tune_toml", ""))).get("parameters") or keys
    days = config.get("duration", {}).get("days")
    title = f"{attrs.get('scenario', '')}{f', {days:g} days' if days else ''}: tuning {', '.join(written)}"
    best = groups.get("best") or {}
    controllers = (config.get("controller", {}).get("kind", "none"),)
    values = [f"{plots.label_for(key, controllers)} = {float(best[key.rpartition('.')[2]]):.4g}" for key in keys
              if key.startswith("controller.") and key.rpartition(".")[2] in best]  # /best: the controller's scalars
    return plots.plot_tuning(groups, path, title=textwrap.fill(title, 70), dpi=dpi, best_values=values)
