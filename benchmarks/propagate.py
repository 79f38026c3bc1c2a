"""One-year uncontrolled GEO propagations per second: geojax vs heyoka vs NumPy/SciPy, same force model.

Scenario ``li2022`` (Li 2022, eq. (4)): Earth point mass + J2 + Sun and Moon
third body (Meeus analytic ephemerides) + solar radiation pressure.  Three
implementations of that one model are timed in the same run:

* geojax: ``jax.jit(jax.vmap(propagate_cycles))`` over a batch of initial
  states, RK4 in modified equinoctial elements at a fixed step, with one
  environment grid (Sun, Moon, Earth angle) shared by the batch;
* heyoka: Taylor integrator in Cartesian ECI (tol 1e-10, plus 1e-12 at the
  largest batch), SIMD batch mode, the batch spread over all cores by threads
  (``baselines/heyoka_model.py``);
* NumPy + ``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-10), one orbit at a
  time (``baselines/numpy_model.py``).

The Earth shadow is switched OFF in all three for the throughput and the main
accuracy comparison: heyoka can write the conical shadow with ``hy.select``,
but its Taylor steps (hours) step over the non-analytic penumbra edges (see
``baselines/heyoka_model.py``).  geojax's cost does not depend on the switch
(``shadow_on`` is an array leaf multiplying a term that is always evaluated).
A supplementary accuracy check runs geojax with the shadow on against heyoka
with the ``hy.select`` shadow and its steps capped at 20 s in eclipse seasons.

Batch samples: sample 0 is the scenario's initial state, the others perturb p
by up to +-1 km and L by up to +-0.01 rad (uniform, seeded).  "One year" is
``geojax.uncontrolled.propagated_cycles(365.25)`` sidereal days (cycles), for every implementation.

Accuracy: the one-year change of the mean inclination vector
i (cos Omega, sin Omega) [deg] from the first to the last one-cycle mean
(trapezoid mean over one sidereal day, Li 2022, eq. (9)), for the unperturbed
state, geojax at each step against heyoka at tol 1e-10 (sampled at 96 + 1
times per cycle over the first and last cycles with ``propagate_grid``);
heyoka at tol 1e-14 is the tight reference for Δi and for the final position.

Timings: every throughput number is a wall time measured in this run.  The
CPU time that other processes used meanwhile ("other load") and the time the
hypervisor took from this virtual machine ("steal") are recorded; a
measurement disturbed by more than 0.2 cores in all is repeated (up to 2 extra
attempts, 1 for calls over a minute) and the fastest undisturbed call kept.

Run ``python benchmarks/propagate.py`` (full: 180 s on 2 cores in the run that wrote its results) or
``--quick`` (30 days, small batches).  Results go to
``benchmarks/results/propagate.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import copy
import threading
from typing import NamedTuple

import heyoka as hy
import jax
import jax.numpy as jnp
import numpy as np
import scipy

import harness
from geojax import scenario as scenario_module
from geojax.physics.constants import SIDEREAL_DAY_S
from geojax.physics.dynamics import SpacecraftState
from geojax.physics.elements import cartesian_to_mee, cycle_mean, mee_to_cartesian
from geojax.physics.forces import ForceModel, perturbing_acceleration, point_mass
from geojax.loop.simulate import propagate as propagate_cycles
from geojax.physics.propagate import MEE, environment_at, environment_grid, for_lanes, steps_per_cycle
from geojax.parallel import per_device
from geojax.uncontrolled import propagated_cycles, inclination_vector_deg

from baselines import heyoka_model, numpy_model
from harness.timing import DISTURBED_CORES, LONG_CALL_S

NAME = "propagate"
SAMPLES_PER_CYCLE = 96  # heyoka/SciPy sampling for the cycle means (96 + 1 points)
HEYOKA_TOL = 1e-10
HEYOKA_TIGHT_TOL = 1e-14  # accuracy reference (compact mode, scalar)
SCIPY_RTOL, SCIPY_ATOL = 1e-10, 1e-6
SHADOW_MAX_STEP_S = 20.0  # heyoka step cap in eclipse seasons, shadow-on reference
GOAL_DEG = 1e-5


class Config(NamedTuple):
    """What one run measures."""

    days: float
    geojax_batches: tuple[int, ...]  # at the default step
    geojax_large_batch_steps: tuple[float, ...]  # other steps, timed at the largest batch only
    accuracy_steps: tuple[float, ...]
    heyoka_batches: tuple[int, ...]  # at HEYOKA_TOL
    heyoka_large_batch_tols: tuple[float, ...]  # other tolerances, largest batch only
    heyoka_compact_row: bool  # also time compact mode at the largest batch
    scipy_orbits: int
    seed: int = 0


FULL = Config(365.25, (1, 64, 1024), (1800.0, 3600.0, 7200.0), (900.0, 1800.0, 3600.0, 7200.0), (1, 64, 1024),
              (1e-12,), True, 3)
QUICK = Config(30.0, (1, 8), (), (900.0, 1800.0, 3600.0, 7200.0), (1, 8), (), False, 1)


class Problem(NamedTuple):
    """The li2022 scenario with the shadow off, and the batch of initial states."""

    scenario: scenario_module.Scenario
    force_model: ForceModel  # geojax, shadow off
    numpy_model: numpy_model.Model  # shadow off
    n_cycles: int
    t_end_s: float  # n_cycles sidereal days
    mee: np.ndarray  # [max batch, 6]
    cartesian: np.ndarray  # [max batch, 6], ECI r, v


def log(message: str) -> None:
    print(message, flush=True)


# --- Rows ------------------------------------------------------------------------------------------


def throughput_row(implementation, setting, batch, timing: harness.Timing, **extra) -> dict:
    """One row of the throughput table; orbits/s = batch / steady-state wall time."""
    row = timing.row()
    return {"implementation": implementation, "setting": setting, "batch": batch, **row,
            "orbits_per_s": batch / row["run_s"], **extra}


def log_row(row: dict) -> None:
    log(f"  {row['implementation']:7s} {row['setting']:52s} batch {row['batch']:5d}: compile {row['compile_s']:5.1f} s, "
        f"run {row['run_s']:7.2f} s, {row['orbits_per_s']:8.3f} orbits/s (other load {row['other_load_cores']:.2f}, "
        f"steal {row['steal_cores']:.2f}, attempts {row['attempts']})")


# --- Problem set-up ----------------------------------------------------------------------------


def make_problem(days: float, max_batch: int, seed: int) -> Problem:
    """The li2022 scenario, shadow off, and ``max_batch`` initial states (sample 0 unperturbed)."""
    scenario = scenario_module.load("li2022")
    force_model = scenario.force_model._replace(shadow_on=0.0)
    rng = np.random.default_rng(seed)
    mee = np.tile(scenario.initial_mee, (max_batch, 1))
    mee[1:, 0] += rng.uniform(-1e3, 1e3, max_batch - 1)
    mee[1:, 5] += rng.uniform(-0.01, 0.01, max_batch - 1)
    r, v = mee_to_cartesian(jnp.asarray(mee), force_model.mu_m3_s2)
    n_cycles = propagated_cycles(days)
    return Problem(
        scenario=scenario,
        force_model=force_model,
        numpy_model=numpy_model.from_scenario(scenario, shadow=False),
        n_cycles=n_cycles,
        t_end_s=n_cycles * SIDEREAL_DAY_S,
        mee=mee,
        cartesian=np.concatenate([np.asarray(r), np.asarray(v)], axis=-1),
    )


def peer_versions() -> dict:
    """The versions of what geojax is compared with (the harness records the rest)."""
    return {"scipy": scipy.__version__, "heyoka": hy.__version__, "heyoka_simd_size": hy.recommended_simd_size()}


# --- Mean inclination vector (shared by all implementations) ---------------------------------


def cycle_sample_times(n_cycles: int) -> np.ndarray:
    """[2, 97] times (s since epoch) spanning the first and the last cycle, both ends included."""
    grid = np.linspace(0.0, SIDEREAL_DAY_S, SAMPLES_PER_CYCLE + 1)
    last = (n_cycles - 1) * SIDEREAL_DAY_S + grid
    last[-1] = n_cycles * SIDEREAL_DAY_S  # exactly the end of the propagation
    return np.stack([grid, last])


def mean_inclination_change_deg(cartesian_samples: np.ndarray, mu: float) -> np.ndarray:
    """Change of the one-cycle mean inclination vector [2] (deg), last cycle minus first.

    ``cartesian_samples`` is [2, n + 1, 6]: osculating ECI states over the first
    and last cycle.  Mean (h, k) with ``geojax.physics.elements.cycle_mean``, then
    ``geojax.uncontrolled.inclination_vector_deg``, exactly as geojax does per cycle.
    """
    samples = jnp.asarray(cartesian_samples)
    mee = cartesian_to_mee(samples[..., :3], samples[..., 3:], mu)
    mean_hk = np.asarray(jax.vmap(cycle_mean)(mee[..., 3:5]))  # [2, 2]
    ivec = inclination_vector_deg(mean_hk[:, 0], mean_hk[:, 1])
    return ivec[1] - ivec[0]


class Outcome(NamedTuple):
    """What the accuracy tables need from one propagation of the unperturbed state."""

    delta_i_deg: np.ndarray  # [2]
    final_r_m: np.ndarray  # [3] ECI position at the end


# --- geojax --------------------------------------------------------------------------------------


class GeojaxRunner:
    """Environment grids and compiled batched propagators, cached per step (and batch size)."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self._env: dict[int, tuple] = {}
        self._compiled: dict[tuple[int, int], tuple] = {}

    def environment(self, step_request_s: float):
        """(n_steps, step_s, env grid, seconds to build it incl. its jit) for a requested step."""
        n_steps = steps_per_cycle(step_request_s)
        if n_steps not in self._env:
            step_s = SIDEREAL_DAY_S / n_steps
            s = self.problem.scenario
            env, call = harness.timed(
                environment_grid, s.epoch_tt_s, s.epoch_tt_s, s.tt_minus_ut1_s, step_s, self.problem.n_cycles, n_steps
            )
            self._env[n_steps] = (n_steps, step_s, env, call.wall_s)
        return self._env[n_steps]

    def states(self, batch: int) -> SpacecraftState:
        p = self.problem
        return SpacecraftState(p.mee[:batch], np.full(batch, p.scenario.mass_kg), np.zeros(batch))

    def compiled(self, step_request_s: float, batch: int):
        """(propagator, compile seconds): ``vmap(propagate_cycles)`` over the initial states, compiled as one
        single-device program per device when the batch splits evenly (``geojax.parallel.per_device``, as
        ``geojax sweep`` runs), else on one device; the environment grid and the force model are arguments
        shared by the batch."""
        n_steps, step_s, env, _ = self.environment(step_request_s)
        key = (n_steps, batch)
        if key not in self._compiled:
            devices = jax.device_count() if batch % jax.device_count() == 0 else 1
            # the step compiled for the lanes each device runs (fusion boundaries from 8 lanes on)
            dynamics = for_lanes(MEE, batch // devices)
            batched = jax.vmap(
                lambda state, env, fm: propagate_cycles(dynamics, state, env, fm, step_s), in_axes=(0, None, None)
            )
            run, compile_s = per_device(batched, (self.states(batch),), jax.local_devices()[:devices],
                                        shared=(env, self.problem.force_model))
            self._compiled[key] = (run, compile_s)
        return self._compiled[key]

    def run(self, step_request_s: float, batch: int, force_model: ForceModel | None = None):
        """(final states, CycleMeans [batch, n_cycles]) of one call of the compiled propagator (numpy)."""
        run, _ = self.compiled(step_request_s, batch)
        if force_model is None:
            return run(self.states(batch))  # the grid and force model placed at compile time
        return run(self.states(batch), shared=(self.environment(step_request_s)[2], force_model))

    def final_positions(self, final: SpacecraftState) -> np.ndarray:
        return np.asarray(mee_to_cartesian(final.orbit, self.problem.force_model.mu_m3_s2)[0])


def bench_geojax(runner: GeojaxRunner, config: Config) -> tuple[list[dict], dict[str, np.ndarray]]:
    """Throughput rows (default step at every batch size, other steps at the largest batch), and the
    final ECI positions [batch, 3] of the largest batch per step."""
    largest = max(config.geojax_batches)
    cases = [(900.0, b) for b in config.geojax_batches]
    cases += [(step, largest) for step in config.geojax_large_batch_steps]
    rows, finals = [], {}
    for step_request, batch in cases:
        n_steps, step_s, _, env_s = runner.environment(step_request)
        _, compile_s = runner.compiled(step_request, batch)
        (final, _), timing = harness.measure(runner.run, step_request, batch, repeats=3 if batch == 1 else 1,
                                             compile_s=compile_s)
        if batch == largest:
            finals[f"{step_s:.1f}"] = runner.final_positions(final)
        row = throughput_row(
            "geojax", f"RK4 MEE, {step_s:.1f} s ({n_steps}/cycle)", batch, timing,
            step_s=step_s, steps_per_cycle=n_steps, environment_grid_s=env_s,
        )
        rows.append(row)
        log_row(row)
    return rows, finals


def geojax_outcome(runner: GeojaxRunner, step_request_s: float, force_model=None) -> Outcome:
    """Δi and final position of the unperturbed state (batch 1)."""
    final, means = runner.run(step_request_s, 1, force_model)
    ivec = inclination_vector_deg(np.asarray(means.ix[0]), np.asarray(means.iy[0]))
    return Outcome(ivec[-1] - ivec[0], runner.final_positions(final)[0])


# --- heyoka --------------------------------------------------------------------------------------


def build_heyoka(model: numpy_model.Model, batch: bool, tol: float = HEYOKA_TOL, compact_mode: bool = False,
                 shadow: bool = False, cold: bool = True):
    """(integrator, compile seconds): scalar or SIMD-batch Taylor integrator of the force model.

    ``cold``: empty heyoka's in-memory cache of compiled code first (its disk
    cache is off for the whole run, see ``main``), so the time is a real
    LLVM compilation.
    """
    if cold:
        hy.llvm_state.clear_memcache()
    system = heyoka_model.ode_system(model, shadow=shadow)
    if batch:
        state = np.zeros((6, hy.recommended_simd_size()))
        make = lambda: hy.taylor_adaptive_batch(system, state, tol=tol, compact_mode=compact_mode)  # noqa: E731
    else:
        make = lambda: hy.taylor_adaptive(system, np.zeros(6), tol=tol, compact_mode=compact_mode)  # noqa: E731
    ta, call = harness.timed(make)
    return ta, call.wall_s


def _check_outcomes(outcomes) -> None:
    bad = [o for o in outcomes if o != hy.taylor_outcome.time_limit]
    if bad:
        raise RuntimeError(f"heyoka propagation failed: {bad[0]}")


def heyoka_propagate_batch(ta, states: np.ndarray, t_end_s: float, workers: int) -> tuple[np.ndarray, float]:
    """Propagate [n, 6] states to ``t_end_s`` with a batch integrator; (final [n, 6], Taylor steps per chunk).

    The states go in chunks of the SIMD width; ``workers`` threads each own one
    copy of the integrator and take every ``workers``-th chunk (heyoka releases
    the GIL while it integrates).  ``hy.ensemble_propagate_until_batch`` does
    the same but copies the integrator for every chunk, which costs tens of ms
    per chunk here.
    """
    width = ta.batch_size
    n = states.shape[0]
    padded = np.concatenate([states, np.repeat(states[-1:], (-n) % width, axis=0)])
    chunks = padded.reshape(-1, width, 6)
    finals = np.empty_like(chunks)
    steps = np.zeros(len(chunks), dtype=np.int64)
    errors: list[Exception] = []

    def work(first: int) -> None:
        try:
            local = copy.deepcopy(ta)
            for j in range(first, len(chunks), workers):
                local.set_time(0.0)
                local.state[:] = chunks[j].T
                local.propagate_until(t_end_s)
                _check_outcomes([res[0] for res in local.propagate_res])
                finals[j] = local.state.T
                steps[j] = max(res[3] for res in local.propagate_res)
        except Exception as err:  # re-raised in the calling thread
            errors.append(err)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(min(workers, len(chunks)))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    if errors:
        raise errors[0]
    return finals.reshape(-1, 6)[:n], float(steps.mean())


def heyoka_propagate_scalar(ta, state: np.ndarray, t_end_s: float) -> tuple[np.ndarray, float]:
    """Propagate one state to ``t_end_s``; (final [6], Taylor steps)."""
    ta.time = 0.0
    ta.state[:] = state
    outcome, _, _, n_steps, *_ = ta.propagate_until(t_end_s)
    _check_outcomes([outcome])
    return ta.state.copy(), float(n_steps)


def bench_heyoka(problem: Problem, config: Config, scalar, batch_default) -> tuple[list[dict], np.ndarray]:
    """Throughput rows and the final ECI positions [batch, 3] of the largest batch at ``HEYOKA_TOL``.

    Batch 1 uses the scalar integrator, larger batches the SIMD batch
    integrator on all cores; extra tolerances and compact mode at the largest
    batch only.  ``scalar`` and ``batch_default`` are (integrator, compile s).
    """
    workers = len(harness.usable_cores())
    width = hy.recommended_simd_size()
    largest = max(config.heyoka_batches)
    cases = [(b, HEYOKA_TOL, False) for b in config.heyoka_batches]
    cases += [(largest, tol, False) for tol in config.heyoka_large_batch_tols]
    if config.heyoka_compact_row:
        cases.append((largest, HEYOKA_TOL, True))
    rows, finals = [], None
    for batch, tol, compact in cases:
        states = problem.cartesian[:batch]
        if batch == 1:
            (ta, compile_s), setting = scalar, f"Taylor tol {tol:g}, scalar, 1 thread"
            (_, steps), timing = harness.measure(heyoka_propagate_scalar, ta, states[0], problem.t_end_s, repeats=3,
                                                 compile_s=compile_s)
        else:
            if tol == HEYOKA_TOL and not compact:
                ta, compile_s = batch_default
            else:
                ta, compile_s = build_heyoka(problem.numpy_model, batch=True, tol=tol, compact_mode=compact)
            setting = f"Taylor tol {tol:g}, SIMD {width} x {workers} threads" + (", compact mode" if compact else "")
            (final, steps), timing = harness.measure(heyoka_propagate_batch, ta, states, problem.t_end_s, workers,
                                                     compile_s=compile_s)
            if batch == largest and tol == HEYOKA_TOL and not compact:
                finals = final[:, :3]
        row = throughput_row("heyoka", setting, batch, timing, tol=tol, compact_mode=compact,
                             order=ta.order, taylor_steps_per_orbit=steps)
        rows.append(row)
        log_row(row)
    return rows, finals


def heyoka_outcome(ta, problem: Problem) -> Outcome:
    """Δi and final position of the unperturbed state with a scalar integrator (``propagate_grid``)."""
    ta.time = 0.0
    ta.state[:] = problem.cartesian[0]
    times = cycle_sample_times(problem.n_cycles)
    outcome, *_, samples = ta.propagate_grid(times.ravel())
    _check_outcomes([outcome])
    samples = samples.reshape(2, -1, 6)
    return Outcome(mean_inclination_change_deg(samples, problem.force_model.mu_m3_s2), samples[-1, -1, :3])


def final_position_agreement(geojax_finals: dict[str, np.ndarray], heyoka_finals: np.ndarray) -> dict:
    """Median and largest |r_geojax - r_heyoka| (m) at the end over the common batch, per geojax step.

    Shows that the timed batches did the same work, sample by sample.
    """
    out = {}
    for step, r in geojax_finals.items():
        n = min(len(r), len(heyoka_finals))
        distance_m = np.linalg.norm(r[:n] - heyoka_finals[:n], axis=1)
        out[step] = {"batch": n, "median_m": float(np.median(distance_m)), "max_m": float(distance_m.max())}
    return out


# --- NumPy + SciPy -------------------------------------------------------------------------------


def bench_scipy(problem: Problem, config: Config) -> tuple[dict, Outcome]:
    """Throughput row (one orbit at a time, so batch-independent) and the outcome of the unperturbed state."""
    times = cycle_sample_times(problem.n_cycles)
    calls, attempts, nfev = [], 0, 0
    outcome = None
    for j in range(config.scipy_orbits):
        t_eval = times.ravel() if j == 0 else None
        sol, timing = harness.measure(numpy_model.propagate, problem.cartesian[j], problem.t_end_s, problem.numpy_model,
                              t_eval, SCIPY_RTOL, SCIPY_ATOL)
        if sol.status != 0:
            raise RuntimeError(f"solve_ivp failed: {sol.message}")
        if j == 0:
            samples = sol.y.T.reshape(2, -1, 6)
            outcome = Outcome(mean_inclination_change_deg(samples, problem.force_model.mu_m3_s2), samples[-1, -1, :3])
        calls.append(timing.best)
        attempts += timing.attempts
        nfev += sol.nfev
        log(f"  scipy orbit {j + 1}/{config.scipy_orbits}: {timing.best_s:.1f} s, {sol.nfev} RHS evaluations")
    row = throughput_row(
        "numpy+scipy", f"DOP853 rtol {SCIPY_RTOL:g} atol {SCIPY_ATOL:g}, 1 orbit at a time",
        config.scipy_orbits, harness.Timing((harness.total(calls),)), attempts=attempts,
        rhs_evaluations_per_orbit=nfev / config.scipy_orbits,
    )
    log_row(row)
    return row, outcome


# --- Model agreement -----------------------------------------------------------------------------


def model_agreement(problem: Problem) -> dict:
    """Largest relative difference of the perturbing acceleration, NumPy and heyoka vs geojax (shadow ON).

    Positions: the initial orbit turned about z at the Earth rate, over a day of
    the March eclipse season (umbra and penumbra included) and over the year.
    """
    s = problem.scenario
    model = numpy_model.from_scenario(s, shadow=True)
    times = np.concatenate([np.linspace(0, problem.t_end_s, 50), 79 * 86400.0 + np.linspace(0, 86400.0, 500)])
    angle = 7.2921159e-5 * times
    r0 = problem.cartesian[0, :3]
    positions = np.stack([np.cos(angle) * r0[0] - np.sin(angle) * r0[1],
                          np.sin(angle) * r0[0] + np.cos(angle) * r0[1],
                          np.full_like(angle, r0[2])], -1)
    env = environment_at(s.epoch_tt_s + times, s.epoch_tt_s, s.tt_minus_ut1_s)
    fm = s.force_model
    a_geojax = np.asarray(point_mass(jnp.asarray(positions), fm.mu_m3_s2)
                          + perturbing_acceleration(jnp.asarray(positions), s.mass_kg, env, fm))
    a_numpy = np.stack([numpy_model.acceleration(t, r, model) for t, r in zip(times, positions)])
    a_heyoka = heyoka_model.acceleration_cfunc(model, shadow=True)(positions.T.copy(), time=times).T
    point = -fm.mu_m3_s2 * positions / np.linalg.norm(positions, axis=-1, keepdims=True) ** 3
    perturbation = np.linalg.norm(a_geojax - point, axis=-1)
    light = np.array([numpy_model.shadow_fraction(r, numpy_model.sun_moon_eci_m(s.epoch_tt_s + t, s.epoch_tt_s)[0],
                                                  model.r_earth_m) for t, r in zip(times, positions)])
    return {
        "points": len(times),
        "points_in_umbra": int(np.sum(light == 0)),
        "points_in_penumbra": int(np.sum((light > 0) & (light < 1))),
        "numpy_vs_geojax_max_rel": float(np.max(np.linalg.norm(a_numpy - a_geojax, axis=-1) / perturbation)),
        "heyoka_vs_geojax_max_rel": float(np.max(np.linalg.norm(a_heyoka - a_geojax, axis=-1) / perturbation)),
    }


# --- Accuracy ------------------------------------------------------------------------------------


def _entry(outcome: Outcome, reference: Outcome, tight: Outcome | None = None, **extra) -> dict:
    entry = {
        "delta_i_deg": outcome.delta_i_deg.tolist(),
        "abs_delta_i_deg": float(np.hypot(*outcome.delta_i_deg)),
        "diff_vs_reference_deg": float(np.hypot(*(outcome.delta_i_deg - reference.delta_i_deg))),
    }
    if tight is not None:
        entry["diff_vs_tight_deg"] = float(np.hypot(*(outcome.delta_i_deg - tight.delta_i_deg)))
        entry["final_position_error_m"] = float(np.linalg.norm(outcome.final_r_m - tight.final_r_m))
    return {**entry, **extra}


def accuracy(problem: Problem, runner: GeojaxRunner, config: Config, heyoka_scalar, scipy_outcome: Outcome) -> dict:
    """Shadow off, unperturbed state: Δi of geojax per step against heyoka tol 1e-10 (the brief's reference),
    and Δi and final position against heyoka tol 1e-14."""
    reference = heyoka_outcome(heyoka_scalar, problem)
    tight_ta, _ = build_heyoka(problem.numpy_model, batch=False, tol=HEYOKA_TIGHT_TOL, compact_mode=True)
    tight = heyoka_outcome(tight_ta, problem)
    rows = {
        f"heyoka tol {HEYOKA_TOL:g}": _entry(reference, reference, tight),
        f"heyoka tol {HEYOKA_TIGHT_TOL:g} (compact)": _entry(tight, reference, tight),
    }
    for tol in config.heyoka_large_batch_tols:
        ta, _ = build_heyoka(problem.numpy_model, batch=False, tol=tol, compact_mode=True)
        rows[f"heyoka tol {tol:g} (compact)"] = _entry(heyoka_outcome(ta, problem), reference, tight)
    rows[f"numpy+scipy DOP853 rtol {SCIPY_RTOL:g}"] = _entry(scipy_outcome, reference, tight)
    for step_request in config.accuracy_steps:
        step_s = runner.environment(step_request)[1]
        rows[f"geojax RK4 MEE {step_s:.1f} s"] = _entry(geojax_outcome(runner, step_request), reference, tight)
    return {"reference": f"heyoka tol {HEYOKA_TOL:g}", "tight_reference": f"heyoka tol {HEYOKA_TIGHT_TOL:g}",
            "rows": rows, "goal_deg": GOAL_DEG}


def eclipse_season_cycles(problem: Problem, max_declination_deg: float = 10.0) -> np.ndarray:
    """[n_cycles] True where the Sun's declination is below ``max_declination_deg`` at either end of the cycle.

    A GEO satellite (inclination < 1 deg here) can only enter the Earth's shadow
    when |declination| < about 8.7 deg (Earth radius / GEO radius).
    """
    s = problem.scenario
    ends = np.arange(problem.n_cycles + 1) * SIDEREAL_DAY_S
    sun = np.stack([numpy_model.sun_moon_eci_m(s.epoch_tt_s + t, s.epoch_tt_s)[0] for t in ends])
    low = np.degrees(np.abs(np.arcsin(sun[:, 2] / np.linalg.norm(sun, axis=1)))) < max_declination_deg
    return low[:-1] | low[1:]


def heyoka_shadow_outcome(ta, problem: Problem, seasons: np.ndarray, max_step_s: float | None):
    """(Outcome, Taylor steps) of the unperturbed state with the ``hy.select`` shadow.

    Cycle by cycle; in eclipse-season cycles the step is capped at
    ``max_step_s`` (None: free steps) so that eclipse edges are not stepped over.
    """
    times = cycle_sample_times(problem.n_cycles)
    ta.time = 0.0
    ta.state[:] = problem.cartesian[0]
    outcome, _, _, steps, _, first = ta.propagate_grid(times[0])
    _check_outcomes([outcome])
    for cycle in range(1, problem.n_cycles - 1):
        cap = {"max_delta_t": max_step_s} if max_step_s and seasons[cycle] else {}
        target = times[1][0] if cycle == problem.n_cycles - 2 else (cycle + 1) * SIDEREAL_DAY_S
        outcome, _, _, n, *_ = ta.propagate_until(target, **cap)
        _check_outcomes([outcome])
        steps += n
    outcome, _, _, n, _, last = ta.propagate_grid(times[1])
    _check_outcomes([outcome])
    samples = np.stack([first, last])
    return Outcome(mean_inclination_change_deg(samples, problem.force_model.mu_m3_s2), last[-1, :3]), steps + n


def accuracy_with_shadow(problem: Problem, runner: GeojaxRunner, config: Config) -> dict:
    """Shadow on: geojax per step vs heyoka with the ``hy.select`` shadow, steps capped in eclipse seasons.

    Also reports heyoka with free steps (which step over eclipse edges) and
    the size of the shadow's effect on Δi in geojax.
    """
    model = numpy_model.from_scenario(problem.scenario, shadow=True)
    ta, compile_s = build_heyoka(model, batch=False, compact_mode=True, shadow=True)
    seasons = eclipse_season_cycles(problem)
    (reference, ref_steps), ref_time = harness.timed(heyoka_shadow_outcome, ta, problem, seasons, SHADOW_MAX_STEP_S)
    (free, free_steps), free_time = harness.timed(heyoka_shadow_outcome, ta, problem, seasons, None)
    name = f"heyoka tol {HEYOKA_TOL:g}, select shadow, steps <= {SHADOW_MAX_STEP_S:g} s in eclipse seasons"
    rows = {
        name: _entry(reference, reference, taylor_steps=ref_steps, wall_s=ref_time.wall_s),
        f"heyoka tol {HEYOKA_TOL:g}, select shadow, free steps": _entry(
            free, reference, taylor_steps=free_steps, wall_s=free_time.wall_s),
    }
    shadow_effect = {}
    fm_on = problem.force_model._replace(shadow_on=1.0)
    for step_request in config.accuracy_steps:
        step_s = runner.environment(step_request)[1]
        on = geojax_outcome(runner, step_request, fm_on)
        off = geojax_outcome(runner, step_request)
        rows[f"geojax RK4 MEE {step_s:.1f} s"] = _entry(on, reference)
        shadow_effect[f"{step_s:.1f}"] = float(np.hypot(*(on.delta_i_deg - off.delta_i_deg)))
    return {"reference": name, "rows": rows, "goal_deg": GOAL_DEG, "eclipse_season_cycles": int(seasons.sum()),
            "heyoka_compile_s": compile_s, "shadow_effect_geojax_deg": shadow_effect}


# --- Output --------------------------------------------------------------------------------------


def ratios(rows: list[dict], batch: int) -> dict:
    """geojax orbits/s over each peer's, at ``batch`` (numbers from this run); SciPy is batch-independent."""
    peers = [r for r in rows if r["implementation"] == "heyoka" and r["batch"] == batch]
    peers += [r for r in rows if r["implementation"] == "numpy+scipy"]
    return harness.ratios({f"geojax {r['step_s']:.1f} s": r["orbits_per_s"] for r in rows
                           if r["implementation"] == "geojax" and r["batch"] == batch},
                          {f"{p['implementation']}, {p['setting']}": p["orbits_per_s"] for p in peers})


def throughput_markdown(results: dict) -> list[str]:
    rows = [[r["implementation"], r["setting"],
             "any (1 at a time)" if r["implementation"] == "numpy+scipy" else r["batch"],
             f"{r['compile_s']:.1f}", f"{r['run_s']:.2f}", f"{r['orbits_per_s']:.3g}", f"{r['cores_busy']:.2f}",
             f"{r['other_load_cores']:.2f}", f"{r['steal_cores']:.2f}"] for r in results["throughput"]]
    return ["## Throughput", "",
            *harness.table(["implementation", "setting", "batch", "compile s", "run s", "orbits/s", "cores busy",
                            "other load", "steal"], rows, align="llrrrrrrr"),
            "", f"Ratios at batch {results['config']['ratio_batch']}: orbits/s of geojax over the peer's "
            "(same run).", "",
            *harness.ratio_table(results["ratios"], "geojax")]


def accuracy_markdown(title: str, acc: dict) -> list[str]:
    has_tight = "tight_reference" in acc
    lines = [
        "",
        f"## {title}",
        "",
        "Δi = i(cos Ω, sin Ω) of the last one-cycle mean minus the first, degrees, unperturbed state; "
        f"diff = |Δi − Δi(reference)|, reference = {acc['reference']}; goal < {acc['goal_deg']:g}°."
        + (f" Tight reference: {acc['tight_reference']}." if has_tight else ""),
        "",
    ]
    if has_tight:
        lines += ["| propagator | Δi_x ° | Δi_y ° | abs Δi ° | diff ° | diff vs tight ° | final position error m |",
                  "|---|---:|---:|---:|---:|---:|---:|"]
    else:
        lines += ["| propagator | Δi_x ° | Δi_y ° | abs Δi ° | diff ° |", "|---|---:|---:|---:|---:|"]
    for name, e in acc["rows"].items():
        line = (f"| {name} | {e['delta_i_deg'][0]:.8f} | {e['delta_i_deg'][1]:.8f} | "
                f"{e['abs_delta_i_deg']:.8f} | {e['diff_vs_reference_deg']:.2e} |")
        if has_tight:
            line += f" {e['diff_vs_tight_deg']:.2e} | {e['final_position_error_m']:.3g} |"
        lines.append(line)
    return lines


def notes_markdown(results: dict) -> list[str]:
    c = results["config"]
    acc_on = results["accuracy_shadow_on"]
    ref_on = acc_on["rows"][acc_on["reference"]]
    free_on = next(e for name, e in acc_on["rows"].items() if name.endswith("free steps"))
    heyoka_default = next(r for r in results["throughput"]
                          if r["implementation"] == "heyoka" and r["tol"] == HEYOKA_TOL)
    mean_heyoka_step_h = c["t_end_s"] / heyoka_default["taylor_steps_per_orbit"] / 3600.0
    agree = results["model_agreement"]
    env_times = ", ".join(f"{r['step_s']:.0f} s step: {r['environment_grid_s']:.2f} s" for r in results["throughput"]
                          if r["implementation"] == "geojax" and r["batch"] == max(c["geojax_batches"]))
    return [
        "",
        "## Notes",
        "",
        "- orbits/s = batch / steady-state wall time of the propagation call; compile time is listed apart. "
        "geojax's environment grid (Sun, Moon, Earth angle at every RK4 stage, shared by the batch) is built "
        f"once per step and is not in 'run s' ({env_times}, including its jit).",
        "- 'cores busy' = this process's CPU time / wall time; 'other load' = CPU time of all other processes "
        "during the measurement / wall time; 'steal' = CPU time the hypervisor took from this virtual machine / "
        "wall time (both from /proc/stat, near 0 = undisturbed). When their sum exceeds "
        f"{DISTURBED_CORES} the measurement is repeated (up to 2 extra attempts, 1 for calls over "
        f"{LONG_CALL_S:.0f} s) and the fastest undisturbed call is kept, else the fastest. geojax splits the CPU into one XLA device per core "
        "(`XLA_FLAGS=--xla_force_host_platform_device_count`, set by the harness) and runs batches that split "
        "evenly over them as one single-device program per device on its share (`geojax.parallel.per_device`, "
        "as `geojax sweep` does; a jit sharded over the devices ran 2.8x slower: 87 against 242 orbit-years/s, "
        "120 days at batch 1024); batch 1 runs on one device; heyoka runs the SIMD batch integrator on one thread per core; SciPy is "
        "serial (one orbit per core; two processes could at most double its figure, which does not depend on "
        "the batch).",
        "- heyoka batch 1 uses the scalar integrator, larger batches the SIMD batch integrator; compile = cold "
        "LLVM JIT of the Taylor integrator with heyoka's disk cache off (default mode; compact mode compiles "
        "faster and runs slower); rebuilding the same batch integrator from heyoka's in-memory cache took "
        f"{c['heyoka_batch_rebuild_from_cache_s']:.2f} s. geojax compile = `jit(...).lower(...).compile()` "
        "(no persistent JAX cache configured).",
        "- Accuracy per setting (final-position error after one year against heyoka tol "
        f"{HEYOKA_TIGHT_TOL:g}, unperturbed state): "
        + "; ".join(f"{name}: {e['final_position_error_m']:.3g} m" for name, e in results["accuracy"]["rows"].items()
                    if name != f"heyoka tol {HEYOKA_TIGHT_TOL:g} (compact)")
        + f". heyoka is timed at tol {HEYOKA_TOL:g} as specified; extra tolerances in the throughput table show "
        "the cost of matching geojax's position accuracy.",
        "- Earth shadow: heyoka can express the conical shadow (`hy.select`), but it is not analytic at the "
        f"penumbra edges, and heyoka's mean step here ({mean_heyoka_step_h:.1f} h) is longer than an eclipse "
        "(at most ~1.2 h), so with free steps it extrapolates one branch across eclipse edges. The shadow is "
        "therefore off in all three implementations for the throughput and the main accuracy table. geojax "
        "evaluates the shadow term regardless (its switch is a multiplier), so its timings include that work. "
        "In geojax the shadow changes the one-year Δi by "
        + ", ".join(f"{v:.2e}° ({k} s step)" for k, v in acc_on["shadow_effect_geojax_deg"].items()) + ". "
        "The supplementary table repeats the comparison with the shadow on, against heyoka with its steps capped "
        f"in the {acc_on['eclipse_season_cycles']} eclipse-season cycles (Sun declination < 10°); that reference "
        f"takes {ref_on['taylor_steps']} Taylor steps ({ref_on['wall_s']:.1f} s) against "
        f"{free_on['taylor_steps']} with free steps, so it is not a throughput configuration.",
        f"- Model agreement (shadow on, {agree['points']} positions incl. {agree['points_in_umbra']} in umbra and "
        f"{agree['points_in_penumbra']} in penumbra): max |Δa| / |perturbing a| = "
        f"{agree['numpy_vs_geojax_max_rel']:.1e} (NumPy vs geojax), {agree['heyoka_vs_geojax_max_rel']:.1e} "
        "(heyoka vs geojax).",
        f"- Final positions of the timed batches, geojax vs heyoka tol {HEYOKA_TOL:g} (same initial states): "
        + "; ".join(f"{k} s step: median {v['median_m']:.3g} m, max {v['max_m']:.3g} m over {v['batch']} samples"
                    for k, v in results["final_position_agreement"].items())
        + " (mostly heyoka's own error at this tolerance, see the final-position column).",
        "- Batch samples: sample 0 is the li2022 initial state; the others perturb p by ±1 km and L by ±0.01 rad "
        f"(uniform, seed {c['seed']}).",
        "",
    ]


def markdown(results: dict, peers: dict) -> list[str]:
    c = results["config"]
    lines = [
        f"heyoka {peers['heyoka']} (SIMD width {peers['heyoka_simd_size']}), SciPy {peers['scipy']}. "
        f"Propagation: {c['n_cycles']} sidereal days (propagated_cycles({c['days']:g} d)), J2 + Sun + Moon + SRP "
        "(Li 2022, eq. (4)), **Earth shadow off in all three** (see Notes). Float64 everywhere.",
        "",
    ]
    lines += throughput_markdown(results)
    lines += accuracy_markdown("Accuracy, shadow off", results["accuracy"])
    lines += accuracy_markdown("Accuracy, shadow on (supplementary): heyoka with steps capped in eclipse seasons "
                               "as the reference", results["accuracy_shadow_on"])
    lines += notes_markdown(results)
    return lines


# --- Main ----------------------------------------------------------------------------------------


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="30-day smoke run with small batches")
    harness.add_arguments(parser)
    return parser.parse_args(argv)


