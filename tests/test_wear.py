"""The thrusters' wear (``geojax.states.wear``), a part added to the package as its own module and one registry
line: firing hours and starts counted from the thrust flown at every step.

Independent checks: the firing hours against the controller's own burn records (the planner's ``fired_s``, which
``duty_fraction`` sums); the starts against the burns the planner fired (``burns_total``: one start per burn, more
where an eclipse suspends one); the status past the qualified life; a key read only where the part is on refused
otherwise, naming it.
"""

import numpy as np
import pytest

from geojax import scenario
from geojax.runner.rollout import simulate


def test_firing_hours_and_starts_are_the_planners_burns():
    r = simulate(scenario.load("li2022-qffc", {"duration.days": 10, "wear.enabled": True}), seed=0)
    m = r.metrics
    run_s = r.records.cycles.dv_mps.shape[0] * 86164.0905
    assert np.isclose(m["wear_firing_hours"] * 3600.0, m["duty_fraction"] * run_s, rtol=1e-12)
    assert m["wear_starts"] >= m["burns_total"] > 0
    assert m["wear_starts"] <= 2 * m["burns_total"]  # at most one eclipse suspension a burn
    assert r.status_meanings[int(r.status)] == "ok"
    cycles = r.cycles()
    assert np.all(np.diff(cycles["wear_firing_hours"]) >= 0) and cycles["wear_starts"][-1] == m["wear_starts"]


def test_past_the_qualified_life_is_a_status_of_its_own_and_the_sample_is_kept():
    r = simulate(scenario.load("li2022-qffc", {"duration.days": 3, "wear.enabled": True,
                                               "wear.qualified_starts": 2.0}), seed=0)
    assert r.status_meanings[int(r.status)] == "thrusters past their qualified life"
    assert r.metrics["wear_life_used_fraction"] > 1.0 and r.metrics["dv_per_year_mps"] > 0


def test_its_keys_are_read_only_where_it_is_on():
    with pytest.raises(ValueError, match="wear.qualified_hours: read only where wear.enabled = true"):
        scenario.load("li2022-qffc", {"wear.qualified_hours": 100.0})
