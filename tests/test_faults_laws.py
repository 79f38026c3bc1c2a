"""Every law told of a fault (``faults.planner_told``) commands nothing from a thruster it knows is out: the burn
planners, Katz's feedback law (one gimbal, or with a spare) and the re-acquisition law (``controller.recovery``)."""

from __future__ import annotations

import numpy as np
import pytest

import geojax
from geojax.physics.constants import SECONDS_PER_DAY

OUT_DAY = 2.0


def run(name: str, days: float, **overrides):
    return geojax.simulate(geojax.load_scenario(name, {"duration.days": days, **overrides}), seed=3)


def _after(table, day: float):
    return np.asarray(table["t_s"]) / SECONDS_PER_DAY > day


@pytest.mark.parametrize("name", ["li2022-fompc", "li2022-mpc", "ye2022-ex1"])
def test_a_told_planner_commands_nothing_from_a_thruster_out(name):
    """Thruster 0 out from day 2, told: from the first cycle that starts after it the planner (FOMPC, MPC, Ye's
    zone NSSK) commands no firing of thruster 0 (/cycles ``planned_s_t0``), where before it did."""
    r = run(name, 6.0, **{"faults.thruster_out": 0, "faults.out_from_day": OUT_DAY})
    table = r.cycles()
    planned = np.asarray(table["planned_s_t0"])
    assert np.all(planned[_after(table, OUT_DAY + 1.0)] == 0)
    assert np.any(planned[~_after(table, OUT_DAY)] > 0)


def test_katz_law_told_flies_its_spare_or_nothing():
    """Katz's continuous law, thruster 0 out from day 2, told: with a spare (``thrusters.count = 2``) every firing
    after the outage is the spare's and none is commanded of thruster 0; with the one thruster, the law commands
    nothing at all (no Delta-V delivered in those cycles: the orbit's own record); not told, it keeps commanding
    thruster 0 (which delivers nothing)."""
    fault = {"faults.thruster_out": 0, "faults.out_from_day": OUT_DAY}
    spare = run("katz2025-continuous", 5.0, **fault, **{"thrusters.count": 2})
    table = spare.cycles()
    late = _after(table, OUT_DAY + 1.0)
    assert np.all(np.asarray(table["planned_s_t0"])[late] == 0)
    assert np.all(np.asarray(table["fired_s_t1"])[late] > 0)
    assert np.all(np.asarray(table["planned_s_t1"])[~_after(table, OUT_DAY)] == 0)  # the spare waits till then
    alone = run("katz2025-continuous", 5.0, **fault)
    table = alone.cycles()
    late = _after(table, OUT_DAY + 1.0)
    assert np.all(np.asarray(table["planned_s_t0"])[late] == 0)
    assert np.all(np.asarray(alone.records.cycles.dv_mps)[late] == 0)
    unaware = run("katz2025-continuous", 5.0, **fault, **{"faults.planner_told": False}).cycles()
    assert np.all(np.asarray(unaware["planned_s_t0"])[late] > 0)


@pytest.mark.parametrize("name, count", [("li2022-qffc", 2), ("katz2025-continuous", 2)])
def test_the_reacquisition_law_told_flies_only_working_thrusters(name, count):
    """The station moved 0.3 deg east (Li's satellite starts outside its +-0.05 deg box; Katz's law, whose start
    follows the station, leaves it in its first days: the re-acquisition law flies), thruster 0 out from the
    start, told: no cycle commands thruster 0 (on Li's arms the law pushes from arm 1 alone, along-track; Katz's
    gimbal flies its spare), the law does fly (recovery cycles, thruster 1 fires), and the longitude offset from
    the station shrinks over the run."""
    r = run(name, 4.0, **{"controller.recovery": True, "thrusters.count": count, "faults.thruster_out": 0,
                          "station.lon_deg": geojax.load_scenario(name).station_lon_deg + 0.3})
    table = r.cycles()
    assert float(r.metrics["recovery_cycles"]) >= 2
    assert np.all(np.asarray(table["planned_s_t0"]) == 0)
    assert np.sum(np.asarray(table["fired_s_t1"])) > 0
    offset = np.abs(np.asarray(table["lon_deg"]) - (geojax.load_scenario(name).station_lon_deg + 0.3))
    assert offset[-1] < np.max(offset)
