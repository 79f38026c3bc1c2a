"""The driver of a tuning: ``tune(spec)`` runs its optimiser from every start and keeps the best feasible point.

Every iterate of every start is evaluated with the *exact* law over the full horizon, and the result is the
iterate of least exact Delta-V whose exact rollout keeps the box.  The discontinuous thrust laws are
differentiated through their surrogates at a temperature annealed geometrically from ``temperature_start`` to
``temperature_end``.  A start whose values or derivatives are not finite stops (its best feasible point is
kept); when every start has stopped the run ends with a message.  With ``out``, the HDF5 file is rewritten
after each iteration (``geojax.tune.write``).
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
import warnings

import jax
import jax.numpy as jnp
import numpy as np

from geojax.runner.setup import controller_of
from geojax.params import Params
from geojax.tune import adam, sqp
from geojax.tune.objective import Problem
from geojax.tune.space import LOG_BOUND, start_points, to_theta
from geojax.tune.spec import TuneSpec, horizon_warning
from geojax.tune import write as write_mod
from geojax.tune.write import write

# The optimisers, by the tuning file's ``method``: each ``run(Run) -> status message``.
METHODS = {"sqp": sqp.run, "adam": adam.run}

# The jitter of a sampled-and-held law's yearly Delta-V between gains 0.2 % apart (measured: a few 0.01 m/s/yr).
SAMPLED_LAW_NOISE_MPS = 0.05


class ShortHorizonWarning(UserWarning):
    """The tuning's horizon is too short for the yearly Delta-V it minimises (``spec.horizon_warning``)."""


@dataclasses.dataclass
class TuneResult:
    best_theta: np.ndarray | None  # None when no iterate kept the box
    best_dv_per_year_mps: float
    best_constraint: np.ndarray  # [C]: lon, lat (then the carried parts'; ``Problem.constraint_names``)
    best_params: Params | None
    history: dict[str, np.ndarray]  # the /iterations datasets
    starts: np.ndarray
    message: str
    wall_s: float
    spec: TuneSpec | None = None  # what its file records (``save``)
    problem: Problem | None = None

    # What ``geojax tune`` writes (``--out``), prints and draws (``geojax plot``): ``geojax.tune.write``'s.
    save, summary, plot = write_mod.save, write_mod.summary, write_mod.plot


def tune(spec: TuneSpec, out=None, problem: Problem | None = None, verbose: bool = True) -> TuneResult:
    """Run the tuning of ``spec``; per-iteration progress on stdout and, with ``out``, in an HDF5 file.

    Warns (``ShortHorizonWarning``) when the horizon is too short for the yearly Delta-V it minimises."""
    fault = horizon_warning(spec)
    if fault:
        warnings.warn(fault, ShortHorizonWarning, stacklevel=2)
    run_ = Run(spec, out, problem, verbose)
    try:
        message = METHODS[spec.method](run_)
    except KeyboardInterrupt:  # Ctrl-C: the file says so (not "running") and keeps the best point so far
        if out and run_.hist["theta"]:
            write(out, spec, run_.problem, run_.hist, run_.hist["theta"][0], run_.best,
                  interrupted_status(len(run_.hist["theta"])), run_.elapsed())
        raise
    best = run_.best
    if best["theta"] is None:
        message += "; no iterate kept the box with the exact law"
    wall_s = run_.elapsed()
    best_params = None if best["theta"] is None else run_.problem.params(jnp.asarray(best["theta"]))
    result = TuneResult(best["theta"], best["dv"], best["g"], best_params, _stack(run_.hist), run_.hist["theta"][0],
                        message, wall_s, spec, run_.problem)
    if out:
        result.save(out)
    return result


def interrupted_status(iterations: int) -> str:
    """The file's ``status`` of a tuning stopped by Ctrl-C after ``iterations`` iterations (a tuning has no
    resume: its iterates are not a function of where it stopped, the trust region and the annealing being
    state of the run)."""
    return f"interrupted after {iterations} iteration(s) (Ctrl-C); the best feasible point so far kept"


def default_margin(spec: TuneSpec) -> float:
    """``margin`` when the tuning file leaves it out.  The SQP aims at the box's edge itself when the exact
    law is smooth (its linearisation is exact there), and 1 % of Delta_s^2 inside it for the sampled-and-held
    laws, whose excursion jumps by about that much between neighbouring gains (a step aimed at the edge lands
    outside half the time).  Adam's penalty needs 2 % of room to settle inside."""
    if spec.margin is not None:
        return spec.margin
    if spec.method == "adam":
        return 0.02
    return 0.0 if _smooth(spec) else 0.01


