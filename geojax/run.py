"""Uncontrolled propagation of a scenario: the orchestration behind ``geojax propagate`` and the demo."""

from __future__ import annotations

import functools
import math
import time
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.constants import SECONDS_PER_DAY, SIDEREAL_DAY_S
from geojax.dynamics import SpacecraftState
from geojax.progress import Progress
from geojax.propagate import DYNAMICS, CycleMeans, environment_grid, propagate_cycles, steps_per_cycle
from geojax.elements import wrap_angle
from geojax.scenario import Scenario


class PropagationResult(NamedTuple):
    cycles: CycleMeans  # numpy leaves [n_cycles]
    step_s: float  # the step actually used
    wall_s: float


def cycle_count(days: float) -> int:
    """Cycles for a run of ``days`` solar days.

    Cycle means refer to mid-cycle times, so the first and last means are
    ``n - 1`` cycles apart; n = ceil(days / sidereal day) + 1 makes that span
    at least ``days`` (365.25 days -> 368 cycles), so the change over exactly
    ``days`` can be read off by interpolation (``drift_summary``).
    """
    return max(1, math.ceil(days * SECONDS_PER_DAY / SIDEREAL_DAY_S - 1e-9) + 1)


def initial_state(scenario: Scenario) -> SpacecraftState:
    dynamics = DYNAMICS[scenario.dynamics]
    orbit = dynamics.from_mee(jnp.asarray(scenario.initial_mee), scenario.force_model.mu_m3_s2)
    return SpacecraftState(orbit, jnp.asarray(scenario.mass_kg), jnp.asarray(0.0))


def propagate_scenario(scenario: Scenario, progress: bool | None = None) -> PropagationResult:
    """Propagate a scenario without control; one-cycle mean elements per sidereal day.

    The run is cut into at most 20 equal blocks of cycles so a progress bar
    can be drawn; every block reuses one compiled function.
    """
    start = time.perf_counter()
    n_steps = steps_per_cycle(scenario.step_s)
    step_s = SIDEREAL_DAY_S / n_steps
    n_cycles = cycle_count(scenario.days)
    block = math.ceil(n_cycles / min(20, n_cycles))
    n_blocks = math.ceil(n_cycles / block)
    dynamics = DYNAMICS[scenario.dynamics]
    run_block = jax.jit(lambda state, env, fm: propagate_cycles(dynamics, state, env, fm, step_s))

    state = initial_state(scenario)
    pieces = []
    with Progress(n_cycles, "cycles", enabled=progress) as bar:
        for b in range(n_blocks):
            block_epoch = scenario.epoch_tt_s + b * block * SIDEREAL_DAY_S
            env = environment_grid(
                block_epoch, scenario.epoch_tt_s, scenario.tt_minus_ut1_s, step_s, block, n_steps
            )
            state, means = run_block(state, env, scenario.force_model)
            means = means._replace(t_s=means.t_s + b * block * SIDEREAL_DAY_S)
            pieces.append(jax.tree_util.tree_map(np.asarray, means))
            bar.update(min(block, n_cycles - b * block))
    cycles = jax.tree_util.tree_map(lambda *xs: np.concatenate(xs)[:n_cycles], *pieces)
    return PropagationResult(cycles, step_s, time.perf_counter() - start)


def cycles_table(cycles: CycleMeans) -> dict[str, np.ndarray]:
    """The ``/cycles`` datasets of ``geojax propagate`` in their edge units (degrees, days)."""
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


class SimulationResult(NamedTuple):
    cycles: dict[str, np.ndarray]  # the /cycles datasets
    metrics: dict[str, float]  # the /metrics datasets
    reference: dict[str, np.ndarray]  # the /reference datasets: uncontrolled mean elements at cycle boundaries
    target: dict[str, float]  # the station's targets (/target)
    wall_s: float


class ClosedLoop(NamedTuple):
    """Everything a closed-loop rollout of a scenario needs, built once and shared by a batch."""

    state: SpacecraftState
    cycles_env: object  # Environment leaves [n_cycles, n_steps, 3, ...]
    reference: object  # control.predictor.Reference at n_cycles + REFERENCE_PAD_CYCLES + 1 boundaries
    params: object  # simulate.LoopParams
    step_s: float
    n_cycles: int
    controller: str  # "qffc" or "fompc"
    annealing: object  # control.fompc.Annealing (static)


