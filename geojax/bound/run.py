"""``bound``: the least Delta-V that holds a scenario's box with its thrusters, and its re-simulation.

1. The uncontrolled reference run (the closed loop with the null controller) is the first nominal; the
   linear model about it (``bound.linear``) and the linear program (``bound.program``) give the least-fuel
   slot Delta-Vs, a lower bound over the continuous direction sets, and their gap.
2. Sequential linearisation: the plan is flown through the same RK4 steps and forces, the model is rebuilt
   about that trajectory, and the program is solved again, until the flown plan holds the box at every step
   start (usually one or two rounds: the reference drifts 4 deg in a year, the controlled orbit does not).
3. The final plan is re-simulated in the closed loop (``geojax.simulate`` with the ``replay`` controller):
   true mass and mass flow, the thrust on/off at the scenario's F with the slot's duty, the box checked at
   every step by the loop's own status.  The gap between the program's Delta-V and the re-simulation's is
   reported.

The bound is the least fuel of any thrust history that is constant in RSW over each slot (``slot_steps``
integration steps; 1 h by default) with the same thrusters (directions, F, one at a time, not in shadow where
the geometry says so), the same box at every step start, from the same initial state, ending where it started:
Gazzino 2016's x(T) = x(0) (Problem 3), the orbit state at the horizon's end equal to the initial one, its true
longitude one turn per sidereal cycle on -- a periodic plan, one that can be flown again the next period, so
its Delta-V per year is a steady state's.  ``free_end=True`` drops that condition (the free end): the plan
may end anywhere in the box and keep the difference, so over a short horizon it spends less than a steady
state can (its program is the periodic one less six equality rows, so its optimum about the same
trajectory is never above the periodic one's).  ``lower_mps`` is rigorous for that
problem's linear model (weak duality, ``bound.program``); how it moves with the slot length is measured
(``studies/bounds``), not assumed.
"""

from __future__ import annotations

import time
from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.bound import program, report
from geojax.bound.directions import Geometry, geometry_of
from geojax.bound.linear import SlotModel, linearize
from geojax.control.base import Controller, no_plan, stateless_init
from geojax.control.burns import sunlit_fraction
from geojax.loop.metrics import SECONDS_PER_YEAR
from geojax.runner.setup import prepare, unstack
from geojax.physics.constants import G0_MPS2
from geojax.physics.dynamics import Thrust
from geojax.scenario import Scenario, from_dict, to_toml

# The program holds the box shrunk by this fraction, so that the flown plan (nonlinear) holds the full box.
BOX_MARGIN = 1e-3
# Cost per m/s of change from the nominal plan in the rounds after the first (per m/s of fuel: 1).
PROX = 1e-3
# Stage length where the uncontrolled run is too far for one linear model (see ``bound``).
STAGE_DAYS = 90.0


class BoundResult(NamedTuple):
    scenario: str
    geometry: str
    days: float  # horizon, solar days (whole sidereal-day cycles)
    slot_s: float
    fuel_mps: float  # the program's optimum over the horizon (an achievable plan in the linear model)
    lower_mps: float  # rigorous lower bound over the continuous direction sets (linear model)
    bound_per_year_mps: float  # lower_mps per year
    plan_per_year_mps: float  # fuel_mps per year
    resim: dict  # the closed loop's metrics of the re-simulated plan (dv_per_year_mps, max_abs_dlon_deg, ...)
    resim_status: int
    linear_error_deg: float  # largest |nonlinear - linear| of (lon, lat) over the last round's steps
    max_abs_box_deg: float  # largest |lon - station|, |lat| of the flown plan after the acquisition
    rounds: list  # per linearisation: dict(fuel_mps, max_abs_box_deg, prox, columns, solve_s, linear_error_deg)
    t_s: np.ndarray  # [S] slot mid-times since the start
    u_rsw_mps: np.ndarray  # [S, 3] Delta-V per slot
    thruster_mps: np.ndarray  # [S, n_thrusters] Delta-V per slot per thruster
    lon_deg: np.ndarray  # [S, T] longitude less the station's at every step start (flown plan)
    lat_deg: np.ndarray  # [S, T] latitude
    wall_s: float
    # What its file records (``bound.report``): the arguments that shaped the program and the scenario's TOML.
    acquisition_days: float = 0.0
    free_end: bool = False
    config_toml: str = ""
    epoch_tt_s: float = float("nan")

    # What ``geojax bound`` writes (``--out``), prints and draws (``--plots``): its report's functions.
    save, summary, plot = report.save, report.summary, report.plot


