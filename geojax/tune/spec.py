"""The tuning file (``geojax tune TUNE.toml``): its keys, declared as ``Field``s, and its loading.

A tuning file names a scenario (any controller) and the scenario keys to tune; everything else has a default:

    scenario = "katz2025-discrete"      # a shipped name or a .toml path
    parameters = ["k_h", "k_e"]         # scenario keys with a tuning transform, by key or by alias:
                                        # "controller.k_h_per_km2_s" and "k_h" are the same parameter
    starts = 16                         # start 0 is the scenario's own values
    iterations = 40
    days = 365.25                       # the horizon each iterate is flown over (default: the scenario's)

Every key is declared in ``FIELDS`` with its default, its range and a line saying what it means; the
documentation's table of them (docs/feedback.md, "The tuning file") is generated from it.

A tuning shorter than ``MIN_HORIZON_DAYS`` or than the controller's prediction window warns
(``horizon_warning``): the yearly Delta-V it minimises is then not the year's.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from geojax import scenario as scenario_mod
from geojax.control.base import Controller
from geojax.runner.setup import controller_of, cycle_count
from geojax.params import REQUIRED, Field, check_table
from geojax.tune.space import resolve, tunable, tuned

_NUMBER = (int, float)

FIELDS = {
    "scenario": Field(str, REQUIRED, doc="the scenario tuned: a shipped name or a .toml path, any controller"),
    "parameters": Field(list, None, doc='the tuned scenario keys ("table.key") or their aliases, each with a tuning '
                                        "transform (unset: the controller's ``tuned_fields``)"),
    "starts": Field(int, 16, lower=1, upper=4097, lower_inclusive=True,
                    doc="starts optimised at once (start 0: the scenario's values; the others spread around them)"),
    "iterations": Field(int, 40, lower=0, upper=10001, lower_inclusive=True, doc="iterations of the optimiser"),
    "step_tolerance": Field(_NUMBER, 1e-4, lower=0.0, lower_inclusive=True,
                            doc="the SQP stops when every start's step is shorter (natural-log units)"),
    "method": Field(str, "sqp", choices=("sqp", "adam"),
                    doc="the optimiser (geojax.tune.sqp, geojax.tune.adam)"),
    "trust_radius": Field(_NUMBER, None, lower=0.0,
                          doc="the SQP's first trust radius (unset: 2 for a smooth law, 0.3 for a sampled-and-held "
                              "one)"),
    "trust_radius_min": Field(_NUMBER, None, lower=0.0,
                              doc="the SQP's smallest trust radius (unset: 1e-6 smooth, 0.02 sampled-and-held)"),
    "days": Field(_NUMBER, None, lower=0.0, upper=36526.0,
                  doc="the horizon in days (unset: the scenario's duration.days)"),
    "step_s": Field(_NUMBER, None, lower=0.0, upper=86401.0,
                    doc="the integration step in s (unset: the scenario's integration.step_s)"),
    "learning_rate": Field(_NUMBER, 0.1, lower=0.0,
                           doc="Adam's first learning rate (natural-log units per iteration)"),
    "learning_rate_end": Field(_NUMBER, 0.02, lower=0.0, doc="Adam's last learning rate (decayed geometrically)"),
    "momentum": Field(_NUMBER, 0.5, lower=0.0, upper=1.0, lower_inclusive=True, doc="Adam's b1"),
    "spread_decades": Field(_NUMBER, 0.3, lower=0.0, lower_inclusive=True,
                            doc="half-width of the starts' spread for keys tuned on a log scale, in decades"),
    "spread_scaled": Field(_NUMBER, 0.2, lower=0.0, lower_inclusive=True,
                           doc="half-width of the starts' spread for the other keys, in their transform's units"),
    "temperature_start": Field(_NUMBER, 0.1, lower=0.0,
                               doc="the surrogate's first temperature (annealed geometrically)"),
    "temperature_end": Field(_NUMBER, 0.03, lower=0.0, doc="the surrogate's last temperature"),
    "penalty_mps": Field(_NUMBER, 200.0, lower=0.0, doc="Adam's penalty weight on the box violation, m/s/yr"),
    "margin": Field(_NUMBER, None, lower=0.0, upper=1.0, lower_inclusive=True,
                    doc="how far inside the box to aim, in units of Delta_s^2 "
                        "(unset: 0 smooth, 0.01 sampled-and-held, 0.02 Adam)"),
    "seed": Field(int, 0, lower=0, lower_inclusive=True, doc="the seed of the starts' spread"),
    "gradient": Field(str, "forward", choices=("forward", "reverse"),
                      doc="forward-mode (no tape) or reverse-mode (checkpointed per day) derivatives"),
}

# Half a year, in days.  The figure a tuning minimises is the yearly Delta-V, extrapolated from its horizon, and
# the Sun drives the inclination (most of the Delta-V) with a half-year period: measured at the papers' gains over
# one year (katz2025-continuous clipped, katz2025-discrete, li2022-qffc), the yearly Delta-V extrapolated from the
# first 182 days is 2.7-4.5 % from the year's (within the studies' 5 % rule), from the first 91 days 3.8-15.8 %,
# from 28 days 17-27 %, from 10 days up to 92 %; from any 91-day window of the year up to 22 %.
MIN_HORIZON_DAYS = 182.6


@dataclasses.dataclass(frozen=True)
class TuneSpec:
    config: dict  # the validated tuning table, defaults filled in, ``parameters`` as scenario keys
    scenario: scenario_mod.Scenario
    text: str  # the tuning file, stored in the results
    controller: Controller | None = None  # a user's controller object (None: the one the scenario names)

    def __getattr__(self, name):
        try:
            return self.config[name]
        except KeyError:
            raise AttributeError(name) from None

    @property
    def days(self) -> float:
        """The horizon flown, days (the scenario's, after the file's ``days``)."""
        return float(self.scenario.config["duration"]["days"])


def load(path: str | Path, controller: Controller | None = None) -> TuneSpec:
    """Read and validate a tuning file; ``ValueError`` with one line naming the fault."""
    raw, text = scenario_mod.read_toml_file(Path(path), "tuning")
    return from_dict(raw, text, controller)


def from_dict(raw: dict, text: str = "", controller: Controller | None = None) -> TuneSpec:
    """A ``TuneSpec`` from a tuning table (``controller``: a user's controller object for the scenario; one named
    by import path in the scenario's ``controller.kind`` needs none)."""
    config = check_table("", raw, FIELDS)
    names = config["parameters"]
    if names is not None and (not names or not all(isinstance(n, str) for n in names) or len(set(names)) != len(names)):
        raise ValueError(f"parameters: must be a list of distinct scenario keys, got {names!r}")
    if None not in (config["trust_radius"], config["trust_radius_min"]) and \
            config["trust_radius_min"] > config["trust_radius"]:
        raise ValueError(f"trust_radius_min: must be <= trust_radius = {config['trust_radius']}, "
                         f"got {config['trust_radius_min']}")
    if config["temperature_end"] > config["temperature_start"]:
        raise ValueError(f"temperature_end: must be <= temperature_start = {config['temperature_start']}, "
                         f"got {config['temperature_end']}")
    overrides = {key: float(config[k]) for k, key in (("days", "duration.days"), ("step_s", "integration.step_s"))
                 if config[k] is not None}
    sc = scenario_mod.load(config["scenario"], overrides, controller)
    if names is None:
        names = [f"controller.{key}" for key in (controller or controller_of([sc])).spec.tuned_fields]
        if not names:
            raise ValueError(f"parameters: missing, and the controller of scenario {sc.name} declares no default "
                             f"(Spec.tuned_fields); tunable: {', '.join(tunable(sc, controller))}")
    config["parameters"] = resolve(sc, controller, names)
    tuned(sc, controller, config["parameters"])  # every name tunable and set
    if len(set(config["parameters"])) != len(names):
        raise ValueError(f"parameters: {names!r} names one key twice (a key and its alias)")
    return TuneSpec(config, sc, text, controller)


def horizon_warning(spec: TuneSpec) -> str | None:
    """Why the tuning's horizon is too short for the yearly Delta-V it minimises (one line), or None: shorter than
    ``MIN_HORIZON_DAYS``, or than the controller's prediction window (a plan would reach past the run's end)."""
    days = spec.days
    window_cycles = (spec.controller or controller_of([spec.scenario])).reference_cycles
    if days >= MIN_HORIZON_DAYS and cycle_count(days) >= window_cycles:
        return None
    why = (f"shorter than the controller's prediction window ({window_cycles} cycles)"
           if cycle_count(days) < window_cycles else
           f"under half a year ({MIN_HORIZON_DAYS} days), the period of the Sun's pull on the inclination; the yearly "
           f"Delta-V extrapolated from 91 days was measured up to 16 % from the year's, from 10 days up to 92 %")
    return f"days = {days:g}: the tuning horizon is {why}; the tuned values fit this horizon, not a year"
