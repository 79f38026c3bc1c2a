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


def test_a_thruster_out_must_be_on_board(tmp_path):
    """Katz's gimbal (thrusters.count = 1): thruster 1 out is refused, naming the key; and a file that leaves
    thrusters.count unset may name thruster 0 only (the count it would get is the controller's)."""
    with pytest.raises(ValueError, match=r"^faults\.thruster_out: thruster 1 is not on board"):
        geojax.load_scenario("katz2025-continuous", {"faults.thruster_out": 1})
    from pathlib import Path

    text = (Path(geojax.__file__).parent / "scenarios" / "li2022-qffc.toml").read_text()
    unset = tmp_path / "unset.toml"
    unset.write_text("\n".join(line for line in text.splitlines() if not line.startswith("count")))
    assert geojax.load_scenario(str(unset), {"faults.thruster_out": 0}).config["faults"]["enabled"]
    with pytest.raises(ValueError, match=r"^faults\.thruster_out: thruster 1 needs thrusters\.count"):
        geojax.load_scenario(str(unset), {"faults.thruster_out": 1})
