"""Batching and cycle bookkeeping of the propagation loop."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics import constants as c
from geojax.physics.dynamics import SpacecraftState
from geojax.physics.forces import ForceModel
from geojax.loop.simulate import propagate as propagate_cycles
from geojax.physics.propagate import MEE, CycleMeans, environment_grid, steps_per_cycle
from geojax.uncontrolled import propagated_cycles, drift_summary

EPOCH = 7305 * 86400.0 + 69.184


def test_cycle_count_spans_the_requested_days():
    assert propagated_cycles(365.25) == 368  # 367 sidereal days between first and last mean >= 365.25 d
    assert (propagated_cycles(30) - 2) * c.SIDEREAL_DAY_S < 30 * 86400 <= (propagated_cycles(30) - 1) * c.SIDEREAL_DAY_S


def test_vmapped_batch_equals_one_by_one():
    # A batch must not couple its samples: each row of a vmapped run equals its own single run.
    n = steps_per_cycle(1800.0)
    h = c.SIDEREAL_DAY_S / n
    env = environment_grid(EPOCH, EPOCH, 69.36, h, 3, n)
    fm = ForceModel(srp_area_m2=200.0)
    mee = jnp.array([[42167e3, 0.0, 1e-4, 0.0, 5e-5, 0.29], [42165e3, 2e-4, 0.0, 1e-3, 0.0, 1.0]])
    states = SpacecraftState(mee, jnp.array([5000.0, 3000.0]), jnp.zeros(2))
    run = jax.jit(lambda s: propagate_cycles(MEE, s, env, fm, h))
    _, batch = jax.jit(jax.vmap(lambda s: propagate_cycles(MEE, s, env, fm, h)))(states)
    for i in range(2):
        _, single = run(jax.tree_util.tree_map(lambda x: x[i], states))
        for got, want in zip(batch, single):
            np.testing.assert_allclose(got[i], want, rtol=1e-13, atol=1e-15)


def test_drift_summary_of_a_synthetic_record():
    # Closed form: a straight-line inclination-vector change of 0.5 deg towards 90 deg.
    t = np.arange(5) * c.SIDEREAL_DAY_S
    iy = np.tan(np.radians(np.linspace(0.0, 0.5, 5)) / 2)
    cycles = CycleMeans(t, np.radians(np.linspace(96, 95, 5)), np.zeros(5), np.zeros(5), np.zeros(5), np.zeros(5), iy, np.zeros(5), np.zeros(5))
    s = drift_summary(cycles)
    assert abs(s.di_deg - 0.5) < 1e-12 and abs(s.di_direction_deg - 90) < 1e-9
    assert abs(s.dlon_deg + 1.0) < 1e-12
    half = drift_summary(cycles, span_days=2 * c.SIDEREAL_DAY_S / 86400)
    assert abs(half.di_deg - 0.25) < 1e-12
    with pytest.raises(ValueError, match="span_days"):
        drift_summary(cycles, span_days=10.0)
