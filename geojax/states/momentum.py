"""The reaction wheels' momentum of a nadir-pointing body, a state of the loop.

The body points at nadir (``physics.attitude.nadir_frame``); its inner attitude loop holds that attitude with
three reaction wheels along the body axes, and the attitude errors are neglected at the station-keeping time
scale (Caverly, Di Cairano & Weiss, IEEE TCST 2021, doi:10.1109/TCST.2020.3014601).  The wheels' momentum h_w
(body axes, N m s) is what the wheels store to hold it.

The equation.  The total angular momentum of body and wheels, in body axes, is H = I omega + h_w, with I the
body's inertia tensor (wheels included) and omega the body's rate relative to inertial space.  Euler's law holds
in an inertial frame: dH/dt|_inertial = tau_ext, the external torque.  Seen from the body frame, which turns at
omega, dH/dt|_inertial = dH/dt|_body + omega x H.  The attitude loop holds the nadir attitude, so omega = (0, -n,
0), the orbit rate about the orbit normal (``physics.attitude.body_rate_rad_s``), and I omega is constant in body
axes: d(I omega)/dt|_body = 0.  Hence

    dh_w/dt|_body = tau_ext - omega x (I omega + h_w).

How it is integrated.  The same equation read in the inertial frame is dH/dt = tau_ext: H in ECI is the
integral of the torque, and the wheels' momentum is h_w = C(t) H_eci - I omega, C(t) the ECI -> body rotation.
The loop carries H_eci, adds each step's torque impulse by the trapezoid rule over the step's two ends (the
torques turn at the orbit rate: relative error (n h)^2 / 12 per step, 3.6e-4 at 900 s), and turns it into body
axes at every step's end.  The gyroscopic term omega x H is then exact (no truncation error: without torque |H|
is conserved to rounding, ``tests/test_momentum.py``).  The torques (ECI):

* solar radiation pressure at a centre-of-pressure offset d from the centre of mass: tau = d x F_srp, F_srp the
  force the orbit feels (``physics.attitude.srp_force_eci_n``); d = C^T d_body + A^T d_array, given in body axes
  (``attitude.srp_offset_body_m``) and in the Sun-tracking array's frame (``attitude.srp_offset_array_m``: along
  its axis, the orbit normal; across it; along its normal, ``physics.attitude.array_frame``);
* the gravity gradient of the inertia tensor (``attitude.inertia_kg_m2``, products of inertia included):
  tau_b = 3 mu / r^5 (r_b x I r_b).  At nadir, r_b = (0, 0, -r) and tau_b = 3 n^2 (-I_yz, I_xz, 0): zero for
  principal body axes (the default tensor), constant for a product of inertia.

Thruster torques (the thrust lines' offsets from the centre of mass) and dumping are not modelled yet: every
controller fires through the centre of mass (docs/momentum.md says what is not built yet).

The default inertia tensor (``DEFAULT_INERTIA_KG_M2``) is an estimate for a satellite of Li 2022's class (5000
kg, 200 m^2 of SRP area), no manufacturer publishing one: a 4600 kg bus as a uniform box 2.5 m (x) x 2.5 m (y) x
3.5 m (z), and two 200 kg wings of 20 m x 5 m (100 m^2 each) on the y axis (the array axis), their centres 12.75
m from the centre of mass, as thin plates turning about y (their width's share of Ixx and Izz averaged over the
turn): Ixx = 7091.7 + 78358.3 + 416.7, Iyy = 7091.7 + 833.3, Izz = 4791.7 + 78358.3 + 416.7 kg m^2, principal.
The default capacity, 50 N m s per wheel, is the wheels planned for Li's satellite with a centre-of-pressure
offset (the li2022-momentum scenario to come).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.physics.attitude import (array_frame, body_rate_rad_s, gravity_gradient_torque_body, inertia_matrix,
                                     nadir_frame, srp_force_eci_n)
from geojax.physics.constants import SECONDS_PER_DAY
from geojax.states.base import StateModel, StepContext

NAME = "wheels"
# (Ixx, Iyy, Izz, Ixy, Ixz, Iyz), kg m^2: the estimate of the module docstring.
DEFAULT_INERTIA_KG_M2 = (85866.7, 7925.0, 83566.7, 0.0, 0.0, 0.0)
DEFAULT_CAPACITY_NMS = 50.0
# ``time_above_80pct_capacity_fraction`` counts the step starts where a wheel holds more than this of its capacity.
HIGH_FRACTION = 0.8
SATURATED = "wheels saturated"


class Wheels(NamedTuple):
    """The carried state."""

    h_total_eci_nms: jnp.ndarray  # [3] total angular momentum I omega + h_w, ECI axes, N m s
    h_body_nms: jnp.ndarray  # [3] the wheels' momentum h_w at the latest step end, body axes, N m s
    srp_impulse_nms: jnp.ndarray  # [] integral of |tau_srp| dt since the start of the run, N m s
    gravity_gradient_impulse_nms: jnp.ndarray  # [] integral of |tau_gg| dt since the start, N m s
    steps_above: jnp.ndarray  # [] step starts so far with a wheel above HIGH_FRACTION of its capacity


class WheelStep(NamedTuple):
    """Per step (kept with ``keep_steps``)."""

    h_nms: jnp.ndarray  # [3] the wheels' momentum at the step start, body axes


class WheelCycle(NamedTuple):
    """Per cycle (always kept)."""

    max_abs_nms: jnp.ndarray  # [3] the largest |h_w| per wheel over the cycle's step starts and its end
    start_nms: jnp.ndarray  # [3] h_w at the cycle start
    end_nms: jnp.ndarray  # [3] h_w at the cycle end
    srp_impulse_nms: jnp.ndarray  # [] integral of |tau_srp| dt from the run's start to the cycle end
    gravity_gradient_impulse_nms: jnp.ndarray  # [] the same of the gravity gradient
    steps_above: jnp.ndarray  # [] step starts from the run's start with a wheel above HIGH_FRACTION of capacity


def init(params, r_eci_m, v_eci_mps) -> Wheels:
    """The wheels at the run's start: ``attitude.initial_momentum_nms`` (body axes)."""
    a = params.attitude
    h0 = a["initial_momentum_nms"]
    inertia = inertia_matrix(a["inertia_kg_m2"])
    c = nadir_frame(r_eci_m, v_eci_mps)
    zero = jnp.zeros_like(h0[0])
    return Wheels(c.T @ (inertia @ body_rate_rad_s(r_eci_m, v_eci_mps) + h0), h0, zero, zero, zero)