def main(argv=None) -> None:
    args = parse_args(argv)
    config = QUICK if args.quick else FULL
    # geojax runs one XLA CPU device per core, each running the one-device program on its share of the batch
    # (geojax.parallel.per_device, as geojax sweep does), as heyoka runs one thread per core.
    run = harness.start(harness.Devices(platform=args.platform))
    # heyoka keeps compiled integrators in ~/.cache/heyoka; off, so compile times are cold.
    hy.llvm_state.set_diskcache_enabled(False)
    max_batch = max(config.geojax_batches + config.heyoka_batches + (config.scipy_orbits,))
    problem = make_problem(config.days, max_batch, config.seed)
    log(f"li2022, {problem.n_cycles} cycles ({config.days} d), shadow off; {len(harness.usable_cores())} cores")

    agreement = model_agreement(problem)
    log(f"model agreement: {agreement}")

    runner = GeojaxRunner(problem)
    log("geojax:")
    rows, geojax_finals = bench_geojax(runner, config)

    log("heyoka:")
    scalar = build_heyoka(problem.numpy_model, batch=False)
    batch_default = build_heyoka(problem.numpy_model, batch=True)
    _, batch_rebuild_s = build_heyoka(problem.numpy_model, batch=True, cold=False)
    heyoka_rows, heyoka_finals = bench_heyoka(problem, config, scalar, batch_default)
    rows += heyoka_rows
    finals_agreement = final_position_agreement(geojax_finals, heyoka_finals)

    log("numpy + scipy:")
    scipy_row, scipy_outcome = bench_scipy(problem, config)
    rows.append(scipy_row)

    log("accuracy:")
    acc = accuracy(problem, runner, config, scalar[0], scipy_outcome)
    acc_on = accuracy_with_shadow(problem, runner, config)
    for label, table in (("shadow off", acc), ("shadow on", acc_on)):
        log(f"  {label}, reference {table['reference']}:")
        for name, entry in table["rows"].items():
            log(f"    {name:72s} |Δi| {entry['abs_delta_i_deg']:.8f} deg, diff {entry['diff_vs_reference_deg']:.2e} deg")

    ratio_batch = max(config.geojax_batches)
    results = {
        "config": {**config._asdict(), "quick": args.quick, "n_cycles": problem.n_cycles,
                   "t_end_s": problem.t_end_s, "shadow": "off in all implementations (throughput, main accuracy)",
                   "heyoka_tol": HEYOKA_TOL, "heyoka_tight_tol": HEYOKA_TIGHT_TOL, "scipy_rtol": SCIPY_RTOL,
                   "scipy_atol": SCIPY_ATOL, "ratio_batch": ratio_batch,
                   "heyoka_batch_rebuild_from_cache_s": batch_rebuild_s},
        "throughput": rows,
        "ratios": ratios(rows, ratio_batch),
        "accuracy": acc,
        "accuracy_shadow_on": acc_on,
        "model_agreement": agreement,
        "final_position_agreement": finals_agreement,
    }
    peers = peer_versions()
    text = harness.write(args.out / NAME, run, f"GEO propagation throughput and accuracy, scenario li2022, "
                         f"{config.days:g} days", results, markdown(results, peers), facts=peers)
    print()
    print(text)


if __name__ == "__main__":
    main()
