"""Gain tuning through differentiable rollouts (Katz 2025, eqs. (8)-(16)): ``geojax tune TUNE.toml``.

Minimise the yearly Delta-V of a Milankovitch-Lyapunov scenario subject to the
box |lambda - lambda_d| <= Delta_s, |latitude| <= Delta_s, by Adam (optax) on
gradients of the whole rollout, from many starts at once (``vmap``; Katz reports
a strong sensitivity to the initial guess).  A tuning file:

    scenario = "katz2025-discrete"      # shipped name or .toml path (controller.kind = "lyapunov")
    parameters = ["k_h", "k_e"]         # any of k_h, k_e, k_lambda, lambda_b, sigma
    starts = 16                         # start 0 is the scenario's own gains
    iterations = 30
    # optional: days, step_s, learning_rate, learning_rate_end, momentum, spread_decades, spread_lambda_b_deg,
    # temperature_start, temperature_end, penalty_mps, margin, seed, gradient ("forward" or "reverse")

Parameters live in an unconstrained space: the natural log of the positive
gains (k_h, k_e, k_lambda), lambda_b / 0.1 deg, and for the discrete
thresholds three log-weights s with sigma = u0 exp(s) / |exp(s)|, so |sigma| =
u0 holds by construction.  The loss is the surrogate Delta-V plus
``penalty_mps`` times the violation of the box tightened by ``margin``
(constraint g = max(excursion^2) / Delta_s^2 - 1 per axis, eq. (10)); the
discontinuous thrust laws use their sigmoid surrogates at a temperature
annealed geometrically from ``temperature_start`` to ``temperature_end``
(``thrust_laws``).  Every iterate of every start is also evaluated with the
*exact* law over the full horizon; the result is the iterate of least exact
Delta-V whose exact rollout keeps the box.  A start whose loss or gradient is
not finite stops (its best feasible point is kept); when every start has
stopped the run ends with a message.

Gradients are forward-mode by default (``jacfwd``: no tape, so memory does not
grow with the horizon; for 2-7 parameters about twice as fast as reverse mode
on a CPU); ``gradient = "reverse"`` takes them through ``jax.checkpoint`` on
each day (``feedback.rollout``), so memory grows with days, not steps.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import optax

from geojax import feedback, run, scenario as scenario_mod, store
from geojax.control import lyapunov
from geojax.parallel import shard_batch
from geojax.propagate import DYNAMICS
from geojax.scenario import REQUIRED, Field


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

TUNABLE = ("k_h", "k_e", "k_lambda", "lambda_b", "sigma")
LAMBDA_B_SCALE_RAD = math.radians(0.1)  # lambda_b enters the optimiser in units of 0.1 deg
# Iterates are kept within this many natural-log units of their start (about 3 decades).
LOG_BOUND = 3 * math.log(10)

FIELDS = {
    "scenario": Field(str, REQUIRED),
    "parameters": Field(list, ["k_h", "k_e"]),
    "starts": Field(int, 16, lower=1, upper=4097, lower_inclusive=True),
    "iterations": Field(int, 30, lower=0, upper=10001, lower_inclusive=True),
    "days": Field((int, float), None, lower=0.0),
    "step_s": Field((int, float), None, lower=0.0),
    "learning_rate": Field((int, float), 0.1, lower=0.0),
    "learning_rate_end": Field((int, float), 0.02, lower=0.0),
    "momentum": Field((int, float), 0.5, lower=0.0, upper=1.0, lower_inclusive=True),
    "spread_decades": Field((int, float), 0.3, lower=0.0, lower_inclusive=True),
    "spread_lambda_b_deg": Field((int, float), 0.02, lower=0.0, lower_inclusive=True),
    "temperature_start": Field((int, float), 0.3, lower=0.0),
    "temperature_end": Field((int, float), 0.03, lower=0.0),
    "penalty_mps": Field((int, float), 200.0, lower=0.0),
    "margin": Field((int, float), 0.02, lower=0.0, upper=1.0, lower_inclusive=True),
    "seed": Field(int, 0, lower=0, lower_inclusive=True),
    "gradient": Field(str, "forward", choices=("forward", "reverse")),
}


@dataclasses.dataclass(frozen=True)
class TuneSpec:
    config: dict  # the validated tuning table, defaults filled in
    scenario: scenario_mod.Scenario
    text: str  # the tuning file, stored in the results

    def __getattr__(self, name):
        try:
            return self.config[name]
        except KeyError:
            raise AttributeError(name) from None


def load(path: str | Path) -> TuneSpec:
    """Read and validate a tuning file; ``ValueError`` with one line naming the fault."""
    path = Path(path)
    raw, text = scenario_mod.read_toml_file(path, "tuning")
    return from_dict(raw, text)


def from_dict(raw: dict, text: str = "") -> TuneSpec:
    config = scenario_mod.check_table("", raw, FIELDS)
    names = config["parameters"]
    if not names or any(n not in TUNABLE for n in names) or len(set(names)) != len(names):
        raise ValueError(f"parameters: must be distinct names from {', '.join(TUNABLE)}, got {names!r}")
    if config["temperature_end"] > config["temperature_start"]:
        raise ValueError(f"temperature_end: must be <= temperature_start = {config['temperature_start']}, "
                         f"got {config['temperature_end']}")
    overrides = {k: config[k] for k in ("days", "step_s") if config[k] is not None}
    overrides = {("duration." if k == "days" else "integration.") + k: float(v) for k, v in overrides.items()}
    sc = scenario_mod.load(config["scenario"], overrides)
    if sc.controller != "lyapunov":
        raise ValueError(f"scenario: tuning needs controller.kind = 'lyapunov', got {sc.controller!r} in {sc.name}")
    if "sigma" in names and sc.config["controller"]["thrust_mode"] != "discrete":
        raise ValueError("parameters: 'sigma' is tuned only with controller.thrust_mode = 'discrete'")
    return TuneSpec(config, sc, text)


# ---------------------------------------------------------------- parameter space


def to_theta(params: feedback.FeedbackParams, names) -> np.ndarray:
    """Unconstrained vector of the tuned parameters (see the module docstring)."""
    g = params.gains
    parts = {
        "k_h": lambda: [math.log(float(g.k_h_per_m2_s))],
        "k_e": lambda: [math.log(float(g.k_e_m2_per_s3))],
        "k_lambda": lambda: [math.log(float(g.k_lambda_m_per_rad))],
        "lambda_b": lambda: [float(g.lambda_b_rad) / LAMBDA_B_SCALE_RAD],
        "sigma": lambda: list(np.log(np.asarray(params.limits.sigma_mps2) / float(params.limits.u0_mps2))),
    }
    return np.array([x for n in names for x in parts[n]()])


def from_theta(theta, base: feedback.FeedbackParams, names) -> feedback.FeedbackParams:
    """The ``FeedbackParams`` of ``theta`` (jax-traceable): ``base`` with the tuned leaves replaced."""
    gains, limits, i = base.gains, base.limits, 0
    for n in names:
        if n == "sigma":
            w = jnp.exp(theta[i:i + 3])
            limits = limits._replace(sigma_mps2=limits.u0_mps2 * w / jnp.linalg.norm(w))
            i += 3
            continue
        value = theta[i] * LAMBDA_B_SCALE_RAD if n == "lambda_b" else jnp.exp(theta[i])
        gains = gains._replace(**{_GAIN_FIELD[n]: value})
        i += 1
    return base._replace(gains=gains, limits=limits)


_GAIN_FIELD = {"k_h": "k_h_per_m2_s", "k_e": "k_e_m2_per_s3", "k_lambda": "k_lambda_m_per_rad", "lambda_b": "lambda_b_rad"}


def paper_units(params: feedback.FeedbackParams) -> dict[str, float]:
    """Gains (and thresholds) in the paper's units, for reports."""
    g = params.gains
    sigma = np.asarray(params.limits.sigma_mps2) / 1e3
    return {
        "k_h_per_km2_s": float(g.k_h_per_m2_s) / lyapunov.K_H_PAPER_TO_SI,
        "k_e_km2_per_s3": float(g.k_e_m2_per_s3) / lyapunov.K_E_PAPER_TO_SI,
        "k_lambda_km_per_rad": float(g.k_lambda_m_per_rad) / lyapunov.K_LAMBDA_PAPER_TO_SI,
        "lambda_b_deg": math.degrees(float(g.lambda_b_rad)),
        "sigma_x_km_per_s2": float(sigma[0]), "sigma_y_km_per_s2": float(sigma[1]),
        "sigma_z_km_per_s2": float(sigma[2]),
    }


