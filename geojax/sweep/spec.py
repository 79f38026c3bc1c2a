"""The sweep file: its keys, the grid and each grid point's scenario (``geojax.sweep``'s format)."""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path

from geojax import lanes as lanes_mod, scenario as scenario_mod
from geojax.sweep import epochs as epoch_axis
from geojax.params import Field, check_table


MAX_SAMPLES = 10_000_000  # samples per sweep file (a larger campaign is several files, or a cluster)
DISPERSION_STREAM = 0x5EED  # the key stream of the initial-state dispersion, apart from the rollout's cycles
DISPERSION_FIELDS = {
    "mee_1sigma": Field(list, [0.0] * 6, length=6),
    "offset_ecef_1sigma_km": Field(list, [0.0] * 3, length=3),
}


@dataclasses.dataclass(frozen=True)
class Sweep:
    name: str
    scenario: str
    controllers: tuple[str, ...]
    repetitions: int
    seed: int
    fixed: dict
    grid: dict  # {path: [values]}, in axis order
    text: str  # the sweep file, stored in the results
    cycles: bool = False  # keep the per-cycle records (loop.metrics.CYCLE_NAMES)
    dispersion: dict = dataclasses.field(default_factory=lambda: {k: f.default for k, f in DISPERSION_FIELDS.items()})
    custom: dict = dataclasses.field(default_factory=dict)  # {name: Controller} of a user's own controllers
    lanes: int | None = None  # samples per device per compiled call; None: the platform's (``geojax.lanes``)
    parts: tuple = ()  # a user's own parts every sample carries (``StateModel`` s or ``Part`` s: ``load(states=)``)

    @property
    def dispersed(self) -> bool:
        return any(x != 0.0 for values in self.dispersion.values() for x in values)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.grid.values())

    @property
    def n_points(self) -> int:
        return math.prod(self.shape)