# The uncontrolled reference runs this many cycles past the end, for the FOMPC's horizon (N <= 10)
# and the V_DT estimate's look at the next cycle.
REFERENCE_PAD_CYCLES = 12


def closed_loop_setup(scenario: Scenario, horizon_max: int | None = None) -> ClosedLoop:
    """Environment grid, uncontrolled reference and loop parameters of a QFFC or FOMPC scenario.

    The FOMPC's horizon is padded to ``horizon_max`` cycles (static; default the
    scenario's N): a sweep over N passes its largest N and compiles once, and a
    single run plans over exactly its N (the padded cycles are masked out of
    the cost but still evaluated, so padding to 10 would cost 10/N).
    """
    from geojax.control.fompc import Annealing
    from geojax.simulate import CONTROLLERS

    if scenario.controller not in CONTROLLERS:
        raise ValueError(
            f"controller.kind: 'geojax simulate' needs one of {', '.join(CONTROLLERS)}, got {scenario.controller!r}"
        )
    cfg = scenario.config
    n_steps = steps_per_cycle(scenario.step_s)
    step_s = SIDEREAL_DAY_S / n_steps
    n_cycles = max(1, round(scenario.days * SECONDS_PER_DAY / SIDEREAL_DAY_S))
    n_env = n_cycles + REFERENCE_PAD_CYCLES
    env = environment_grid(scenario.epoch_tt_s, scenario.epoch_tt_s, scenario.tt_minus_ut1_s, step_s, n_env, n_steps)
    state = initial_state(scenario)
    ref = _reference(state, env, scenario.force_model, step_s)
    params = loop_params(scenario)
    ctl = cfg["controller"]
    horizon_max = ctl["horizon"] if horizon_max is None else horizon_max
    if not ctl["horizon"] <= horizon_max <= Annealing().n_max:
        raise ValueError(f"horizon_max: must lie in [controller.horizon, {Annealing().n_max}], got {horizon_max}")
    annealing = Annealing(n_max=horizon_max, chains=ctl["chains"], iterations=ctl["iterations"])
    cycles_env = jax.tree_util.tree_map(lambda x: x[:n_cycles], env)
    return ClosedLoop(state, cycles_env, ref, params, step_s, n_cycles, scenario.controller, annealing)


def loop_params(scenario: Scenario):
    """The ``simulate.LoopParams`` of a scenario: every value a sweep may vary, as array leaves."""
    from geojax.control.fompc import MpcParams
    from geojax.propulsion import arm_limits_deg
    from geojax.simulate import NOMINAL_3SIGMA_ATT_DEG, NOMINAL_3SIGMA_R_M, NOMINAL_3SIGMA_V_MPS, LoopParams

    cfg = scenario.config
    t, st, err, ctl = cfg["thrusters"], cfg["station"], cfg["errors"], cfg["controller"]
    return LoopParams(
        arm_limits_deg(t["beta_max_deg"], t["beta_min_deg"], t["alpha_max_deg"], t["alpha_min_deg"]),
        jnp.asarray(float(t["thrust_n"])), jnp.asarray(float(t["isp_s"])), jnp.asarray(float(t["min_burn_s"])),
        jnp.array([np.radians(st["lon_deg"]), 0.0, st["ex"], st["ey"], st["ix"], st["iy"]]),
        sigma_r_m=jnp.asarray(err["h_rv"] * NOMINAL_3SIGMA_R_M / 3),
        sigma_v_mps=jnp.asarray(err["h_rv"] * NOMINAL_3SIGMA_V_MPS / 3),
        sigma_att_rad=jnp.asarray(np.radians(err["h_att"] * NOMINAL_3SIGMA_ATT_DEG / 3)),
        vdt_estimate=jnp.asarray(float(ctl["vdt_estimate"])),
        mpc=MpcParams(jnp.asarray(ctl["horizon"]), jnp.asarray(float(ctl["di_max"])), jnp.asarray(float(ctl["penalty"]))),
    )


@functools.partial(jax.jit, static_argnames=("step_s",))
def _reference(state, env, fm, step_s):
    from geojax.control.predictor import reference

    return reference(state, env, fm, step_s)


@functools.partial(jax.jit, static_argnames=("step_s", "controller", "annealing"))
def closed_loop_rollout(loop_state, env, fm, ref, params, key, step_s, controller, annealing):
    """``simulate.rollout``, compiled once per (shapes, step, controller, annealing) and reused."""
    from geojax.simulate import rollout

    return rollout(loop_state, env, fm, step_s, ref, params, key, controller, annealing)


