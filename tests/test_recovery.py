"""controller.recovery (geojax.control.recovery): the re-acquisition law after a failure.

Checked against: vis-viva (the along-track Delta-V that sets a drift, against the exact two-body drift after an
impulse), the QFFC alone (an idle recovery changes no number of a run that never fails, bit for bit), and
the integrated dynamics (a sample displaced 1 deg, which the QFFC alone leaves coasting, is flown back into its
box and handed over; its status still records the failure and its recovery Delta-V is the sum of the cycles
recovery flew).
"""

import math

import numpy as np
import pytest

import geojax
from geojax import scenario
from geojax.control import recovery
from geojax.loop.metrics import STATUS_LEFT_LON_BOX
from geojax.runner.setup import controller_of
from geojax.physics.constants import MU_EARTH_M3_S2, OMEGA_EARTH_RAD_S, SECONDS_PER_DAY

L0_RAD = 0.289893  # li2022-qffc's initial true longitude
DISPLACED = {"orbit.L_rad": L0_RAD + math.radians(1.0), "duration.days": 20}


@pytest.mark.parametrize("drift_deg_day", [-0.5, -0.05, 0.2])
def test_along_track_dv_sets_the_drift_by_vis_viva(drift_deg_day):
    # From a circular orbit at the Keplerian synchronous radius (drift 0), an along-track impulse dv gives
    # the orbit 1 / a' = 2 / a - (v + dv)^2 / mu (vis-viva), whose drift is sqrt(mu / a'^3) - omega_E.
    mu = MU_EARTH_M3_S2
    a = (mu / OMEGA_EARTH_RAD_S ** 2) ** (1 / 3)
    goal = math.radians(drift_deg_day) / SECONDS_PER_DAY
    dv = float(recovery.along_track_dv_mps(a, 0.0, goal))
    a_new = 1.0 / (2.0 / a - (math.sqrt(mu / a) + dv) ** 2 / mu)
    drift = math.sqrt(mu / a_new ** 3) - OMEGA_EARTH_RAD_S
    assert drift == pytest.approx(goal, rel=0.01)  # first order in dD / n (here at most 2.4e-3)


def test_off_in_the_papers_on_in_the_starting_point():
    assert scenario.load("li2022-qffc").config["controller"]["recovery"] is False
    assert scenario.load("geo").config["controller"]["recovery"] is True
    plain = controller_of([scenario.load("li2022-qffc")])
    assert plain is geojax.control.REGISTRY["qffc"].CONTROLLER  # off: the controller itself, the same program
    on = controller_of([scenario.load("li2022-qffc", {"controller.recovery": True})])
    assert on is controller_of([scenario.load("li2022-qffc", {"controller.recovery": True})])  # one program
    with pytest.raises(ValueError, match="controller.recovery: sets the compiled controller; one value per batch"):
        controller_of([scenario.load("li2022-qffc"), scenario.load("li2022-qffc", {"controller.recovery": True})])


@pytest.mark.slow
def test_an_idle_recovery_changes_no_number():
    """A nominal run never leaves its box: recovery never flies, and every metric is the QFFC's, bit for bit, in
    the programs a sweep runs (two samples, XLA's defaults).  A single sample's programs are compiled for start-up
    (XLA's classic emitters, ``geojax.compilation.ONE_SAMPLE_OPTIONS``), under which the two programs (the recovery
    wrapper is code of its own) may round differently in the last bit; ``tests/test_compilation.py`` bounds a
    single sample's rounding against the batch's."""
    off = geojax.simulate_batch([scenario.load("li2022-qffc", {"duration.days": 10})] * 2, seeds=[0, 1])
    on = geojax.simulate_batch([scenario.load("li2022-qffc", {"duration.days": 10, "controller.recovery": True})] * 2,
                               seeds=[0, 1])
    assert np.all(off.status == 0) and np.all(on.metrics["recovery_cycles"] == 0)
    assert np.all(on.metrics["dv_recovery_mps"] == 0)
    for name, value in off.metrics.items():
        assert np.array_equal(on.metrics[name], value), name


@pytest.fixture(scope="module")
def displaced():
    return {flag: geojax.simulate(scenario.load("li2022-qffc", {**DISPLACED, "controller.recovery": flag}))
            for flag in (False, True)}


def test_the_qffc_alone_coasts_when_displaced(displaced):
    # The failure recovery is for: 1 deg east of its slot the QFFC finds no plan in any cycle and coasts.
    alone = displaced[False]
    assert float(alone.metrics["cycles_without_solution"]) == 20
    assert np.all(np.abs(alone.cycles()["lon_deg"] - 96.0) > 10 * math.degrees(float(alone.params.station["box_half_width_rad"])))


def test_recovery_flies_a_displaced_sample_back_and_reports_it_apart(displaced):
    run = displaced[True]
    cycles = run.cycles()
    box_deg = math.degrees(float(run.params.station["box_half_width_rad"]))
    recovering = cycles["recovering"].astype(bool)
    assert recovering[0] and not recovering[-1]  # took over at once, handed back
    handed = int(np.argmin(recovering))
    assert np.all(~recovering[handed:])  # once settled, the QFFC keeps it
    assert np.all(np.abs(cycles["lon_deg"][handed:] - 96.0) < box_deg)  # and it holds the box from there
    assert int(run.status) == STATUS_LEFT_LON_BOX  # the failure is still what the sample reports
    assert float(run.metrics["recovery_cycles"]) == handed
    assert float(run.metrics["dv_recovery_mps"]) == pytest.approx(np.sum(cycles["dv_mps"][recovering]), rel=1e-12)
    assert 0 < float(run.metrics["dv_recovery_mps"]) < float(run.final.dv_mps)
    # the QFFC's own burns are not what flew in recovery cycles: its records there are zero
    assert np.all(cycles["burn1_s"][recovering] == 0) and np.all(cycles["burn2_s"][recovering] == 0)
