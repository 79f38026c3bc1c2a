"""Burn magnitude execution errors (``errors.sigma3_dv_pct``, ``control.burns.magnitude_scale``).

Checked against the documented draw, re-derived here from JAX's generator (not through geojax's function): each
cycle's delivered Delta-V (the integrated thrust, ``/cycles/dv_mps``) equals the burns' planned magnitudes
each times 1 + sigma3 / 3 x normal(fold_in(fold_in(key, cycle), 2))[burn], within the mass's change over a
cycle; and the key is refused by a law that flies no planned burns.  At 0 % every number is unchanged: the stored
reference numbers (``tests/test_reference_numbers.py``) are run with the key at its default.
"""

import jax
import numpy as np
import pytest

import geojax
from geojax import scenario
from geojax.control.burns import MAGNITUDE_KEY

SIGMA3_PCT = 30.0  # large, so the check sees the error well above the mass's 1e-5 effect


def test_each_burn_flies_its_planned_magnitude_times_the_drawn_level():
    seed = 7
    sc = scenario.load("li2022-qffc", {"duration.days": 6, "errors.sigma3_dv_pct": SIGMA3_PCT})
    run = geojax.simulate(sc, seed=seed)
    cycles = run.cycles()
    key = jax.random.key(seed)
    levels = np.array([1 + SIGMA3_PCT / 100 / 3 * np.asarray(
        jax.random.normal(jax.random.fold_in(jax.random.fold_in(key, k), MAGNITUDE_KEY), (2,)))
        for k in range(len(cycles["dv_mps"]))])
    planned = np.stack([cycles["v1_mps"], cycles["v2_mps"]], axis=1)
    fired = planned > 0
    assert fired.sum() >= 8  # both burns fly in most cycles
    expected = np.sum(planned * levels, axis=1)
    np.testing.assert_allclose(cycles["dv_mps"], expected, rtol=2e-4)
    # and the planned alone would be off by far more: the error is in the flight
    assert np.max(np.abs(cycles["dv_mps"] / np.sum(planned, axis=1) - 1)) > 0.02


def test_a_law_without_planned_burns_refuses_the_key():
    with pytest.raises(ValueError, match="errors.sigma3_dv_pct"):
        scenario.load("katz2025-continuous", {"errors.sigma3_dv_pct": 5.0})
