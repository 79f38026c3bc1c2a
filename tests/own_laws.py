"""A user's controller, outside the package (named by import path, ``"own_laws:DAMPER"``): an inclination damper.

Thrust against the velocity's ECEF z (Li 2022's normal direction), of acceleration k_inc * |v_z| capped at the
thrusters' F / m.  It declares what a shipped controller declares: its own CPU width (16 lanes), the thruster
geometry of its fuel bound (a gimbal), and its one tunable field with an alias and a unit, the one a tuning moves
by default.  Used by ``test_controllers.py`` (simulate, sweep, bound geometry, bad paths) and
``test_tune_package.py`` (tuning).
"""

import jax.numpy as jnp

import geojax
from geojax.control.base import no_plan, stateless_init


def thrust(params, plan, t, state, environment):
    """Damp the daily north-south swing: thrust against the velocity's ECEF z (m/s^2 per m/s)."""
    accel = jnp.stack([0.0, 0.0, -params.controller["k_inc"] * environment.v_eci_mps[2]])
    norm = jnp.maximum(jnp.linalg.norm(accel), 1e-30)
    magnitude = jnp.minimum(norm, params.thrusters["thrust_n"] / state.mass_kg)
    return geojax.Thrust(accel / norm, magnitude * state.mass_kg, params.thrusters["isp_s"], jnp.asarray(1.0))


DAMPER = geojax.Controller(stateless_init, no_plan, thrust, geojax.Spec(fields={
    "k_inc_per_s": geojax.Field(float, 1e-5, lower=0.0, si="k_inc", transform=geojax.LOG, alias="k_inc",
                                symbol="k_inc", unit="1/s", doc="inclination damping gain")},
    tuned_fields=("k_inc_per_s",), bound_geometry="gimbal"), sizing=geojax.Sizing(lanes_cpu=16))
NOT_A_CONTROLLER = 3
