"""What was flown, not what was planned: with the faults part, ``duty_fraction`` and the RTN split of the Delta-V
per year count the thrust delivered."""

from __future__ import annotations

import numpy as np
import pytest

import geojax
from geojax.export import trajectory
from geojax.loop.metrics import SECONDS_PER_YEAR


@pytest.fixture(scope="module")
def thruster_out():
    """Thruster 0 out from day 5 on li2022-qffc, the planner not told: it keeps planning burns of thruster 0
    that are never flown."""
    return geojax.simulate(geojax.load_scenario("li2022-qffc", {
        "duration.days": 15, "faults.thruster_out": 0, "faults.out_from_day": 5.0,
        "faults.planner_told": False}), seed=3)


def test_duty_and_the_rtn_split_are_the_burns_files_flown_delta_v(thruster_out):
    """The burns file (the rocket equation over each burn's delivered firing time, along its direction flown)
    gives the RTN components per year and the firing time that the metrics report, to the rocket equation's
    difference from F t / m within a burn (1e-5); its Delta-V is the orbit's own (``dv_per_year_mps``, the
    integrated state); and the planned firing time (the controller's records) is more than what was flown."""
    r = thruster_out
    m = {k: float(v) for k, v in r.metrics.items()}
    burns = trajectory.run_burns(r)
    table = r.cycles()
    t_s = np.asarray(table["t_s"])
    run_s = len(t_s) * (t_s[1] - t_s[0])
    per_year = SECONDS_PER_YEAR / run_s
    flown = burns.status != "missed"
    assert np.sum(~flown) >= 5  # the burns of thruster 0 after day 5
    dv = burns.dv_rtn_mps[flown]
    for axis, name in enumerate(("dv_radial_per_year_mps", "dv_ew_per_year_mps", "dv_ns_per_year_mps")):
        assert m[name] == pytest.approx(np.sum(np.abs(dv[:, axis])) * per_year, rel=1e-5)
    assert m["dv_per_year_mps"] == pytest.approx(np.sum(np.linalg.norm(dv, axis=1)) * per_year, rel=1e-5)
    assert m["duty_fraction"] == pytest.approx(np.sum(burns.duration_s) / run_s, rel=1e-12)
    planned_s = np.sum(np.asarray(r.records.cycles.controller["fired_s"]))
    assert planned_s / run_s > 1.2 * m["duty_fraction"]
