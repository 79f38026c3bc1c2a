"""A stuck arm (``faults.stuck_arm``): its thrusters keep firing, along the direction its joints had when the fault
started; told, the planner flies from the other arm alone."""

from __future__ import annotations

import numpy as np
import pytest

import geojax
from geojax.physics.constants import SECONDS_PER_DAY

FAULT_DAY = 5.0


def run(told: bool, days: float = 20.0):
    return geojax.simulate(geojax.load_scenario("li2022-qffc", {
        "duration.days": days, "faults.stuck_arm": 0, "faults.out_from_day": FAULT_DAY,
        "faults.planner_told": told}), seed=3)


def test_a_stuck_arm_fires_along_one_body_direction_after_the_fault():
    """Not told, the planner keeps steering arm 0 (its planned directions move from cycle to cycle), but every
    cycle that starts after the fault delivers thruster 0's Delta-V along one direction in body (= RSW) axes: the
    direction of arm 0's last burn that ended before the fault (the planned direction of that burn, a second
    record), and before the fault what was flown is what was planned."""
    r = run(told=False)
    rec = r.records.cycles.controller
    planned = np.asarray(rec["directions_rsw"])[:, 0]
    fired_s, start_s = np.asarray(rec["fired_s"])[:, 0], np.asarray(rec["start_s"])[:, 0]
    flown = np.asarray(r.records.cycles.states["faults"].flown_dv_rsw)[:, 0]
    size = np.linalg.norm(flown, axis=1)
    table = r.cycles()
    t_mid = np.asarray(table["t_s"])
    cycle_s = t_mid[1] - t_mid[0]
    t0 = t_mid - cycle_s / 2
    fault_s = FAULT_DAY * SECONDS_PER_DAY
    ended = (t0 + start_s + fired_s <= fault_s) & (fired_s > 0)
    frozen = planned[np.flatnonzero(ended)[-1]]
    after = (t0 >= fault_s) & (size > 0)
    assert after.sum() >= 10
    np.testing.assert_allclose(flown[after] / size[after, None], np.broadcast_to(frozen, flown[after].shape),
                               atol=1e-12)
    assert np.max(np.linalg.norm(planned[after] - frozen, axis=1)) > 1e-3  # the plan kept moving the arm
    before = (t0 + cycle_s <= fault_s) & (size > 0)
    np.testing.assert_allclose(flown[before] / size[before, None], planned[before], atol=1e-12)


def test_a_told_planner_flies_the_other_arm_alone_and_keeps_the_box():
    """Told, the planner treats the stuck arm as lost from the first cycle start after the fault: thruster 0 is
    commanded nothing from then on (the /cycles columns), arm 1 flies every cycle, and the box is kept for 30 days
    (the loop's check at every step start)."""
    r = run(told=True, days=30.0)
    table = r.cycles()
    t_days = np.asarray(table["t_s"]) / SECONDS_PER_DAY
    late = t_days > FAULT_DAY + 1.0
    assert np.all(np.asarray(table["planned_s_t0"])[late] == 0)
    assert np.all(np.asarray(table["fired_s_t1"])[late] > 0)
    assert r.status == 0 and float(r.metrics["days_out_of_box"]) == 0.0


@pytest.mark.parametrize("scenario, overrides, says", [
    ("li2022-qffc", {"faults.stuck_arm": 2}, "faults.stuck_arm"),
    ("li2022-qffc", {"faults.stuck_arm": -2}, "faults.stuck_arm"),
    ("katz2025-continuous", {"faults.stuck_arm": 1}, "faults.stuck_arm: arm 1 is not on board"),
])
def test_a_bad_stuck_arm_is_refused_naming_the_key(scenario, overrides, says):
    with pytest.raises(ValueError, match="^" + says.replace(".", r"\.")):
        geojax.load_scenario(scenario, overrides)