def run_closed_loop(loop: ClosedLoop, fm, key):
    """One rollout of a set-up closed loop; (final state, CycleRecord)."""
    return closed_loop_rollout(loop.state, loop.cycles_env, fm, loop.reference, loop.params, key,
                               step_s=loop.step_s, controller=loop.controller, annealing=loop.annealing)


def simulate_scenario(scenario: Scenario, seed: int = 0) -> SimulationResult:
    """Closed-loop run of a scenario (``controller.kind`` "qffc" or "fompc"): per-cycle records and metrics.

    ``seed`` draws the orbit-determination and attitude errors (``[errors]``)
    and the FOMPC's annealing; same seed, same result.
    """
    start = time.perf_counter()
    loop = closed_loop_setup(scenario)
    final, rec = run_closed_loop(loop, scenario.force_model, jax.random.key(seed))
    rec, final = jax.tree_util.tree_map(np.asarray, (rec, final))
    wall_s = time.perf_counter() - start
    target = np.asarray(loop.params.target)
    ref_mean = np.asarray(loop.reference.mean)[: loop.n_cycles + 1]
    uncontrolled = {"t_s": np.arange(loop.n_cycles + 1) * SIDEREAL_DAY_S, "lon_deg": np.degrees(ref_mean[:, 0]),
                    "ex": ref_mean[:, 3], "ey": ref_mean[:, 4], "ix": ref_mean[:, 5], "iy": ref_mean[:, 6]}
    goals = dict(zip(("lon_deg", "drift_deg_per_day", "ex", "ey", "ix", "iy"),
                     [float(np.degrees(target[0])), 0.0, *map(float, target[2:])]))
    metrics = _metrics(rec, final, target, loop.n_cycles, wall_s)
    return SimulationResult(_cycle_records(rec), metrics, uncontrolled, goals, wall_s)


def _cycle_records(rec) -> dict[str, np.ndarray]:
    table = cycles_table(rec.means)
    dv = rec.burns.dv_rsw_mps  # [n, 2, 3]
    fired = rec.burn_s > 0
    table.update({
        "max_abs_lat_deg": np.degrees(rec.means.max_abs_lat_rad),
        "v1_mps": np.where(fired[:, 0], rec.burns.v_mps[:, 0], 0.0),
        "v2_mps": np.where(fired[:, 1], rec.burns.v_mps[:, 1], 0.0),
        "alpha1_deg": np.degrees(rec.burns.alpha_rad[:, 0]),
        "beta1_deg": np.degrees(rec.burns.beta_rad[:, 0]),
        "alpha2_deg": np.degrees(rec.burns.alpha_rad[:, 1]),
        "beta2_deg": np.degrees(rec.burns.beta_rad[:, 1]),
        "l1_deg": np.degrees(np.mod(rec.burns.l_rad[:, 0], 2 * np.pi)),
        # Li 2022, eq. (45).
        "dv_ns_mps": np.sum(np.where(fired, np.abs(dv[..., 2]), 0.0), axis=1),
        "burn1_s": rec.burn_s[:, 0],
        "burn2_s": rec.burn_s[:, 1],
        "ns_fraction": rec.fraction,
        "status": np.where(rec.burns.feasible, 0, 1).astype(np.int8),
    })
    return table


def _metrics(rec, final, target, n_cycles: int, wall_s: float) -> dict[str, float]:
    from geojax.metrics import closed_loop_metrics

    metrics = {name: float(value) for name, value in closed_loop_metrics(rec, final, target, n_cycles).items()}
    return {**metrics, "cpu_s_per_orbit": wall_s / n_cycles}


class FeedbackSetup(NamedTuple):
    """A feedback-law scenario (``controller.kind = "lyapunov"``), built once and shared by a batch."""

    state: SpacecraftState
    env: object  # Environment leaves [n_days, n_steps, 3, ...]
    params: object  # feedback.FeedbackParams
    step_s: float
    mode: str  # thrust_laws.MODES
    dynamics: str  # "mee" or "cartesian"
    box_half_width_rad: float