def load(path: str | Path, changes: dict | None = None, controllers: dict | None = None,
         states: dict | None = None) -> Sweep:
    """Read and validate a sweep file; ``ValueError`` with one line naming the fault.

    ``changes`` replaces top-level keys and adds to ``[set]`` (a study's quick
    run: ``{"repetitions": 2, "set": {"duration.days": 30}}``); the sweep then
    stores its changed text.  ``controllers`` ({name: Controller}) adds a user's own controllers, named
    in the file's ``controllers`` list like the registered ones; ``states`` ({name: StateModel or Part}) a user's
    own parts every sample carries (their metrics go to the file under their names).
    """
    from geojax.control import REGISTRY, lookup

    path = Path(path)
    controllers_arg = controllers
    raw, text = scenario_mod.read_toml_file(path, "sweep")
    if changes:
        raw = {**raw, **changes, "set": {**raw.get("set", {}), **changes.get("set", {})}}
        text = scenario_mod.to_toml(raw)
    allowed = {"name", "scenario", "controllers", "repetitions", "seed", "set", "grid", "cycles", "dispersion",
               "lanes"}
    unknown = sorted(set(raw) - allowed)
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown key; allowed: {', '.join(sorted(allowed))}")
    if "scenario" not in raw:
        raise ValueError("scenario: missing (the base scenario, a shipped name or a .toml path)")
    if not isinstance(raw.get("name", ""), str) or not isinstance(raw["scenario"], str):
        key = "name" if not isinstance(raw.get("name", ""), str) else "scenario"
        raise ValueError(f"{key}: must be a string, got {raw[key]!r}")
    controllers = raw.get("controllers", ["qffc"])
    known = {**REGISTRY, **(controllers_extra := dict(controllers_arg or {}))}
    if not (isinstance(controllers, list) and controllers
            and all(isinstance(c, str) and (c in known or ":" in c) for c in controllers)
            and len(set(controllers)) == len(controllers)):
        raise ValueError(f"controllers: must be a non-empty list of distinct names from {', '.join(known)} or "
                         f"controllers of one's own as 'package.module:NAME', got {controllers!r}")
    for name in controllers:
        if name not in known:
            try:
                lookup(name)
            except ValueError as err:
                raise ValueError(f"controllers: {str(err).removeprefix('controller.kind: ')}") from None
    reps, seed = raw.get("repetitions", 1), raw.get("seed", 0)
    if not (isinstance(reps, int) and not isinstance(reps, bool) and 1 <= reps <= MAX_SAMPLES):
        raise ValueError(f"repetitions: must be an integer from 1 to {MAX_SAMPLES}, got {reps!r}")
    if not (isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise ValueError(f"seed: must be an integer >= 0, got {seed!r}")
    lanes = lanes_mod.checked(raw.get("lanes"))
    if not isinstance(raw.get("cycles", False), bool):
        raise ValueError(f"cycles: must be true or false, got {raw['cycles']!r}")
    grid = raw.get("grid", {})  # none: a Monte Carlo over the repetitions alone, metrics [controller, repetition]
    if not isinstance(grid, dict):
        raise ValueError(f"grid: must be a table of parameters, e.g. \"thrusters.beta_max_deg\" = [60, 70], got {grid!r}")
    fixed = raw.get("set", {})
    if not isinstance(fixed, dict):
        raise ValueError(f"set: must be a table of scenario keys, e.g. \"duration.days\" = 30, got {fixed!r}")
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ValueError(f"grid.{key}: must be a non-empty list of values, got {values!r}")
        if key == epoch_axis.KEY:
            epoch_axis.check_values(values)
            continue
        for value in values:
            if not isinstance(value, (int, float, bool)):
                raise ValueError(f"grid.{key}: must be a list of numbers (or true/false), got {value!r}")
    n_samples = math.prod(len(v) for v in grid.values()) * reps * len(controllers)
    if n_samples > MAX_SAMPLES:
        raise ValueError(f"grid: {n_samples} samples in all, more than {MAX_SAMPLES}; split the sweep")
    dispersion = check_table("dispersion.", raw.get("dispersion", {}), DISPERSION_FIELDS)
    sweep = Sweep(str(raw.get("name", path.stem)), str(raw["scenario"]), tuple(controllers), reps, seed, dict(fixed),
                  {k: list(v) for k, v in grid.items()}, text, raw.get("cycles", False), dispersion,
                  {k: v for k, v in controllers_extra.items() if k in controllers}, lanes, _own_parts(states))
    for controller in sweep.controllers:  # every value within its range, every batch compilable
        prepare_check(sweep, controller)
    return sweep


def _own_parts(states: dict | None) -> tuple:
    """The parts of ``load(states=)``, each under its own name (``ValueError`` naming a mismatch)."""
    from geojax.states.base import part_of

    out = []
    for name, entry in (states or {}).items():
        try:
            part = part_of(entry)
        except TypeError as err:
            raise ValueError(f"states[{name!r}]: {err}") from None
        if part.name != name:
            raise ValueError(f"states[{name!r}]: the part is named {part.name!r}; give it under its own name")
        out.append(entry)
    return tuple(out)


def prepare_check(sweep: Sweep, controller: str) -> None:
    """Load every grid point's scenario (the ranges and checks of ``geojax.scenario``) and check that they
    differ only in array leaves (``runner.setup``), naming the grid key at fault."""
    from geojax.runner.setup import _check_static, controller_of

    points = list(_points(sweep))
    scenarios = [_scenario(sweep, controller, p) for p in points]
    ctrl = sweep.custom.get(controller) or controller_of(scenarios)
    groups = epoch_axis.groups(points)
    try:
        for group in groups:  # within an epoch, as every sweep
            _check_static([scenarios[i] for i in group], ctrl)
        _check_static([scenarios[g[0]] for g in groups], ctrl, skip=epoch_axis.STATIC_KEYS)  # and between them
    except ValueError as err:
        raise ValueError(f"grid.{err}") from None


def _points(sweep: Sweep):
    keys = list(sweep.grid)
    for values in itertools.product(*sweep.grid.values()):
        yield dict(zip(keys, values, strict=True))


def _scenario(sweep: Sweep, controller: str, point: dict):
    overrides = {**sweep.fixed, **point, "controller.kind": controller}
    if isinstance(point.get("controller.vdt_estimate"), (int, float)):
        overrides["controller.vdt_estimate"] = bool(point["controller.vdt_estimate"])  # 0 / 1 on a numeric axis
    if epoch_axis.KEY in point:
        return epoch_axis.scenario_at(sweep.scenario, overrides.pop(epoch_axis.KEY), overrides,
                                      sweep.custom.get(controller))
    return scenario_mod.load(sweep.scenario, overrides, sweep.custom.get(controller))
