"""The burn-effect matrix B (Li 2022, eqs. (15)-(22), re-derived) against propagated burns.

Independent check: a 60 s burn in a two-body GEO orbit, propagated to the end of
the cycle with and without it.  In two-body motion the osculating e and i
vectors carry no short-period terms, so their differences are the mean-element
changes; the drift change is that of n = sqrt(mu / a^3), the longitude change
that of the mean longitude.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics import constants as c
from geojax.control.effects import R_SYNC_M, cycle_coast_s, effect_matrix, remaining_fraction
from geojax.physics.dynamics import SpacecraftState
from geojax.physics.elements import semi_major_axis_m
from geojax.physics.forces import ForceModel
from geojax.physics.integrate import ThrustWindow, window_thrust
from geojax.loop.simulate import propagate as propagate_cycles
from geojax.physics.propagate import MEE, environment_grid

MU = c.MU_EARTH_M3_S2
TWO_BODY = ForceModel(j2_on=0.0, sun_on=0.0, moon_on=0.0, srp_on=0.0)
MASS, THRUST, BURN_S = 3000.0, 0.25, 60.0  # Delta-V = 5 mm/s
MEE0 = jnp.array([R_SYNC_M, 1e-4, -5e-5, 2e-4, 1e-4, 0.7])
N_STEPS = 96 * 8


def mean_longitude(mee):
    """Mean longitude to first order in e: L - 2 f sin L + 2 g cos L."""
    return mee[5] - 2 * mee[1] * jnp.sin(mee[5]) + 2 * mee[2] * jnp.cos(mee[5])


def end_of_cycle(direction, burn_mid_s):
    h = c.SIDEREAL_DAY_S / N_STEPS
    env = environment_grid(0.0, 0.0, 69.0, h, 1, N_STEPS)
    window = ThrustWindow(jnp.asarray(burn_mid_s - BURN_S / 2), jnp.asarray(burn_mid_s + BURN_S / 2),
                          jnp.asarray(direction, dtype=float), jnp.asarray(THRUST), jnp.asarray(1e12))
    state = SpacecraftState(MEE0, jnp.asarray(MASS), jnp.asarray(0.0))
    final, _ = propagate_cycles(MEE, state, env, TWO_BODY, h, lambda t, hh: window_thrust(window, t, hh))
    return final.orbit


def state_vector(mee):
    a = semi_major_axis_m(mee)
    return jnp.stack([mean_longitude(mee), jnp.sqrt(MU / a**3), mee[1], mee[2], mee[3], mee[4]])


@pytest.mark.parametrize("burn_fraction", [0.3, 0.8])
def test_effect_matrix_matches_propagated_burns(burn_fraction):
    burn_mid = burn_fraction * c.SIDEREAL_DAY_S
    n0 = np.sqrt(MU / R_SYNC_M**3)
    l_burn = float(MEE0[5]) + n0 * burn_mid
    coast = c.SIDEREAL_DAY_S - burn_mid
    B = np.asarray(effect_matrix(jnp.asarray(l_burn), coast))
    dv = THRUST / MASS * BURN_S
    run = jax.jit(end_of_cycle)
    base = np.asarray(state_vector(run(jnp.zeros(3), burn_mid)))
    for axis in range(3):
        direction = np.eye(3)[axis]
        got = np.asarray(state_vector(run(jnp.asarray(direction), burn_mid))) - base
        want = B[:, axis] * dv
        scale = np.abs(B).max(axis=1) * dv  # the size of each row's effect
        # Measured: within 0.11 % of each row's scale (linearisation, 60 s burn arc).
        assert np.all(np.abs(got - want) <= 0.005 * scale), (axis, got, want)


def test_remaining_fraction_eq21():
    # Eq. (21): a burn just after the cycle start leaves ~1, just before it ~0.
    assert float(remaining_fraction(0.1, 0.0)) == pytest.approx(1 - 0.1 / (2 * np.pi))
    assert float(remaining_fraction(5.0, 5.5)) == pytest.approx(0.5 / (2 * np.pi))
    assert float(cycle_coast_s(np.pi, 0.0)) == pytest.approx(c.SIDEREAL_DAY_S / 2)