def bound(sc: Scenario, *, slot_steps: int = 4, thrusters: str | None = None, acquisition_days: float = 0.0,
          iterations: int = 4, rounds: int = 8, rtol: float = 1e-3, free_end: bool = False,
          say: Callable = lambda *a, **k: None) -> BoundResult:
    """The fuel bound of scenario ``sc`` over its duration (see the module docstring).

    ``slot_steps`` integration steps per control slot (must divide the steps of a sidereal day);
    ``thrusters`` the geometry (``arms``, ``gimbal``, ``fixed4``; default from the scenario);
    ``acquisition_days``: the box is held from then on (a start the thrusters cannot keep in the box at once,
    as Katz 2025's 2 km offset; the closed loop's status still counts the acquisition);
    ``iterations`` linearisation rounds at most; ``rounds`` column-generation rounds per program;
    ``rtol`` the relative gap between the plan and the lower bound at which column generation stops;
    by default the plan ends where it started (Gazzino's x(T) = x(0): the MEE p, f, g, h, k at the end equal
    the initial ones and L the initial one plus the Earth's rotation over the horizon; each round's
    ``terminal_miss`` is the flown end state less that target, SI); ``free_end``: no end condition.
    Raises ``ValueError`` (``program.Infeasible``) when the box cannot be held.
    """
    start = time.perf_counter()
    geometry = geometry_of(sc.config, thrusters)
    uncontrolled = _uncontrolled(sc)
    batch = prepare([uncontrolled])
    params = unstack(batch.params, 0)
    env = batch.shared.env
    n_cycles, n_steps = env.earth_angle_rad.shape[:2]
    if slot_steps < 1 or n_steps % slot_steps:
        raise ValueError(f"bound.slot_steps: must divide the {n_steps} integration steps of a sidereal day, got {slot_steps}")
    n_slots = n_cycles * n_steps // slot_steps
    slot_s = slot_steps * batch.step_s
    env_slots = jax.tree_util.tree_map(lambda x: x.reshape((n_slots, slot_steps) + x.shape[2:]), env)
    mass_kg = float(params.initial.mass_kg)
    thrust_n = float(params.thrusters["thrust_n"])
    box = float(params.station["box_half_width_rad"])
    cap = np.full(n_slots, thrust_n / mass_kg * slot_s)
    if geometry.dark_off:
        steps = jax.tree_util.tree_map(lambda x: x.reshape((n_cycles * n_steps,) + x.shape[2:]), env)
        lit = np.asarray(sunlit_fraction(steps, params.station["lon_rad"], params.forces))
        cap = cap * lit.reshape(n_slots, slot_steps).mean(axis=1)
    exhaust_mps = float(params.thrusters["isp_s"]) * G0_MPS2

    def model_of(u, fuel):
        spent = np.concatenate([[0.0], np.cumsum(fuel)[:-1]])  # Delta-V before each slot (rocket equation)
        return jax.tree_util.tree_map(np.asarray, linearize(
            params.initial.orbit, jnp.asarray(u), env_slots, params.forces, jnp.asarray(mass_kg * np.exp(-spent / exhaust_mps)),
            params.station["lon_rad"], slot_s=slot_s, step_s=batch.step_s, dynamics=batch.dynamics))

    u = np.zeros((n_slots, 3))
    model = model_of(u, np.zeros(n_slots))
    if not 0 <= acquisition_days < n_cycles * n_steps * batch.step_s / 86400.0:
        raise ValueError(f"bound.acquisition_days: must be >= 0 and shorter than the horizon, got {acquisition_days!r}")
    first = int(np.ceil(acquisition_days * 86400.0 / slot_s - 1e-9))
    start_lon, start_lat = np.degrees(np.abs(model.y[0, 0]))
    if first == 0 and max(start_lon, start_lat) > np.degrees(box):
        raise program.Infeasible(f"the initial state is outside the box: |dlon| {start_lon:.4f} deg, |lat| "
                                 f"{start_lat:.4f} deg, box +-{np.degrees(box):g} deg (station.box_half_width_deg)")
    history, solution = [], None
    target = np.asarray(params.initial.orbit, float).copy()  # x(T) = x(0), the Earth turned n_cycles times since
    angle = np.asarray(env.earth_angle_rad)
    target[5] += 2 * np.pi * n_cycles + float(np.angle(np.exp(1j * (angle[-1, -1, -1] - angle[0, 0, 0]))))

    def terminal_dx(model, horizon):
        return target - model.x[horizon] if not free_end and horizon == n_slots else None

    def linearisations(horizon, u, model, solution, prox):
        """Sequential linearisation of the program over the first ``horizon`` slots (the rest coasts)."""
        for i in range(iterations):
            head = _head(model, horizon)
            solution = program.solve(head, u[:horizon], cap[:horizon], box * (1 - BOX_MARGIN), geometry,
                                     float(model.x[0, 0]), rounds=rounds, rtol=rtol, prox=prox, first_boxed_slot=first,
                                     generators=None if solution is None else solution.generators,
                                     terminal_dx=terminal_dx(model, horizon))
            predicted = _linear_outputs(head, solution, u[:horizon])
            u = np.concatenate([solution.u_mps, u[horizon:] * 0.0])
            fuel = np.concatenate([sum(w.sum(axis=1) for w in solution.w_mps), np.zeros(n_slots - horizon)])
            model = model_of(u, fuel)
            worst = float(np.degrees(np.max(np.abs(model.y[first:horizon]))))
            history.append({"fuel_mps": solution.fuel_mps, "max_abs_box_deg": worst, "prox": prox, "slots": horizon,
                            "columns": int(sum(len(g) for g in solution.generators)), "solve_s": solution.solve_s,
                            "linear_error_deg": float(np.degrees(np.max(np.abs(predicted - model.y[:horizon])))),
                            **({} if free_end else {"terminal_miss": model.x[n_slots] - target})})
            say(f"  linearisation {len(history)} ({horizon * slot_s / 86400:.0f} days): plan {solution.fuel_mps:.4f} m/s; "
                f"flown, max |box| {worst:.5f} deg of {np.degrees(box):g}, {history[-1]['linear_error_deg']:.1e} deg "
                f"from the linear model ({solution.solve_s:.1f} s)", flush=True)
            if worst <= np.degrees(box):
                break
            prox = PROX  # from now on, of the plans of least fuel the one nearest the nominal
        return u, fuel, model, solution

    try:
        u, fuel, model, solution = linearisations(n_slots, u, model, solution, 0.0)
    except program.Infeasible:
        # About the uncontrolled run the program may be infeasible where the flown one is not: the run drifts
        # too far for the linear model (katz2025 at 10 deg E with C22: tens of degrees in a year).  Plan in
        # stages: each one's model is linearised about the plan so far, coasting only over the new stage.
        stage = int(np.ceil(max(STAGE_DAYS, acquisition_days + 30.0) * 86400.0 / slot_s))
        if stage >= n_slots:
            raise
        say(f"  infeasible about the uncontrolled run; planning in stages of {stage * slot_s / 86400:.0f} days", flush=True)
        history.clear()
        u, model, solution = np.zeros((n_slots, 3)), model_of(np.zeros((n_slots, 3)), np.zeros(n_slots)), None
        for horizon in [*range(stage, n_slots, stage), n_slots]:
            u, fuel, model, solution = linearisations(horizon, u, model, solution, PROX if solution else 0.0)
    # The bound: the unrestricted program about the flown trajectory, over the full box.
    lower = program.solve(model, u, cap, box, geometry, float(model.x[0, 0]), rounds=rounds, rtol=rtol,
                          generators=solution.generators, first_boxed_slot=first, terminal_dx=terminal_dx(model, n_slots))
    say(f"  bound about the flown trajectory: {lower.lower_mps:.4f} m/s ({lower.rounds} pricing rounds, "
        f"{lower.solve_s:.1f} s)", flush=True)
    result = _resimulate(uncontrolled, u, fuel, slot_steps, slot_s, geometry)
    per_year = SECONDS_PER_YEAR / (n_cycles * n_steps * batch.step_s)
    per_thruster = np.stack([w.sum(axis=1) for w in solution.w_mps], axis=1)
    return BoundResult(
        sc.name, geometry.name, n_cycles * n_steps * batch.step_s / 86400.0, slot_s, solution.fuel_mps,
        lower.lower_mps, lower.lower_mps * per_year, solution.fuel_mps * per_year,
        {k: float(v) for k, v in result.metrics.items()}, int(result.status), history[-1]["linear_error_deg"],
        history[-1]["max_abs_box_deg"],
        history, (np.arange(n_slots) + 0.5) * slot_s, u, per_thruster, np.degrees(model.y[..., 0]),
        np.degrees(model.y[..., 1]), time.perf_counter() - start, float(acquisition_days), bool(free_end),
        to_toml(sc.config), sc.epoch_tt_s)