def start_points(spec: TuneSpec, center: np.ndarray) -> np.ndarray:
    """[starts, P]: start 0 at ``center`` (the scenario's gains), the rest uniform around it."""
    rng = np.random.default_rng(spec.seed)
    half = np.concatenate([
        [spec.spread_lambda_b_deg / 0.1] if n == "lambda_b" else
        [spec.spread_decades * math.log(10)] * (3 if n == "sigma" else 1)
        for n in spec.parameters
    ])
    starts = center + rng.uniform(-1.0, 1.0, (spec.starts, center.size)) * half
    starts[0] = center
    return starts


# ---------------------------------------------------------------- objective


class Problem:
    """The tuning problem of one scenario: batched exact evaluation and surrogate gradients, compiled once."""

    def __init__(self, sc: scenario_mod.Scenario, names, penalty_mps: float = 200.0, margin: float = 0.02,
                 gradient: str = "forward"):
        self.setup = run.feedback_setup(sc)
        self.names = tuple(names)
        self.fm = sc.force_model
        self.penalty_mps, self.margin = penalty_mps, margin
        self._exact = jax.jit(jax.vmap(lambda th: self.evaluate(th, smooth=False)[1]))
        self._single = jax.jit(lambda th: self.evaluate(th, smooth=False)[1])
        self._grad = jax.jit(jax.vmap(_value_and_grad(self.evaluate, gradient), in_axes=(0, None)))

    @property
    def exact_is_smooth(self) -> bool:
        """The clipped continuous law has no surrogate: its gradient run already is the exact evaluation."""
        return self.setup.mode == "continuous-clipped"

    def evaluate(self, theta, smooth: bool, temperature=0.05):
        """(loss, (dv_per_year_mps, constraint [2] lon/lat, box_ok)) of one parameter vector."""
        s = self.setup
        params = from_theta(theta, s.params, self.names)._replace(temperature=jnp.asarray(temperature))
        final, records = feedback.rollout(DYNAMICS[s.dynamics], s.state, s.env, self.fm, s.step_s, params, s.mode, smooth)
        m = feedback.metrics(s.state, final, records, s.step_s, params.station.lon_rad, s.box_half_width_rad)
        excursion = jnp.radians(jnp.stack([m.max_abs_dlon_deg, m.max_abs_dlat_deg]))
        # Katz eq. (10): delta^2 - Delta_s^2 <= 0, (lambda - lambda_d)^2 - Delta_s^2 <= 0, normalised.
        constraint = (excursion / s.box_half_width_rad) ** 2 - 1.0
        loss = m.dv_per_year_mps + self.penalty_mps * jnp.sum(jax.nn.relu(constraint + self.margin))
        return loss, (m.dv_per_year_mps, constraint, m.box_ok)

    def exact(self, thetas):
        """Exact-law (dv_per_year_mps [n], constraint [n, 2], box_ok [n]) of a batch of parameter vectors."""
        return self._exact(_spread(thetas))

    def exact_one(self, theta):
        return self._single(jnp.asarray(theta))

    def surrogate_grad(self, thetas, temperature):
        (loss, aux), grad = self._grad(_spread(thetas), jnp.asarray(temperature))
        return loss, aux, grad


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
    best_params: feedback.FeedbackParams | None
    history: dict[str, np.ndarray]  # the /iterations datasets
    starts: np.ndarray
    message: str
    wall_s: float