def default_trust_radius(spec: TuneSpec) -> float:
    """The SQP's first trust radius (natural-log units) when the tuning file leaves it out: 2 for a smooth
    law, whose linearisation holds over long steps, 0.3 for the sampled-and-held laws, whose surrogate's
    linearisation points the right way over a shorter range (both measured with benchmarks/tune.py)."""
    if spec.trust_radius is not None:
        return spec.trust_radius
    return 2.0 if _smooth(spec) else 0.3


def _smooth(spec: TuneSpec) -> bool:
    """Whether the scenario's controller is its own surrogate (smooth)."""
    return (spec.controller or controller_of([spec.scenario])).surrogate is None


class Run:
    """What every method shares: the problem, the starts, the best feasible point, the history and its output."""

    def __init__(self, spec: TuneSpec, out, problem: Problem | None, verbose: bool):
        self.start_wall = time.perf_counter()
        self.spec, self.out = spec, out
        self.margin = default_margin(spec)
        self.problem = problem or Problem(spec.scenario, spec.parameters, spec.penalty_mps, self.margin,
                                          spec.gradient, spec.controller,
                                          lanes=max(1, spec.starts // jax.device_count()))
        self.noise_mps = 0.0 if self.problem.exact_is_smooth else SAMPLED_LAW_NOISE_MPS
        # The smallest trust region: for the sampled-and-held laws the scale below which they are noise (their
        # refused starts then probe a random neighbour); a smooth law's may shrink until its steps converge.
        self.trust_radius_min = spec.trust_radius_min
        if self.trust_radius_min is None:
            self.trust_radius_min = 1e-6 if self.problem.exact_is_smooth else 0.02
        self.trust_radius = max(default_trust_radius(spec), self.trust_radius_min)
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
        """Keep the feasible (exact-law) iterate of least Delta-V among ``theta`` [n, P] if it beats the best."""
        feasible = (ok > 0) & np.isfinite(dv)
        if np.any(feasible):
            j = int(np.argmin(np.where(feasible, dv, np.inf)))
            if dv[j] < self.best["dv"]:
                self.best.update(dv=float(dv[j]), theta=np.array(theta[j]), g=np.array(g[j]))

    def record(self, it, dv, g, ok, loss, step, theta, temperature, active, trust_radius):
        values = (dv, g, loss, step, theta, temperature, active, trust_radius, self.best["dv"], self.elapsed())
        for key, value in zip(self.hist, values):
            self.hist[key].append(np.array(value))
        if len(self.hist["wall_s"]) == 1:  # the first evaluation compiled the rollout and its derivatives
            self.say(f"  compiled and evaluated the first iterate in {self.elapsed():.1f} s", flush=True)
        self.say(f"  it {it:3d}  T {temperature:.3f}  ΔV exact median {np.nanmedian(dv):7.3f} m/s/yr  max constraint "
                 f"{'(box, wheels)' if g.shape[1] > 2 else '(excursion/box)²-1'} median {np.nanmedian(np.max(g, axis=1)):+.3f}  "
                 f"feasible {int(np.sum(ok > 0))}/{len(dv)}  step "
                 f"{np.median(step):.3g}  best feasible {self.best['dv']:.3f}", flush=True)
        if self.out:
            write(self.out, self.spec, self.problem, self.hist, self.hist["theta"][0], self.best, "running",
                  self.elapsed())

    def diverged(self, it, bad, active) -> np.ndarray:
        """Stop the active starts flagged ``bad`` (non-finite values or derivatives), with a message."""
        if np.any(bad & active):
            self.say(f"  iteration {it}: start(s) {np.flatnonzero(bad & active).tolist()} diverged "
                     "(non-finite values or derivatives); stopped, best feasible point kept")
        return active & ~bad

    def all_diverged(self, it: int) -> str:
        """The status message of a run whose every start has diverged by iteration ``it``."""
        message = f"stopped at iteration {it}: every start diverged (non-finite values or derivatives)"
        self.say(f"tune: {message}; keeping the best feasible point found", file=sys.stderr)
        return message


def _stack(hist):
    return {k: np.stack(v) for k, v in hist.items()}
