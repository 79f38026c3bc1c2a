"""Gain tuning through differentiable rollouts (Katz 2025, eqs. (8)-(16)): ``geojax tune TUNE.toml``.

Minimise the yearly Delta-V of a scenario, with any controller, subject to the
box |lambda - lambda_d| <= Delta_s, |latitude| <= Delta_s, by Adam (optax) on
gradients of the whole rollout, from many starts at once (``vmap``; Katz reports
a strong sensitivity to the initial guess).  A tuning file:

    scenario = "katz2025-discrete"      # shipped name or .toml path, any controller
    parameters = ["k_h", "k_e"]         # scenario keys with a tuning transform, e.g. "controller.k_h_per_km2_s",
                                        # "thrusters.thrust_n"; k_h, k_e, k_lambda, lambda_b, sigma name Katz's gains
    starts = 16                         # start 0 is the scenario's own gains
    iterations = 40
    # optional: method ("sqp" or "adam"), days, step_s, spread_decades, spread_lambda_b_deg, temperature_start,
    # temperature_end, margin, seed, gradient ("forward" or "reverse"); for "sqp": trust_radius,
    # trust_radius_min, step_tolerance; for "adam": learning_rate, learning_rate_end, momentum, penalty_mps

Parameters live in an unconstrained space given by each key's declared
transform (``params.Field.transform``): the natural log of positive gains
(k_h, k_e, k_lambda), lambda_b / 0.1 deg, and for the discrete thresholds
three log-weights s with sigma = u0 exp(s) / |exp(s)|, so |sigma| = u0 holds
by construction.  The box is Katz's eq. (10) normalised: one
constraint per axis, g = max(excursion^2) / Delta_s^2 - 1 <= 0.  The
discontinuous thrust laws are differentiated through their sigmoid surrogates
at a temperature annealed geometrically from ``temperature_start`` to
``temperature_end`` (``thrust_laws``); every iterate of every start is also
evaluated with the *exact* law over the full horizon, and the result is the
iterate of least exact Delta-V whose exact rollout keeps the box.

Two methods, both on all starts at once:

- ``"sqp"`` (default): a trust-region sequential quadratic programme.  One
  forward-mode pass gives the whole Jacobian of (Delta-V, g_lon, g_lat) with
  respect to the parameters; each start then solves a small QP (the
  linearised box tightened by ``margin``, elastic when it cannot be met, a
  damped-BFGS model of the Lagrangian's curvature that starts from one
  curvature fitted to all the starts' gradients, an infinity-norm trust
  region) and the step is accepted on the *exact* law: while outside the box,
  when the violation shrinks; inside it, when the box is kept and Delta-V
  falls.  A rejected step halves the trust region (down to
  ``trust_radius_min``: 0.02 for the sampled-and-held laws, about the scale
  below which they are noise, and where a refused start probes a random
  neighbour instead of proposing the same step again; 1e-6 for the smooth
  law); the run stops early when every step is shorter than
  ``step_tolerance``.  Constraint Jacobians are what a penalty cannot
  give: a start walks along the edge of the box instead of bouncing off it.
- ``"adam"``: optax Adam on the surrogate Delta-V plus ``penalty_mps`` times
  the violation of the box tightened by ``margin`` (the first-order method,
  kept for comparison and for many-parameter problems).

A start whose values or derivatives are not finite stops (its best feasible
point is kept); when every start has stopped the run ends with a message.

Gradients are forward-mode by default (``jacfwd``: no tape, so memory does not
grow with the horizon; for 2-7 parameters about twice as fast as reverse mode
on a CPU); ``gradient = "reverse"`` takes them through ``jax.checkpoint`` on
each day (``feedback.rollout``), so memory grows with days, not steps.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import sys
import time
from pathlib import Path
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax
from scipy.optimize import minimize

from geojax import scenario as scenario_mod, store
from geojax.control import lyapunov
from geojax.control.base import Controller
from geojax.loop.metrics import STATUS_LEFT_LAT_BOX, STATUS_LEFT_LON_BOX, STATUS_NONFINITE
from geojax.loop.rollout import rollout_fn
from geojax.loop.setup import prepare, unstack
from geojax.parallel import shard_batch
from geojax.params import LEAF_TABLES, REQUIRED, Field, Params, check_table, degrees


# Katz 2025, Table 1 and Secs. 3.1-3.3, per thrust mode ("+-" excursions as the paper states them).
PAPER = {
    "continuous": {"dv_per_year_mps": "62.795", "dlon_half_range_deg": "0.0083", "dlat_half_range_deg": "0.047",
                   "k_h_per_km2_s": "9.3926e-16", "k_e_km2_per_s3": "5.48482e-6"},
    "discrete": {"dv_per_year_mps": "55.55", "dlon_half_range_deg": "0.0176", "dlat_half_range_deg": "0.0436",
                 "duty_x": "0", "duty_y": "0.115", "duty_z": "0.466",
                 "k_h_per_km2_s": "1.6407e-15", "k_e_km2_per_s3": "6.8936e-6"},
    "constant": {"dv_per_year_mps": "56.088", "dlon_half_range_deg": "0.0437", "dlat_half_range_deg": "0.0288",
                 "duty_x": "0.467", "duty_y": "0.467", "duty_z": "0.467",
                 "k_h_per_km2_s": "2.7147e-15", "k_e_km2_per_s3": "1.043e-5"},
}

# Short names of Katz 2025's gains (tuning files before parameters were scenario keys).
ALIASES = {"k_h": "controller.k_h_per_km2_s", "k_e": "controller.k_e_km2_per_s3",
           "k_lambda": "controller.k_lambda_km_per_rad", "lambda_b": "controller.lambda_b_deg",
           "sigma": "controller.sigma_km_per_s2"}
# Iterates are kept within this many natural-log units of their start (about 3 decades).
LOG_BOUND = 3 * math.log(10)

FIELDS = {
    "scenario": Field(str, REQUIRED),
    "parameters": Field(list, ["k_h", "k_e"]),
    "starts": Field(int, 16, lower=1, upper=4097, lower_inclusive=True),
    "iterations": Field(int, 40, lower=0, upper=10001, lower_inclusive=True),
    "step_tolerance": Field((int, float), 1e-4, lower=0.0, lower_inclusive=True),
    "method": Field(str, "sqp", choices=("sqp", "adam")),
    "trust_radius": Field((int, float), None, lower=0.0),
    "trust_radius_min": Field((int, float), None, lower=0.0),
    "days": Field((int, float), None, lower=0.0, upper=36526.0),
    "step_s": Field((int, float), None, lower=0.0, upper=86401.0),
    "learning_rate": Field((int, float), 0.1, lower=0.0),
    "learning_rate_end": Field((int, float), 0.02, lower=0.0),
    "momentum": Field((int, float), 0.5, lower=0.0, upper=1.0, lower_inclusive=True),
    "spread_decades": Field((int, float), 0.3, lower=0.0, lower_inclusive=True),
    # Half-width of the starts' spread for keys tuned on a linear scale, in that scale's units
    # (lambda_b: 0.1 deg, so 0.2 is +-0.02 deg); spread_lambda_b_deg sets it in degrees of lambda_b.
    "spread_scaled": Field((int, float), 0.2, lower=0.0, lower_inclusive=True),
    "spread_lambda_b_deg": Field((int, float), None, lower=0.0, lower_inclusive=True),
    "temperature_start": Field((int, float), 0.1, lower=0.0),
    "temperature_end": Field((int, float), 0.03, lower=0.0),
    "penalty_mps": Field((int, float), 200.0, lower=0.0),
    "margin": Field((int, float), None, lower=0.0, upper=1.0, lower_inclusive=True),
    "seed": Field(int, 0, lower=0, lower_inclusive=True),
    "gradient": Field(str, "forward", choices=("forward", "reverse")),
}


@dataclasses.dataclass(frozen=True)
class TuneSpec:
    config: dict  # the validated tuning table, defaults filled in
    scenario: scenario_mod.Scenario
    text: str  # the tuning file, stored in the results
    controller: Controller | None = None  # a user's controller (None: the scenario's registered one)

    def __getattr__(self, name):
        try:
            return self.config[name]
        except KeyError:
            raise AttributeError(name) from None


def load(path: str | Path, controller: Controller | None = None) -> TuneSpec:
    """Read and validate a tuning file; ``ValueError`` with one line naming the fault."""
    path = Path(path)
    raw, text = scenario_mod.read_toml_file(path, "tuning")
    return from_dict(raw, text, controller)


def from_dict(raw: dict, text: str = "", controller: Controller | None = None) -> TuneSpec:
    """A ``TuneSpec`` from a tuning table (``controller``: a user's controller for the scenario)."""
    config = check_table("", raw, FIELDS)
    names = config["parameters"]
    if not names or not all(isinstance(n, str) for n in names) or len(set(names)) != len(names):
        raise ValueError(f"parameters: must be a list of distinct scenario keys, got {names!r}")
    config["parameters"] = [ALIASES.get(n, n) for n in names]
    if None not in (config["trust_radius"], config["trust_radius_min"]) and \
            config["trust_radius_min"] > config["trust_radius"]:
        raise ValueError(f"trust_radius_min: must be <= trust_radius = {config['trust_radius']}, "
                         f"got {config['trust_radius_min']}")
    if config["temperature_end"] > config["temperature_start"]:
        raise ValueError(f"temperature_end: must be <= temperature_start = {config['temperature_start']}, "
                         f"got {config['temperature_end']}")
    if config["spread_lambda_b_deg"] is not None:
        config["spread_scaled"] = config["spread_lambda_b_deg"] / math.degrees(lyapunov.LAMBDA_B_SCALE_RAD)
    overrides = {k: config[k] for k in ("days", "step_s") if config[k] is not None}
    overrides = {("duration." if k == "days" else "integration.") + k: float(v) for k, v in overrides.items()}
    sc = scenario_mod.load(config["scenario"], overrides, controller)
    tuned(sc, controller, config["parameters"])  # every name tunable and set
    return TuneSpec(config, sc, text, controller)


# ---------------------------------------------------------------- parameter space


class Tuned(NamedTuple):
    """A tuned scenario key: its ``Params`` table, its field and its TOML name."""

    name: str  # "controller.k_h_per_km2_s"
    table: str
    field: Field


def tuned(sc: scenario_mod.Scenario, controller: Controller | None, names) -> list[Tuned]:
    """The declarations of the tuned keys; ``ValueError`` for a key that is not tunable or not set."""
    fields = _fields(sc, controller)
    tunable = [f"{t}.{k}" for t, table in fields.items() for k, f in table.items() if f.transform is not None]
    out = []
    for name in names:
        table, _, key = name.rpartition(".")
        field = fields.get(table, {}).get(key)
        if field is None or field.transform is None:
            raise ValueError(f"parameters: {name!r} is not tunable here; tunable: {', '.join(tunable)}")
        if sc.config[table].get(key) is None:
            raise ValueError(f"parameters: {name!r} is not set in scenario {sc.name} (it is not used there)")
        out.append(Tuned(name, table, field))
    return out


def _fields(sc, controller) -> dict:
    fields = {t: scenario_mod.SCHEMA[t] for t in LEAF_TABLES if t != "controller"}
    fields["controller"] = controller.fields if controller is not None else \
        scenario_mod.controller_fields(sc.config["controller"])
    return fields


def _leaves(params: Params, table: str) -> dict:
    return getattr(params, table)


def to_theta(params: Params, entries: list[Tuned]) -> np.ndarray:
    """The unconstrained vector of the tuned leaves (each by its declared transform)."""
    parts = []
    for e in entries:
        leaves = {k: np.asarray(v) for k, v in _leaves(params, e.table).items()}
        parts.append(np.atleast_1d(e.field.transform.to_theta(leaves[e.field.si], leaves)))
    return np.concatenate(parts).astype(float)


def from_theta(theta, base: Params, entries: list[Tuned]) -> Params:
    """``base`` with the tuned leaves replaced by those of ``theta`` (jax-traceable)."""
    tables = {t: dict(_leaves(base, t)) for t in LEAF_TABLES}
    i = 0
    for e in entries:
        leaves = tables[e.table]
        size = int(np.size(leaves[e.field.si]))
        value = e.field.transform.from_theta(theta[i:i + size] if np.ndim(leaves[e.field.si]) else theta[i], leaves)
        leaves[e.field.si] = value
        i += size
    return base._replace(**tables)


def reported(params: Params, entries_or_fields) -> dict[str, float]:
    """Values of the controller's keys in their TOML units (list keys by component: ``_x``, ``_y``, ``_z``)."""
    out = {}
    for key, field in entries_or_fields.items():
        if field.si is None or field.si not in params.controller or callable(field.to_si):
            if field.si in params.controller and key.endswith("_deg"):
                out[key] = math.degrees(float(params.controller[field.si]))
            continue
        value = field.from_si(params.controller[field.si])
        if isinstance(value, list):
            stem, _, unit = key.partition("_km") if "_km" in key else (key, "", "")
            for axis, x in zip("xyz", value):
                out[f"{stem}_{axis}{'_km' + unit if unit else ''}"] = x
        else:
            out[key] = value
    return out


def paper_units(params: Params, controller_fields=None) -> dict[str, float]:
    """The controller's gains (and thresholds) in the scenario's (the paper's) units, for reports."""
    return reported(params, controller_fields if controller_fields is not None else lyapunov.FIELDS)


def start_points(spec: TuneSpec, center: np.ndarray, entries: list[Tuned], sizes: list[int]) -> np.ndarray:
    """[starts, P]: start 0 at ``center`` (the scenario's values), the rest uniform around it (``spread_decades``
    for the keys tuned on a log scale, ``spread_scaled`` for the others)."""
    rng = np.random.default_rng(spec.seed)
    half = np.concatenate([
        [spec.spread_decades * math.log(10) if e.field.transform.name.startswith("log") else spec.spread_scaled] * n
        for e, n in zip(entries, sizes)
    ])
    starts = center + rng.uniform(-1.0, 1.0, (spec.starts, center.size)) * half
    starts[0] = center
    return starts


# ---------------------------------------------------------------- objective


class Problem:
    """The tuning problem of one scenario: batched exact evaluation and surrogate gradients, compiled once."""

    def __init__(self, sc: scenario_mod.Scenario, names, penalty_mps: float = 200.0, margin: float = 0.02,
                 gradient: str = "forward", controller: Controller | None = None, lanes: int = 1):
        """``lanes``: starts evaluated per device (the rollout is compiled for it)."""
        self.batch = prepare([sc], controller)
        self.base = unstack(self.batch.params, 0)
        self.entries = tuned(sc, controller, names)
        self.names = tuple(names)
        self.sizes = [int(np.size(getattr(self.base, e.table)[e.field.si])) for e in self.entries]
        self.box_half_width_rad = float(self.base.station["box_half_width_rad"])
        self._rollouts = {False: rollout_fn(self.batch, lanes=lanes),
                          True: rollout_fn(self.batch, controller=self.batch.controller.surrogate or self.batch.controller,
                                           lanes=lanes)}
        self.penalty_mps, self.margin = penalty_mps, margin
        self._exact = jax.jit(jax.vmap(lambda th: self.evaluate(th, smooth=False)[1]))
        self._single = jax.jit(lambda th: self.evaluate(th, smooth=False)[1])
        self._grad = jax.jit(jax.vmap(_value_and_grad(self.evaluate, gradient), in_axes=(0, None)))
        self._jacobian = jax.jit(jax.vmap(_jacobian(self.evaluate, gradient), in_axes=(0, None)))

    @property
    def exact_is_smooth(self) -> bool:
        """A controller without a surrogate (the clipped continuous law) is smooth: its gradient run already is
        the exact evaluation."""
        return self.batch.controller.surrogate is None

    @property
    def days(self) -> int:
        return self.batch.n_cycles

    def params(self, theta) -> Params:
        return from_theta(theta, self.base, self.entries)

    def evaluate(self, theta, smooth: bool, temperature=0.05):
        """(loss, (dv_per_year_mps, constraint [2] lon/lat, box_ok)) of one parameter vector."""
        params = self.params(theta)
        if "temperature" in params.controller:
            params = params._replace(controller={**params.controller, "temperature": jnp.asarray(temperature)})
        _, _, m = self._rollouts[smooth](params, jax.random.key(0))
        excursion = jnp.radians(jnp.stack([m["max_abs_dlon_deg"], m["max_abs_dlat_deg"]]))
        # Katz eq. (10): delta^2 - Delta_s^2 <= 0, (lambda - lambda_d)^2 - Delta_s^2 <= 0, normalised.
        constraint = (excursion / self.box_half_width_rad) ** 2 - 1.0
        loss = m["dv_per_year_mps"] + self.penalty_mps * jnp.sum(jax.nn.relu(constraint + self.margin))
        box_ok = ~jnp.isin(m["status"], jnp.array([STATUS_LEFT_LON_BOX, STATUS_LEFT_LAT_BOX, STATUS_NONFINITE]))
        return loss, (m["dv_per_year_mps"], constraint, box_ok.astype(float))

    def exact(self, thetas):
        """Exact-law (dv_per_year_mps [n], constraint [n, 2], box_ok [n]) of a batch of parameter vectors."""
        return self._exact(_spread(thetas))

    def exact_one(self, theta):
        return self._single(jnp.asarray(theta))

    def surrogate_grad(self, thetas, temperature):
        (loss, aux), grad = self._grad(_spread(thetas), jnp.asarray(temperature))
        return loss, aux, grad

    def linearise(self, thetas, temperature):
        """Exact (dv [n], constraint [n, 2], box_ok [n]) and the surrogate's Jacobian [n, 3, P] of
        (dv, constraint_lon, constraint_lat); one pass when the exact law is itself smooth."""
        jac, aux = self._jacobian(_spread(thetas), jnp.asarray(temperature))
        exact = aux if self.exact_is_smooth else self.exact(thetas)
        return (*(np.array(v) for v in exact), np.array(jac))


def _value_and_grad(evaluate, gradient: str):
    """(loss, aux), d loss / d theta of the surrogate rollout.

    "forward": forward-mode (``jacfwd``), P tangents carried through one pass: no tape at all, so memory does
    not grow with the horizon, and for the few parameters tuned here (2 to 7) it is about twice as fast as
    reverse mode on a CPU.  "reverse": ``value_and_grad`` through the day-checkpointed rollout (memory grows
    with the number of days only), the choice when many parameters are tuned.
    """
    def surrogate(theta, temperature):
        loss, aux = evaluate(theta, smooth=True, temperature=temperature)
        return loss, (loss, aux)

    if gradient == "forward":
        def forward(theta, temperature):
            grad, (loss, aux) = jax.jacfwd(surrogate, has_aux=True)(theta, temperature)
            return (loss, aux), grad
        return forward
    if gradient == "reverse":
        return jax.value_and_grad(lambda th, t: evaluate(th, smooth=True, temperature=t), has_aux=True)
    raise ValueError(f"gradient: must be 'forward' or 'reverse', got {gradient!r}")


def _jacobian(evaluate, gradient: str):
    """theta -> (d(dv, g_lon, g_lat)/d theta [3, P], (dv, g, box_ok)) of the surrogate rollout, in one pass
    (forward mode: P tangents; reverse: three cotangents through the checkpointed rollout)."""
    def outputs(theta, temperature):
        _, (dv, g, ok) = evaluate(theta, smooth=True, temperature=temperature)
        return jnp.concatenate([dv[None], g]), (dv, g, ok)

    if gradient == "forward":
        return jax.jacfwd(outputs, has_aux=True)
    if gradient == "reverse":
        return jax.jacrev(outputs, has_aux=True)
    raise ValueError(f"gradient: must be 'forward' or 'reverse', got {gradient!r}")


def _spread(thetas):
    """The batch of starts, sharded over the local devices when it divides evenly (``geojax.parallel``)."""
    thetas = jnp.asarray(thetas)
    if jax.device_count() > 1 and thetas.shape[0] % jax.device_count() == 0:
        return shard_batch(thetas)
    return thetas


# ---------------------------------------------------------------- the optimiser


@dataclasses.dataclass
class TuneResult:
    best_theta: np.ndarray | None  # None when no iterate kept the box
    best_dv_per_year_mps: float
    best_constraint: np.ndarray  # [2]
    best_params: Params | None
    history: dict[str, np.ndarray]  # the /iterations datasets
    starts: np.ndarray
    message: str
    wall_s: float


def tune(spec: TuneSpec, out=None, problem: Problem | None = None, verbose: bool = True) -> TuneResult:
    """Run the tuning of ``spec``; per-iteration progress on stdout and, with ``out``, in an HDF5 file."""
    run_ = _Run(spec, out, problem, verbose)
    message = (_sqp if spec.method == "sqp" else _adam)(run_)
    best = run_.best
    if best["theta"] is None:
        message += "; no iterate kept the box with the exact law"
    wall_s = run_.elapsed()
    best_params = None if best["theta"] is None else run_.problem.params(jnp.asarray(best["theta"]))
    result = TuneResult(best["theta"], best["dv"], best["g"], best_params, _stack(run_.hist), run_.hist["theta"][0],
                        message, wall_s)
    if out:
        _write(out, spec, run_.problem, run_.hist, result.starts, best, message, wall_s)
    return result


# The jitter of a sampled-and-held law's yearly Delta-V between gains 0.2 % apart (measured: a few 0.01 m/s/yr).
SAMPLED_LAW_NOISE_MPS = 0.05


def default_margin(spec: TuneSpec, sc: scenario_mod.Scenario) -> float:
    """``margin`` when the tuning file leaves it out.  The SQP aims at the box's edge itself when the exact
    law is smooth (continuous-clipped: its linearisation is exact there), and 1 % of Delta_s^2 inside it for
    the sampled-and-held laws, whose excursion jumps by about that much between neighbouring gains (a step
    aimed at the edge lands outside half the time).  Adam's penalty needs 2 % of room to settle inside."""
    if spec.margin is not None:
        return spec.margin
    if spec.method == "adam":
        return 0.02
    return 0.0 if _smooth(spec) else 0.01


def default_trust_radius(spec: TuneSpec, sc: scenario_mod.Scenario) -> float:
    """The SQP's first trust radius (natural-log units) when the tuning file leaves it out: 2 for the smooth
    law, whose linearisation holds over long steps, 0.3 for the sampled-and-held laws, whose surrogate's
    linearisation points the right way over a shorter range (both measured with benchmarks/tune.py)."""
    if spec.trust_radius is not None:
        return spec.trust_radius
    return 2.0 if _smooth(spec) else 0.3


def _smooth(spec: TuneSpec) -> bool:
    """Whether the scenario's controller is its own surrogate (the clipped continuous law)."""
    return prepare([spec.scenario], spec.controller).controller.surrogate is None


class _Run:
    """What both methods share: the problem, the starts, the best feasible point, the history and its output."""

    def __init__(self, spec: TuneSpec, out, problem: Problem | None, verbose: bool):
        self.start_wall = time.perf_counter()
        self.spec, self.out = spec, out
        self.problem = problem or Problem(spec.scenario, spec.parameters, spec.penalty_mps,
                                          default_margin(spec, spec.scenario), spec.gradient, spec.controller,
                                          lanes=max(1, spec.starts // jax.device_count()))
        self.margin = default_margin(spec, spec.scenario)
        self.noise_mps = 0.0 if self.problem.exact_is_smooth else SAMPLED_LAW_NOISE_MPS
        # The smallest trust region: for the sampled-and-held laws the scale below which they are noise (their
        # refused starts then probe a random neighbour); the smooth law's may shrink until its steps converge.
        self.trust_radius_min = spec.trust_radius_min
        if self.trust_radius_min is None:
            self.trust_radius_min = 1e-6 if self.problem.exact_is_smooth else 0.02
        self.trust_radius = max(default_trust_radius(spec, spec.scenario), self.trust_radius_min)
        center = to_theta(self.problem.base, self.problem.entries)
        self.theta0 = start_points(spec, center, self.problem.entries, self.problem.sizes)
        self.low, self.high = center - LOG_BOUND, center + LOG_BOUND
        self.best = {"dv": math.inf, "theta": None, "g": np.full(2, np.nan)}
        self.hist = {k: [] for k in ("dv_per_year_mps", "constraint", "loss", "step_norm", "theta", "temperature",
                                     "active", "trust_radius", "best_dv_per_year_mps", "wall_s")}
        self.say = print if verbose else (lambda *a, **k: None)
        self.say(f"tune {spec.scenario.name}: {', '.join(spec.parameters)} by {spec.method} from {spec.starts} starts, "
                 f"{spec.iterations} iterations, {self.problem.days} days (compiling...)",
                 flush=True)

    def elapsed(self) -> float:
        return time.perf_counter() - self.start_wall

    def temperature(self, it: int) -> float:
        spec = self.spec
        return spec.temperature_start * (spec.temperature_end / spec.temperature_start) ** (it / max(spec.iterations, 1))

    def keep_best(self, theta, dv, g, ok):
        _keep_best(self.best, theta, dv, g, ok)

    def record(self, it, dv, g, ok, loss, step, theta, temperature, active, trust_radius):
        _record(self.hist, dv, g, loss, step, theta, temperature, active, trust_radius, self.best["dv"], self.elapsed())
        if len(self.hist["wall_s"]) == 1:  # the first evaluation compiled the rollout and its derivatives
            self.say(f"  compiled and evaluated the first iterate in {self.elapsed():.1f} s", flush=True)
        self.say(f"  it {it:3d}  T {temperature:.3f}  ΔV exact median {np.nanmedian(dv):7.3f} m/s/yr  max constraint "
                 f"median {np.nanmedian(np.max(g, axis=1)):+.3f}  feasible {int(np.sum(ok > 0))}/{len(dv)}  step "
                 f"{np.median(step):.3g}  best feasible {self.best['dv']:.3f}", flush=True)
        if self.out:
            _write(self.out, self.spec, self.problem, self.hist, self.hist["theta"][0], self.best, "running",
                   self.elapsed())

    def diverged(self, it, bad, active) -> np.ndarray:
        """Stop the active starts flagged ``bad`` (non-finite values or derivatives), with a message."""
        if np.any(bad & active):
            self.say(f"  iteration {it}: start(s) {np.flatnonzero(bad & active).tolist()} diverged "
                     "(non-finite values or derivatives); stopped, best feasible point kept")
        return active & ~bad


def _all_diverged(run_: _Run, it: int) -> str:
    message = f"stopped at iteration {it}: every start diverged (non-finite values or derivatives)"
    run_.say(f"tune: {message}; keeping the best feasible point found", file=sys.stderr)
    return message


def _sqp(run_: _Run) -> str:
    """Trust-region SQP on every start at once (see the module docstring); returns the run's status message."""
    spec, problem = run_.spec, run_.problem
    theta = run_.theta0.copy()
    n, n_par = theta.shape
    dv, g, ok, jac = problem.linearise(theta, run_.temperature(0))
    run_.keep_best(theta, dv, g, ok)
    radius = np.full(n, run_.trust_radius)
    # The first model's curvature: fitted over the starts; with too few, an unconstrained step as long as
    # the trust region.
    norms = np.linalg.norm(jac[:, 0], axis=1)
    norms = norms[np.isfinite(norms) & (norms > 0)]
    scale = (float(np.median(norms)) if norms.size else 1.0) / run_.trust_radius
    hessian = np.tile(population_hessian(theta, jac[:, 0], np.eye(n_par) * scale), (n, 1, 1))
    margin = np.full((n, 2), run_.margin)  # per start and axis; see the end of the loop
    refused = np.zeros(n, bool)
    rng = np.random.default_rng(spec.seed + 1)
    active = np.ones(n, bool)
    step = np.zeros(n)
    for it in range(spec.iterations + 1):
        temperature = run_.temperature(it)
        active = run_.diverged(it, ~_finite(dv, g, jac), active)
        run_.record(it, dv, g, ok, np.where(ok > 0, dv, np.nan), step, theta, temperature, active, radius)
        if it == spec.iterations:
            return f"finished {spec.iterations} iterations"
        if not active.any():
            return _all_diverged(run_, it)
        steps = np.zeros_like(theta)
        multipliers = np.zeros((n, 2))
        for i in np.flatnonzero(active):
            steps[i], multipliers[i] = qp_step(jac[i, 0], hessian[i], g[i] + margin[i], jac[i, 1:], radius[i],
                                               run_.low - theta[i], run_.high - theta[i])
        if np.all(np.max(np.abs(steps[active]), axis=1) < spec.step_tolerance):
            return f"converged at iteration {it}: every step below {spec.step_tolerance:g} (natural-log units)"
        # A start refused at the smallest trust region would propose the same step again: below that scale the
        # sampled-and-held laws are noise the model cannot see, so it probes a random neighbour instead.
        stuck = active & refused & (radius <= run_.trust_radius_min) & (run_.noise_mps > 0)
        steps += np.where(stuck[:, None], rng.uniform(-1.0, 1.0, steps.shape) * run_.trust_radius_min, 0.0)
        trial = np.clip(theta + steps, run_.low, run_.high)
        steps = trial - theta
        dv_t, g_t, ok_t, jac_t = problem.linearise(trial, run_.temperature(it + 1))
        finite = _finite(dv_t, g_t, jac_t)
        run_.keep_best(trial, np.where(finite, dv_t, np.nan), g_t, np.where(finite, ok_t, 0.0))
        accept = active & finite & _better(dv, g, dv_t, g_t, run_.noise_mps)
        step_len = np.max(np.abs(steps), axis=1)
        for i in np.flatnonzero(accept):
            lagrangian_change = (jac_t[i, 0] - jac[i, 0]) + multipliers[i] @ (jac_t[i, 1:] - jac[i, 1:])
            hessian[i] = damped_bfgs(hessian[i], steps[i], lagrangian_change)
        grow = accept & (step_len >= 0.9 * radius)
        radius = np.where(grow, np.minimum(2.0 * radius, 2.0 * run_.trust_radius), radius)
        radius = np.where(active & ~accept, np.maximum(0.5 * step_len, run_.trust_radius_min), radius)
        take = lambda new, old: np.where(accept.reshape((-1,) + (1,) * (np.ndim(old) - 1)), new, old)  # noqa: E731
        theta, dv, g, ok, jac = take(trial, theta), take(dv_t, dv), take(g_t, g), take(ok_t, ok), take(jac_t, jac)
        step = np.where(accept, step_len, 0.0)
        refused = active & ~accept
        # A step refused for leaving the box aims that much further inside next time (the linearised constraint
        # under-predicted the exact one by ``miss``); an accepted step relaxes the start's margin halfway back.
        miss = np.maximum(g_t - (g + np.einsum("ncp,np->nc", jac[:, 1:], steps)), 0.0)
        refused_outside = (active & ~accept & (np.max(g_t, axis=1) > 0))[:, None]
        margin = np.where(refused_outside, np.minimum(margin + miss * (g_t > 0), 0.5), margin)
        margin = np.where(accept[:, None], 0.5 * (margin + run_.margin), margin)


def _finite(dv, g, jac) -> np.ndarray:
    return np.isfinite(dv) & np.all(np.isfinite(g), axis=1) & np.all(np.isfinite(jac), axis=(1, 2))


def _better(dv, g, dv_new, g_new, tolerance_mps: float) -> np.ndarray:
    """The SQP's acceptance on the exact law: outside the box, a smaller violation; inside, the box kept and
    a Delta-V no more than ``tolerance_mps`` higher (a filter with two entries: no penalty weight, so noise in
    the constraint cannot outweigh a Delta-V gain).  The tolerance is the noise of the sampled-and-held laws,
    whose yearly Delta-V jumps by a few 0.01 m/s/yr between neighbouring gains: without it a step along the
    smooth trend is refused by a jump, and then proposed again and again."""
    violation, violation_new = np.sum(np.maximum(g, 0.0), axis=1), np.sum(np.maximum(g_new, 0.0), axis=1)
    return np.where(violation > 0, violation_new < violation, (violation_new == 0) & (dv_new < dv + tolerance_mps))


def qp_step(grad, hessian, g, jac_g, radius, low, high, elastic_weight: float = 1e3):
    """min grad.d + d'Hd/2 + w sum(t)  s.t.  g + jac_g d <= t, t >= 0, |d|_inf <= radius, low <= d <= high.

    The elastic t keeps the subproblem solvable when the linearised box cannot be reached inside the trust
    region (it then moves as far toward it as it can).  Returns (d, multipliers of the two constraints),
    the multipliers estimated from the stationarity of the step (zero for inactive constraints).
    """
    n_par, n_con = grad.size, g.size
    lower, upper = np.maximum(-radius, low), np.minimum(radius, high)

    def objective(x):
        d, t = x[:n_par], x[n_par:]
        return grad @ d + 0.5 * d @ hessian @ d + elastic_weight * t.sum(), \
            np.concatenate([grad + hessian @ d, np.full(n_con, elastic_weight)])

    constraint = {"type": "ineq", "fun": lambda x: x[n_par:] - g - jac_g @ x[:n_par],
                  "jac": lambda x: np.hstack([-jac_g, np.eye(n_con)])}
    x0 = np.concatenate([np.zeros(n_par), np.maximum(g, 0.0)])
    bounds = [(lo, hi) for lo, hi in zip(lower, upper)] + [(0.0, None)] * n_con
    res = minimize(objective, x0, jac=True, method="SLSQP", constraints=[constraint], bounds=bounds,
                   options={"maxiter": 200, "ftol": 1e-14})
    d = np.clip(res.x[:n_par], lower, upper)
    binding = g + jac_g @ d >= -1e-9 * (1.0 + np.abs(g))
    free = (d > lower + 1e-12) & (d < upper - 1e-12)
    multipliers = np.zeros(n_con)
    if binding.any() and free.any():
        residual = -(grad + hessian @ d)
        solution = np.linalg.lstsq(jac_g[binding][:, free].T, residual[free], rcond=None)[0]
        multipliers[binding] = np.maximum(solution, 0.0)
    return d, multipliers


def population_hessian(theta, grad, fallback):
    """One curvature for every start's first model: the symmetric H of grad_i - mean = H (theta_i - mean),
    fitted by least squares over the starts, its eigenvalues floored at 1e-3 of the largest so that it is
    positive definite.  The starts sample the landscape around the scenario's gains, so their gradients
    together see a curvature no single start has yet (on the smooth law it saves about two iterations).
    ``fallback`` when there are too few finite starts to fit it."""
    keep = np.all(np.isfinite(grad), axis=1)
    theta, grad = theta[keep], grad[keep]
    if len(theta) <= theta.shape[1]:
        return fallback
    d_theta, d_grad = theta - theta.mean(axis=0), grad - grad.mean(axis=0)
    h = np.linalg.lstsq(d_theta, d_grad, rcond=None)[0]
    w, v = np.linalg.eigh(0.5 * (h + h.T))
    if not np.all(np.isfinite(w)) or np.max(w) <= 0.0:
        return fallback
    return (v * np.maximum(w, 1e-3 * np.max(w))) @ v.T


def damped_bfgs(hessian, s, y):
    """Powell's damped BFGS update: stays positive definite when the curvature along s is negative."""
    hs = hessian @ s
    shs, sy = float(s @ hs), float(s @ y)
    if shs <= 0.0:
        return hessian
    if sy < 0.2 * shs:
        weight = 0.8 * shs / (shs - sy)
        y = weight * y + (1.0 - weight) * hs
        sy = float(s @ y)
    return hessian - np.outer(hs, hs) / shs + np.outer(y, y) / sy


def _adam(run_: _Run) -> str:
    """optax Adam on the penalised surrogate (see the module docstring); returns the run's status message."""
    spec, problem = run_.spec, run_.problem
    theta = run_.theta0.copy()
    # Few parameters, few iterations: a learning rate decaying geometrically (large steps to find the box,
    # small ones to settle on its edge), a short momentum (b1), so a start that has crossed into the box
    # does not coast on through it, and a short second-moment memory (b2 = 0.5), so the penalty's large
    # gradients outside the box do not shrink the steps along the Delta-V gradient inside it.
    schedule = optax.exponential_decay(spec.learning_rate, max(spec.iterations, 1),
                                       spec.learning_rate_end / spec.learning_rate)
    optimiser = optax.adam(schedule, b1=spec.momentum, b2=0.5)
    opt_state = optimiser.init(jnp.asarray(theta))
    active = np.ones(spec.starts, bool)
    no_radius = np.full(spec.starts, np.nan)
    for it in range(spec.iterations + 1):
        temperature = run_.temperature(it)
        last = it == spec.iterations
        if last or not problem.exact_is_smooth:
            dv, g, ok = map(np.asarray, problem.exact(theta))
        if not last:
            loss, aux, grad = problem.surrogate_grad(theta, temperature)
            loss, grad = np.asarray(loss), np.asarray(grad)
            if problem.exact_is_smooth:
                dv, g, ok = map(np.asarray, aux)
        run_.keep_best(theta, dv, g, ok)
        if last:
            run_.record(it, dv, g, ok, np.full(spec.starts, np.nan), np.zeros(spec.starts), theta, temperature, active,
                        no_radius)
            return f"finished {spec.iterations} iterations"
        bad = ~(np.isfinite(loss) & np.all(np.isfinite(grad), axis=1))
        active = run_.diverged(it, bad, active)
        grad = np.where(active[:, None], grad, 0.0)
        updates, opt_state = optimiser.update(jnp.asarray(grad), opt_state)
        new = np.clip(theta + np.where(active[:, None], np.asarray(updates), 0.0), run_.low, run_.high)
        run_.record(it, dv, g, ok, loss, np.linalg.norm(new - theta, axis=1), theta, temperature, active, no_radius)
        theta = new
        if not active.any():
            return _all_diverged(run_, it)


def _keep_best(best, theta, dv, g, ok):
    feasible = (ok > 0) & np.isfinite(dv)
    if np.any(feasible):
        j = int(np.argmin(np.where(feasible, dv, np.inf)))
        if dv[j] < best["dv"]:
            best.update(dv=float(dv[j]), theta=np.array(theta[j]), g=np.array(g[j]))


def _record(hist, *values):
    for key, value in zip(hist, values):
        hist[key].append(np.array(value))


def _stack(hist):
    return {k: np.stack(v) for k, v in hist.items()}


def _write(out, spec, problem, hist, theta_starts, best, message, wall_s):
    groups = {"iterations": _stack(hist), "starts": {"theta": np.asarray(theta_starts)}}
    groups["iterations"]["active"] = groups["iterations"]["active"].astype(np.int8)
    if best["theta"] is not None:
        params = problem.params(jnp.asarray(best["theta"]))
        groups["best"] = {**paper_units(params, scenario_mod.controller_fields(spec.scenario.config["controller"],
                                                                                spec.controller)), "theta": best["theta"]}
        groups["metrics"] = {"dv_per_year_mps": best["dv"], "constraint_lon": best["g"][0],
                             "constraint_lat": best["g"][1]}
    attrs = {"kind": "tune", "scenario": spec.scenario.name, "parameters": ",".join(spec.parameters),
             "status": message, "tune_toml": spec.text,
             "controller": spec.scenario.controller}
    store.write_h5(out, groups, scenario_mod.to_toml(spec.scenario.config), wall_s, attrs=attrs, dims=TUNE_DIMS)
    if best["theta"] is not None and message != "running":
        store.atomic_write(tuned_scenario_path(out), tuned_scenario_toml(spec, params).encode())


# Axis names of a tuning file's datasets (geojax.results).
TUNE_DIMS = {"iterations": ("iteration", "start"), "iterations/theta": ("iteration", "start", "parameter"),
             "iterations/constraint": ("iteration", "start", "box_axis"),
             **{f"iterations/{k}": ("iteration",) for k in ("temperature", "best_dv_per_year_mps", "wall_s")},
             "starts": ("start", "parameter"), "best/theta": ("parameter",)}


def tuned_scenario_path(out) -> Path:
    """Where ``geojax tune --out FILE.h5`` writes the tuned scenario: ``FILE-tuned.toml`` beside it."""
    out = Path(out)
    return out.with_name(f"{out.stem}-tuned.toml")


def tuned_config(spec: TuneSpec, params: Params) -> dict:
    """The tuning's scenario table with each tuned key set to its value in ``params``, in the key's own unit."""
    config = copy.deepcopy(spec.scenario.config)
    for entry in tuned(spec.scenario, spec.controller, spec.parameters):
        leaf = np.asarray(getattr(params, entry.table)[entry.field.si], dtype=float)
        if entry.field.to_si is degrees:
            value = np.degrees(leaf).tolist()
        else:
            value = entry.field.from_si(leaf)
        config[entry.table][entry.name.rpartition(".")[2]] = value
    config["name"] = f"{spec.scenario.name}-tuned"
    return config


def tuned_scenario_fault(spec: TuneSpec, params: Params) -> str | None:
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


def tuned_scenario_toml(spec: TuneSpec, params: Params) -> str:
    """The tuned scenario as TOML (``geojax simulate FILE-tuned.toml`` runs it): the tuning's scenario with
    each tuned key set to its best value, in the key's own unit."""
    config = tuned_config(spec, params)
    header = (f"# {spec.scenario.name} with the gains tuned by geojax tune ({', '.join(spec.parameters)});\n"
              f"# run it with: geojax simulate THIS_FILE\n")
    return header + scenario_mod.to_toml(config)