def step(params, state: Wheels, ctx: StepContext):
    """One integration step: the torques at the step's start and end, their impulse (trapezoid rule) added to
    H_eci, the wheels' momentum in body axes at the end."""
    a, fm = params.attitude, ctx.force_model
    inertia = inertia_matrix(a["inertia_kg_m2"])
    at = lambda j: jax.tree_util.tree_map(lambda x: x[j], ctx.env)  # noqa: E731
    srp0, gg0, _ = torques(a, inertia, ctx.r_eci_m, ctx.v_eci_mps, at(0), fm)
    srp1, gg1, c1 = torques(a, inertia, ctx.r_end_eci_m, ctx.v_end_eci_mps, at(2), fm)
    half = ctx.step_s / 2
    h_total = state.h_total_eci_nms + half * ((srp0 + gg0) + (srp1 + gg1))
    h_end = c1 @ h_total - inertia @ body_rate_rad_s(ctx.r_end_eci_m, ctx.v_end_eci_mps)
    above = jnp.max(jnp.abs(state.h_body_nms)) > HIGH_FRACTION * a["wheel_capacity_nms"]
    new = Wheels(h_total, h_end,
                 state.srp_impulse_nms + half * (jnp.linalg.norm(srp0) + jnp.linalg.norm(srp1)),
                 state.gravity_gradient_impulse_nms + half * (jnp.linalg.norm(gg0) + jnp.linalg.norm(gg1)),
                 state.steps_above + above)
    return new, WheelStep(state.h_body_nms)


def torques(attitude: dict, inertia, r_eci_m, v_eci_mps, env, fm):
    """(tau_srp, tau_gg) [3] each, ECI axes, N m, at one instant (``env``), and the ECI -> body rotation [3, 3]."""
    c = nadir_frame(r_eci_m, v_eci_mps)
    offset = c.T @ attitude["srp_offset_body_m"] + array_frame(r_eci_m, v_eci_mps, env.r_sun_eci_m).T @ \
        attitude["srp_offset_array_m"]
    srp = jnp.cross(offset, srp_force_eci_n(r_eci_m, env, fm))
    gg = c.T @ gravity_gradient_torque_body(c @ r_eci_m, inertia, fm.mu_m3_s2)
    return srp, gg, c