def tune(spec: TuneSpec, out=None, problem: Problem | None = None, verbose: bool = True) -> TuneResult:
    """Run the tuning of ``spec``; per-iteration progress on stdout and, with ``out``, in an HDF5 file."""
    start_wall = time.perf_counter()
    problem = problem or Problem(spec.scenario, spec.parameters, spec.penalty_mps, spec.margin, spec.gradient)
    center = to_theta(problem.setup.params, spec.parameters)
    theta = start_points(spec, center)
    low, high = center - LOG_BOUND, center + LOG_BOUND
    # Few parameters, few iterations: a learning rate decaying geometrically (large steps to find the box,
    # small ones to settle on its edge), a short momentum (b1), so a start that has crossed into the box
    # does not coast on through it, and a short second-moment memory (b2 = 0.5), so the penalty's large
    # gradients outside the box do not shrink the steps along the Delta-V gradient inside it.
    schedule = optax.exponential_decay(spec.learning_rate, max(spec.iterations, 1),
                                       spec.learning_rate_end / spec.learning_rate)
    optimiser = optax.adam(schedule, b1=spec.momentum, b2=0.5)
    opt_state = optimiser.init(jnp.asarray(theta))
    active = np.ones(spec.starts, bool)
    best = {"dv": math.inf, "theta": None, "g": np.full(2, np.nan)}
    hist = {k: [] for k in ("dv_per_year_mps", "constraint", "loss", "step_norm", "theta", "temperature", "active",
                            "best_dv_per_year_mps", "wall_s")}
    message = f"finished {spec.iterations} iterations"
    say = print if verbose else (lambda *a, **k: None)
    say(f"tune {spec.scenario.name}: {', '.join(spec.parameters)} from {spec.starts} starts, {spec.iterations} "
        f"iterations, {problem.setup.env.earth_angle_rad.shape[0]} days (compiling...)", flush=True)
    for it in range(spec.iterations + 1):
        frac = it / max(spec.iterations, 1)
        temperature = spec.temperature_start * (spec.temperature_end / spec.temperature_start) ** frac
        last = it == spec.iterations
        if last or not problem.exact_is_smooth:
            dv, g, ok = map(np.asarray, problem.exact(theta))
        if not last:
            loss, aux, grad = problem.surrogate_grad(theta, temperature)
            loss, grad = np.asarray(loss), np.asarray(grad)
            if problem.exact_is_smooth:
                dv, g, ok = map(np.asarray, aux)
        _keep_best(best, theta, dv, g, ok)
        if last:
            step = np.zeros(spec.starts)
            loss = np.full(spec.starts, np.nan)
        else:
            bad = ~(np.isfinite(loss) & np.all(np.isfinite(grad), axis=1))
            if np.any(bad & active):
                say(f"  iteration {it}: start(s) {np.flatnonzero(bad & active).tolist()} diverged "
                    "(non-finite loss or gradient); stopped, best feasible point kept")
            active &= ~bad
            grad = np.where(active[:, None], grad, 0.0)
            updates, opt_state = optimiser.update(jnp.asarray(grad), opt_state)
            new = np.clip(theta + np.where(active[:, None], np.asarray(updates), 0.0), low, high)
            step = np.linalg.norm(new - theta, axis=1)
        _record(hist, dv, g, loss, step, theta, temperature, active, best["dv"], time.perf_counter() - start_wall)
        say(f"  it {it:3d}  T {temperature:.3f}  ΔV exact median {np.nanmedian(dv):7.3f} m/s/yr  "
            f"max constraint median {np.nanmedian(np.max(g, axis=1)):+.3f}  feasible {int(np.sum(ok > 0))}/{spec.starts}"
            f"  step {np.median(step):.3g}  best feasible {best['dv']:.3f}", flush=True)
        if out:
            _write(out, spec, problem, hist, theta_starts=hist["theta"][0], best=best, message="running",
                   wall_s=time.perf_counter() - start_wall)
        if last:
            break
        theta = new
        if not active.any():
            message = f"stopped at iteration {it}: every start diverged (non-finite loss or gradient)"
            say(f"tune: {message}; keeping the best feasible point found", file=sys.stderr)
            break
    if best["theta"] is None:
        message += "; no iterate kept the box with the exact law"
    wall_s = time.perf_counter() - start_wall
    best_params = None if best["theta"] is None else from_theta(jnp.asarray(best["theta"]), problem.setup.params, spec.parameters)
    result = TuneResult(best["theta"], best["dv"], best["g"], best_params, _stack(hist), hist["theta"][0], message, wall_s)
    if out:
        _write(out, spec, problem, hist, result.starts, best, message, wall_s)
    return result


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
        params = from_theta(jnp.asarray(best["theta"]), problem.setup.params, spec.parameters)
        groups["best"] = {**paper_units(params), "theta": best["theta"]}
        groups["metrics"] = {"dv_per_year_mps": best["dv"], "constraint_lon": best["g"][0],
                             "constraint_lat": best["g"][1]}
    attrs = {"kind": "tune", "scenario": spec.scenario.name, "parameters": ",".join(spec.parameters),
             "status": message, "tune_toml": spec.text, "thrust_mode": problem.setup.mode}
    store.write_h5(out, groups, scenario_mod.to_toml(spec.scenario.config), wall_s, attrs=attrs)