def _head(model: SlotModel, horizon: int) -> SlotModel:
    return SlotModel(model.x[:horizon + 1], *(a[:horizon] for a in model[1:]))


def _uncontrolled(sc: Scenario) -> Scenario:
    config = {k: {f: x for f, x in v.items() if x is not None} if isinstance(v, dict) else v
              for k, v in sc.config.items()}
    config["controller"] = {"kind": "none"}
    return from_dict(config)


def _linear_outputs(model, solution, u_nominal):
    """(lon, lat) at every step start [S, T, 2] that the linear model predicts for the program's solution."""
    dx = np.concatenate([np.zeros((1, 6)), solution.dx[:-1]])  # state deviation at each slot's start
    return (model.y + np.einsum("ktoj,kj->kto", model.c, dx)
            + np.einsum("ktoj,kj->kto", model.e, solution.u_mps - u_nominal))


def replay(u_rsw_mps, fuel_mps, slot_steps: int, slot_s: float, concurrent: int = 1) -> Controller:
    """A controller that flies slot Delta-Vs: the resultant u [S, 3] (RSW, m/s) of burns whose magnitudes add
    up to ``fuel_mps`` [S] (the thrusters time-share the slot along their own directions).

    Each step fires at the scenario's thrust (times ``concurrent`` thrusters) with the duty that spends the
    slot's fuel at the true mass; ``Thrust.direction_rsw`` is the resultant over the fuel (norm <= 1), so the
    orbit feels the time-shared burns' mean acceleration and the delivered Delta-V and the mass flow count
    every burn (firing d1 then d2 within a step differs from their mean acceleration at second order).
    """
    accel = jnp.asarray(np.asarray(u_rsw_mps) / slot_s)
    spend = jnp.asarray(np.maximum(np.asarray(fuel_mps), np.linalg.norm(u_rsw_mps, axis=1)) / slot_s)

    def thrust(params, plan, t, state, environment):
        k = jnp.clip(jnp.round(t / environment.step_s).astype(int) // slot_steps, 0, accel.shape[0] - 1)
        force_n = concurrent * params.thrusters["thrust_n"]
        on = spend[k] > 0
        direction = jnp.where(on, accel[k] / jnp.where(on, spend[k], 1.0), jnp.array([0.0, 1.0, 0.0]))
        return Thrust(direction, force_n, params.thrusters["isp_s"], jnp.clip(spend[k] * state.mass_kg / force_n, 0, 1))

    return Controller(stateless_init, no_plan, thrust)


def _resimulate(uncontrolled: Scenario, u, fuel, slot_steps, slot_s, geometry: Geometry):
    from geojax.runner.rollout import simulate

    concurrent = 1 if geometry.one_at_a_time else len(geometry.generators)
    return simulate(uncontrolled, 0, controller=replay(u, fuel, slot_steps, slot_s, concurrent), keep_steps=False)