def summary(params, start: Wheels, end: Wheels, steps: WheelStep) -> WheelCycle:
    """The cycle's record: per-wheel extremes over its step starts and its end, the running totals."""
    h = jnp.concatenate([steps.h_nms, end.h_body_nms[None]])
    return WheelCycle(jnp.max(jnp.abs(h), axis=0), start.h_body_nms, end.h_body_nms, end.srp_impulse_nms,
                      end.gravity_gradient_impulse_nms, end.steps_above)


def metrics(params, cycles: WheelCycle, n_steps_total: int, run_s: float):
    """({name: []}, saturated): the largest wheel momentum, its secular growth per day (the net change of h_w
    between the run's first and last cycle boundaries, one orbit apart each, so the orbit-periodic part drops
    out), the torque impulse per source, the fraction of step starts above 80 % of capacity; saturated where a
    wheel exceeded its capacity (``attitude.wheel_capacity_nms``) at any step start or cycle end."""
    peak = jnp.max(cycles.max_abs_nms)
    out = {
        "max_wheel_momentum_nms": peak,
        "wheel_momentum_per_day_nms": jnp.linalg.norm(cycles.end_nms[-1] - cycles.start_nms[0])
        * SECONDS_PER_DAY / run_s,
        "srp_torque_impulse_nms": cycles.srp_impulse_nms[-1],
        "gravity_gradient_impulse_nms": cycles.gravity_gradient_impulse_nms[-1],
        "time_above_80pct_capacity_fraction": cycles.steps_above[-1] / n_steps_total,
    }
    return out, peak > params.attitude["wheel_capacity_nms"]


def columns(cycles: WheelCycle) -> dict:
    """The per-cycle series in edge units: h_w at each cycle end and the largest |h_w| per wheel (N m s)."""
    out = {}
    for k, axis in enumerate("xyz"):
        out[f"wheel_{axis}_nms"] = np.asarray(cycles.end_nms)[:, k]
        out[f"wheel_max_abs_{axis}_nms"] = np.asarray(cycles.max_abs_nms)[:, k]
    return out


MODEL = StateModel(NAME, init, step, summary, metrics, status=SATURATED, columns=columns)


def validate(config: dict) -> None:
    """Checks across the ``[attitude]`` table at load (``ValueError`` naming the key): every key but ``wheels``
    is read only where ``attitude.wheels = true``; the inertia tensor is physical (positive definite, each
    principal moment at most the sum of the other two); an SRP offset needs SRP (``forces.srp`` and
    ``spacecraft.srp_area_m2`` > 0)."""
    from geojax.scenario_schema import SCHEMA  # the schema imports this module's defaults

    table = config["attitude"]
    if not table["wheels"]:
        for key, field in SCHEMA["attitude"].items():
            if key != "wheels" and table[key] != field.default:
                raise ValueError(f"attitude.{key}: read only where attitude.wheels = true, got {table[key]!r}; "
                                 f"set attitude.wheels = true or leave it out")
        return
    inertia = np.asarray(inertia_matrix(np.asarray(table["inertia_kg_m2"])))
    moments = np.linalg.eigvalsh(inertia)
    if moments[0] <= 0 or moments[2] > moments[0] + moments[1] * (1 + 1e-12):
        raise ValueError(f"attitude.inertia_kg_m2: not a physical inertia tensor (principal moments "
                         f"{', '.join(f'{m:g}' for m in moments)} kg m^2: each must be > 0 and at most the sum of "
                         f"the other two), got {table['inertia_kg_m2']!r}")
    has_srp = config["forces"]["srp"] and config["spacecraft"]["srp_area_m2"] > 0
    for key in ("srp_offset_body_m", "srp_offset_array_m"):
        if any(table[key]) and not has_srp:
            raise ValueError(f"attitude.{key}: an SRP torque needs SRP (forces.srp = true and "
                             f"spacecraft.srp_area_m2 > 0), got {table[key]!r}")
