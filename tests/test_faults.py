"""The faults part (``geojax.states.faults``): burns lost with a probability, a thruster out over a window, thrust
degraded, each checked against what the loop flew."""

from __future__ import annotations

import math

import numpy as np
import pytest

import geojax
from geojax.physics.constants import SECONDS_PER_DAY

DAYS = 30


def run(faults: dict, seed: int = 3, days: float = DAYS, count: int | None = None):
    overrides = {"duration.days": days, **{f"faults.{k}": v for k, v in faults.items()}}
    if count is not None:
        overrides["thrusters.count"] = count
    return geojax.simulate(geojax.load_scenario("li2022-qffc", overrides), seed=seed)


def test_missed_burns_are_binomial_and_the_box_holds():
    """Each planned burn is lost with p = 0.2: the count lost against the burns planned lies within the binomial
    4-sigma band (an independent law of the draws), the burns flown are the rest, and the QFFC keeps its box."""
    r = run({"missed_burn_probability": 0.2})
    m = {k: float(v) for k, v in r.metrics.items()}
    n, lost = m["burns_planned"], m["burns_missed"]
    assert n > 40
    assert abs(lost - 0.2 * n) <= 4 * math.sqrt(n * 0.2 * 0.8)
    assert m["burns_flown"] == n - lost == m["burns_total"]
    assert r.status == 0


def test_a_thruster_out_fires_nothing_in_its_window_and_the_rest_unchanged():
    """Thruster 0 out from day 10 for 5 days, the planner not told: its delivered firing time is zero in every
    cycle of the window (counted from the /cycles columns) while it is still commanded, thruster 1 fires what it
    was commanded, and before the window what was flown is what was planned (the part changes nothing it is not
    asked to)."""
    r = run({"thruster_out": 0, "out_from_day": 10.0, "out_days": 5.0, "planner_told": False})
    table = r.cycles()
    t_days = np.asarray(table["t_s"]) / SECONDS_PER_DAY
    fired0, planned0 = np.asarray(table["fired_s_t0"]), np.asarray(table["planned_s_t0"])
    inside = (t_days > 10.5) & (t_days < 14.5)
    assert inside.sum() >= 3 and np.all(fired0[inside] == 0) and np.any(planned0[inside] > 0)
    before = t_days < 9.5
    np.testing.assert_array_equal(fired0[before], planned0[before])
    np.testing.assert_array_equal(np.asarray(table["fired_s_t1"]), np.asarray(table["planned_s_t1"]))


def test_a_told_planner_commands_nothing_from_a_thruster_it_knows_is_out():
    """Told (the default), the planner learns of the outage at the first cycle start after day 10: from the next
    cycle on it commands nothing from thruster 0 until the outage ends."""
    r = run({"thruster_out": 0, "out_from_day": 10.0, "out_days": 5.0})
    table = r.cycles()
    t_days = np.asarray(table["t_s"]) / SECONDS_PER_DAY
    inside = (t_days > 10.5) & (t_days < 14.5)
    assert np.all(np.asarray(table["planned_s_t0"])[inside] == 0)
    assert np.any(np.asarray(table["planned_s_t0"])[t_days > 15.5] > 0)


@pytest.mark.parametrize("told", [False, True])
def test_degraded_thrust_delivers_its_fraction_or_is_planned_for(told):
    """Every thruster at 0.9 of its thrust.  Unaware, the first cycle's burns are planned alike, so that cycle's
    Delta-V is 0.9 x the nominal run's (F t / m, the rocket equation linear in thrust to 1e-5 over a burn); told,
    each burn fires 1 / 0.9 as long at 0.9 of the thrust, the nominal Delta-V (to the mass flow's second order)."""
    nominal = run({}, days=2)
    degraded = run({"thrust_scale": 0.9, "planner_told": told}, days=2)
    dv_n = float(np.asarray(nominal.records.cycles.dv_mps)[0])
    dv_d = float(np.asarray(degraded.records.cycles.dv_mps)[0])
    assert dv_d == pytest.approx((1.0 if told else 0.9) * dv_n, rel=1e-5)


@pytest.mark.parametrize("key, value, says", [
    ("missed_burn_probability", 1.5, "faults.missed_burn_probability"),
    ("thruster_out", 3, "faults.thruster_out"),
    ("out_days", -1.0, "faults.out_days"),
    ("thrust_scale", 0.0, "faults.thrust_scale"),
])
def test_bad_faults_are_refused_naming_the_key(key, value, says):
    with pytest.raises(ValueError, match=says.replace(".", r"\.")):
        geojax.load_scenario("li2022-qffc", {f"faults.{key}": value, "thrusters.count": 2})


def test_the_burns_file_lists_the_burns_as_flown():
    """With burns lost and every thruster at 0.9, the burn list (what the CSV and the OPM write) holds the burns
    flown, no more (``burns_flown``), and their Delta-V, by the rocket equation at the delivered thrust, adds up
    to the loop's own RK4 Delta-V (an independent integration of the same burns, to 1e-6)."""
    from geojax.export import trajectory

    r = run({"missed_burn_probability": 0.3, "thrust_scale": 0.9, "planner_told": False}, days=10)
    burns = trajectory.run_burns(r)
    assert len(burns.cycle) == float(r.metrics["burns_flown"]) < float(r.metrics["burns_planned"])
    dv_file = float(np.sum(np.linalg.norm(burns.dv_rtn_mps, axis=1)))
    dv_loop = float(np.sum(np.asarray(r.records.cycles.dv_mps)))
    assert dv_file == pytest.approx(dv_loop, rel=1e-6)


def test_four_thrusters_fly_on_with_one_out_and_the_planner_told():
    """Two thrusters per arm, thruster 0 out from day 10 to the end, the planner told: thruster 0 fires nothing
    after the cycle that met the outage, its arm's second thruster (2) takes its burns, the box is kept, and the
    Delta-V is within 3 % of the run without the fault (the same arm, the same directions)."""
    days = 30
    plain = run({"enabled": True}, days=days, count=4)
    faulty = run({"thruster_out": 0, "out_from_day": 10.0}, days=days, count=4)
    table = faulty.cycles()
    t_days = np.asarray(table["t_s"]) / SECONDS_PER_DAY
    assert np.all(np.asarray(table["fired_s_t0"])[t_days > 11.0] == 0)
    assert np.all(np.asarray(table["fired_s_t2"])[t_days < 9.5] == 0)
    assert np.sum(np.asarray(table["fired_s_t2"])[t_days > 11.0] > 0) >= 10
    from geojax.export import trajectory

    burns = trajectory.run_burns(faulty)  # the burn list numbers thrusters from 1: thruster 2 is "3"
    late = burns.cycle > 11
    assert set(np.asarray(burns.thruster)[late]) <= {2, 3} and 3 in set(np.asarray(burns.thruster)[late])
    assert faulty.status == 0 and plain.status == 0
    dv_plain, dv_faulty = float(plain.metrics["dv_per_year_mps"]), float(faulty.metrics["dv_per_year_mps"])
    assert dv_faulty == pytest.approx(dv_plain, rel=0.03)


def test_four_thrusters_without_faults_fly_as_two():
    """thrusters.count = 4 and nothing wrong: the planner flies thrusters 0 and 1, every number as with 2."""
    two, four = run({"enabled": True}, days=3, count=2), run({"enabled": True}, days=3, count=4)
    np.testing.assert_array_equal(np.asarray(two.records.cycles.dv_mps), np.asarray(four.records.cycles.dv_mps))