def feedback_setup(scenario: Scenario) -> FeedbackSetup:
    """Initial state, environment grid and parameters of a Katz 2025 feedback scenario."""
    if scenario.controller != "lyapunov":
        raise ValueError(f"controller.kind: a feedback rollout needs 'lyapunov', got {scenario.controller!r}")
    n_steps = steps_per_cycle(scenario.step_s)
    step_s = SIDEREAL_DAY_S / n_steps
    n_days = max(1, round(scenario.days * SECONDS_PER_DAY / SIDEREAL_DAY_S))
    env = environment_grid(scenario.epoch_tt_s, scenario.epoch_tt_s, scenario.tt_minus_ut1_s, step_s, n_days, n_steps)
    cfg = scenario.config
    return FeedbackSetup(initial_state(scenario), env, feedback_params(scenario), step_s,
                         cfg["controller"]["thrust_mode"], scenario.dynamics,
                         math.radians(cfg["station"]["box_half_width_deg"]))


def feedback_params(scenario: Scenario):
    """The ``feedback.FeedbackParams`` of a scenario, SI units (gains as array leaves)."""
    from geojax import constants as c
    from geojax.control import lyapunov
    from geojax.feedback import FeedbackParams
    from geojax.thrust_laws import ThrustLimits

    cfg = scenario.config
    ctl, st = cfg["controller"], cfg["station"]
    sigma = ctl["sigma_km_per_s2"] or [0.0, 0.0, 0.0]
    f = lambda x: jnp.asarray(float(x))  # noqa: E731
    return FeedbackParams(
        gains=lyapunov.LyapunovGains(f(ctl["k_h_per_km2_s"] * lyapunov.K_H_PAPER_TO_SI),
                                     f(ctl["k_e_km2_per_s3"] * lyapunov.K_E_PAPER_TO_SI),
                                     f(ctl["k_lambda_km_per_rad"] * lyapunov.K_LAMBDA_PAPER_TO_SI),
                                     f(math.radians(ctl["lambda_b_deg"]))),
        limits=ThrustLimits(f(ctl["u0_km_per_s2"] * 1e3), jnp.asarray(sigma) * 1e3),
        station=lyapunov.Station(f(math.radians(st["lon_deg"])), f(st["radius_km"] * 1e3),
                                 f(c.OMEGA_EARTH_RAD_S), f(scenario.force_model.mu_m3_s2)),
        isp_s=f(cfg["thrusters"]["isp_s"]),
    )


@functools.partial(jax.jit, static_argnames=("dynamics", "step_s", "mode", "smooth"))
def feedback_rollout(state, env, fm, params, box_half_width_rad, dynamics: str, step_s: float, mode: str,
                     smooth: bool = False):
    """``feedback.rollout`` and its metrics, compiled once per (shapes, dynamics, step, mode, smooth)."""
    from geojax import feedback

    final, records = feedback.rollout(DYNAMICS[dynamics], state, env, fm, step_s, params, mode, smooth)
    summary = feedback.metrics(state, final, records, step_s, params.station.lon_rad, box_half_width_rad)
    return final, records, summary


def run_feedback(setup: FeedbackSetup, fm, params=None, smooth: bool = False):
    """One rollout of a set-up feedback scenario (its own parameters unless ``params`` is given)."""
    return feedback_rollout(setup.state, setup.env, fm, setup.params if params is None else params,
                            setup.box_half_width_rad, dynamics=setup.dynamics, step_s=setup.step_s,
                            mode=setup.mode, smooth=smooth)


class FeedbackResult(NamedTuple):
    metrics: dict[str, float]  # the /metrics datasets
    steps: dict[str, np.ndarray]  # the /steps datasets: per integration step
    wall_s: float


def simulate_feedback(scenario: Scenario) -> FeedbackResult:
    """Closed-loop run of a Milankovitch-Lyapunov scenario: metrics and the per-step history."""
    start = time.perf_counter()
    setup = feedback_setup(scenario)
    final, records, summary = run_feedback(setup, scenario.force_model)
    records = jax.tree_util.tree_map(np.asarray, records)
    wall_s = time.perf_counter() - start
    metrics = {name: float(value) for name, value in summary._asdict().items()}
    metrics["mass_used_kg"] = float(setup.state.mass_kg - final.mass_kg)
    u = records.u_ecef_mps2.reshape(-1, 3)
    steps = {
        "t_s": np.arange(u.shape[0]) * setup.step_s,
        "dlon_deg": np.degrees(np.asarray(wrap_angle(records.lon_rad.ravel() - float(setup.params.station.lon_rad)))),
        "lat_deg": np.degrees(records.lat_rad.ravel()),
        "ux_mps2": u[:, 0], "uy_mps2": u[:, 1], "uz_mps2": u[:, 2],
    }
    return FeedbackResult(metrics, steps, wall_s)
