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
    ("thruster_out", [0, 3], "faults.thruster_out"),
    ("thruster_out", [0, 5], "faults.thruster_out"),
    ("thruster_out", [0, True], "faults.thruster_out"),
    ("out_days", -1.0, "faults.out_days"),
    ("out_from_day", "soon", "faults.out_from_day"),
    ("out_from_spread_days", -2.0, "faults.out_from_spread_days"),
    ("thrust_scale", 0.0, "faults.thrust_scale"),
    ("thrust_scale", [0.9, 1.0], "faults.thrust_scale"),
    ("thrust_scale", [0.9, 1.0, 0.0, 1.0], "faults.thrust_scale"),
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


@pytest.mark.parametrize("out_days", [0.0, 10.0])
def test_time_out_of_the_box_and_to_reacquire_it_counted_from_the_steps(out_days):
    """An arm lost on day 10 (thruster 0 out to the end, or for 10 days), the planner not told: the days out of
    the box and the days to re-acquire are those counted again from the step records (a second computation: the
    osculating longitude and latitude of every step start against the box, cycle by cycle), and the status
    agrees.  Lost to the end the run ends out of the box (-1); back after 10 days the box is re-acquired."""
    sc = geojax.load_scenario("li2022-qffc", {"duration.days": 60, "faults.thruster_out": 0,
                                              "faults.out_from_day": 10.0, "faults.out_days": out_days,
                                              "faults.planner_told": False})
    r = geojax.simulate(sc, seed=3, keep_steps=True)
    box_rad = float(r.params.station["box_half_width_rad"])
    dlon = np.abs(np.angle(np.exp(1j * (np.asarray(r.records.steps.lon_rad)
                                         - float(r.params.station["lon_rad"])))))
    lat = np.abs(np.asarray(r.records.steps.lat_rad))
    out = np.any((dlon > box_rad) | (lat > box_rad), axis=1)  # [n_cycles]
    cycle_days = dlon.shape[1] * r.step_s / SECONDS_PER_DAY
    m = {k: float(v) for k, v in r.metrics.items()}
    assert out.sum() >= 1 and r.status in (2, 3)
    assert m["days_out_of_box"] == pytest.approx(out.sum() * cycle_days, rel=1e-12)
    ends = (np.arange(len(out)) + 1) * cycle_days
    expected = -1.0 if out[-1] else ends[out & (ends > 10.0)].max() - 10.0
    assert m["reacquire_days"] == pytest.approx(expected, rel=1e-12)
    assert (expected == -1.0) == (out_days == 0.0)


def test_a_sample_that_stays_in_its_box_has_no_time_out_of_it():
    """Burns lost with p = 0.05 over 20 days on li2022-qffc: the box is kept (status 0), so no cycle is out and
    nothing is to be re-acquired (the status' own check, any step start out of the box, says the same)."""
    r = run({"missed_burn_probability": 0.05}, days=20)
    assert r.status == 0
    assert float(r.metrics["days_out_of_box"]) == 0.0 and float(r.metrics["reacquire_days"]) == 0.0


def _burn_rows(result, tmp_path, name):
    import csv

    with result.save_oem(tmp_path / f"{name}.oem")[1].open() as handle:
        return list(csv.DictReader(handle))


def test_the_burns_file_marks_missed_cut_and_degraded_burns_beside_the_planned(tmp_path):
    """The burns CSV of a run with burns lost (p = 0.2, the planner not told) lists every burn the plan fired,
    each marked: the missed ones (duration and Delta-V 0) number ``burns_missed``, the flown ones fired their
    planned time, and their Delta-V (the rocket equation over the firing time) sums to the Delta-V the loop
    integrated (a second computation).  The same run with that thruster out from a step start within a flown
    burn (the outage is read at step starts; nothing changes before it) marks that burn cut, fired from its start
    to that step's; every
    thruster at 0.9 marks every burn degraded, their Delta-V again the loop's."""
    from geojax.export.trajectory import FAULT_BURN_COLUMNS

    lossy = run({"missed_burn_probability": 0.2, "planner_told": False}, days=12)
    rows = _burn_rows(lossy, tmp_path, "lossy")
    assert tuple(rows[0])[-2:] == FAULT_BURN_COLUMNS
    status = np.array([r["status"] for r in rows])
    duration = np.array([float(r["duration_s"]) for r in rows])
    planned = np.array([float(r["planned_duration_s"]) for r in rows])
    dv = np.array([float(r["dv_mps"]) for r in rows])
    assert set(status) == {"flown", "missed"}
    assert (status == "missed").sum() == float(lossy.metrics["burns_missed"]) >= 2
    assert np.all(duration[status == "missed"] == 0) and np.all(dv[status == "missed"] == 0)
    assert np.all(planned > 0)
    np.testing.assert_allclose(duration[status == "flown"], planned[status == "flown"], rtol=1e-9)
    delivered = float(lossy.final.dv_mps - lossy.params.initial.dv_mps)
    assert abs(dv.sum() - delivered) < 1e-8 * len(rows) + 1e-9 * delivered

    epoch_tt_s, cycle_s = lossy.scenario.epoch_tt_s, float(lossy.records.cycles.means.t_s[1]
                                                            - lossy.records.cycles.means.t_s[0])
    start_tt = np.array([float(r["start_tt_s"]) for r in rows])
    step_after = epoch_tt_s + np.array([int(r["cycle"]) for r in rows]) * cycle_s  # the next step boundary
    step_after += np.ceil((start_tt + 60 - step_after) / lossy.step_s) * lossy.step_s
    pick = np.flatnonzero((status == "flown") & (step_after < start_tt + duration - 60))[0]
    cut = run({"missed_burn_probability": 0.2, "planner_told": False, "thruster_out": int(rows[pick]["thruster"]) - 1,
               "out_from_day": (step_after[pick] - 1.0 - epoch_tt_s) / SECONDS_PER_DAY, "out_days": 0.5}, days=12)
    again = _burn_rows(cut, tmp_path, "cut")
    assert again[:pick] == rows[:pick]
    assert again[pick]["status"] == "cut"
    assert float(again[pick]["duration_s"]) == pytest.approx(step_after[pick] - start_tt[pick], abs=1e-3)

    weak = run({"thrust_scale": 0.9, "planner_told": False}, days=4)
    rows = _burn_rows(weak, tmp_path, "weak")
    assert {r["status"] for r in rows} == {"degraded"}
    delivered = float(weak.final.dv_mps - weak.params.initial.dv_mps)
    assert abs(sum(float(r["dv_mps"]) for r in rows) - delivered) < 1e-8 * len(rows) + 1e-9 * delivered


@pytest.mark.parametrize("beta_min_deg", [0.0, 10.0])
def test_one_arm_keeps_the_pairs_effect_on_drift_eccentricity_and_inclination(beta_min_deg):
    """Li's QFFC pairs of a short run, flown by one arm (``control.burns.one_arm``): by the effect matrix of eq.
    (29) (``control.qffc.effect``, computed apart from the transform) the one arm's two burns move the drift, the
    eccentricity vector and the inclination vector as the pair did, and each burn lies within the keeper's arm
    limits of eq. (1) (the pitch floor 10 deg too: the lost node's burn then pitches at the floor, the keeper's
    node makes up its inclination)."""
    import jax

    from geojax.control import burns as burns_mod
    from geojax.control.qffc import effect
    from geojax.physics.propulsion import alpha_beta_bounds, arm_limits_deg

    r = run({}, days=3)
    pairs = r.records.cycles.controller["burns"]
    limits = arm_limits_deg(70.0, beta_min_deg, 60.0, 30.0)
    (alpha_lo, alpha_hi), (beta_lo, beta_hi) = alpha_beta_bounds(limits)
    checked = 0
    for cycle in range(1, 3):
        pair = jax.tree_util.tree_map(lambda x: x[cycle], pairs)
        l_start = float(pair.l_rad[0]) - 1.0
        before = np.asarray(effect(pair, l_start))
        for keeper in (0, 1):
            one = burns_mod.one_arm(pair, keeper, limits)
            after = np.asarray(effect(one, l_start))
            scale = np.abs(before[1:]).max()
            np.testing.assert_allclose(after[1:], before[1:], rtol=0, atol=1e-9 * scale)
            tol = 1e-9
            assert np.all((np.asarray(one.alpha_rad) >= float(alpha_lo[keeper]) - tol)
                          & (np.asarray(one.alpha_rad) <= float(alpha_hi[keeper]) + tol))
            assert np.all((np.asarray(one.beta_rad) >= float(beta_lo[keeper]) - 1e-6)
                          & (np.asarray(one.beta_rad) <= float(beta_hi[keeper]) + 1e-6))
            np.testing.assert_allclose(np.asarray(one.v_mps), np.linalg.norm(np.asarray(one.dv_rsw_mps), axis=1))
            checked += 1
    assert checked == 4


def test_an_arm_lost_is_kept_by_the_other_arm_when_the_planner_is_told():
    """Li's two thrusters, thruster 0 (arm 0) out from day 10 to the end: told, the planner flies both nodes from
    arm 1 and the box is kept for 60 days (the loop's box check at every step start), thruster 0 firing nothing
    after the cycle that met the outage (/cycles); not told, it plans the pair as if nothing were wrong, half of
    it is never flown, and the sample leaves its box (status 2 or 3, days out of it counted)."""
    lost = {"thruster_out": 0, "out_from_day": 10.0}
    told = run(lost, days=60)
    table = told.cycles()
    t_days = np.asarray(table["t_s"]) / SECONDS_PER_DAY
    assert told.status == 0 and float(told.metrics["days_out_of_box"]) == 0.0
    assert np.all(np.asarray(table["fired_s_t0"])[t_days > 11.0] == 0)
    assert float(told.metrics["burns_t1"]) > 1.5 * float(told.metrics["burns_t0"])
    unaware = run({**lost, "planner_told": False}, days=60)
    assert unaware.status in (2, 3) and float(unaware.metrics["days_out_of_box"]) > 0


def test_a_drawn_outage_start_is_uniform_over_its_spread():
    """``out_from_spread_days``: the part's first cycle start draws the outage's start uniform over [out_from_day,
    out_from_day + spread) from its own key.  Over 2000 keys the draws pass a Kolmogorov-Smirnov test against the
    uniform law (the 1 % critical distance 1.63 / sqrt(n)), and the missed burns' draws of that cycle are those of
    a run without the spread (the outage's draw is a stream apart)."""
    import jax

    from geojax.states import faults
    from geojax.states.base import CycleStart

    sc = geojax.load_scenario("li2022-qffc", {"duration.days": 30, "faults.out_from_day": 5.0,
                                              "faults.out_from_spread_days": 20.0, "faults.thruster_out": 0})
    plain = geojax.load_scenario("li2022-qffc", {"duration.days": 30, "faults.out_from_day": 5.0,
                                                 "faults.thruster_out": 0})
    from types import SimpleNamespace

    def first(scenario, key):
        params = SimpleNamespace(states={"faults": faults.leaves(scenario.config["faults"])},
                                 thrusters={f"{name}_rad": math.radians(scenario.config["thrusters"][f"{name}_deg"])
                                            for name in ("beta_max", "beta_min", "alpha_max", "alpha_min")})
        zero = jax.numpy.zeros(3)
        start = CycleStart(jax.numpy.asarray(0), jax.numpy.asarray(0.0), zero, zero, jax.numpy.asarray(1.0), key)
        state = faults.init(params, zero, zero, None, None)
        return faults.cycle(params, state, start)

    keys = jax.random.split(jax.random.key(7), 2000)
    drawn = jax.vmap(lambda k: first(sc, k))(keys)
    days = np.sort(np.asarray(drawn.out_from_s)) / SECONDS_PER_DAY
    assert days.min() >= 5.0 and days.max() < 25.0
    uniform = (days - 5.0) / 20.0
    n = len(uniform)
    distance = max(np.max(np.arange(1, n + 1) / n - uniform), np.max(uniform - np.arange(n) / n))
    assert distance < 1.63 / math.sqrt(n)
    without = jax.vmap(lambda k: first(plain, k))(keys[:50])
    np.testing.assert_array_equal(np.asarray(without.missed), np.asarray(drawn.missed)[:50])
    assert np.all(np.asarray(without.out_from_s) == 5.0 * SECONDS_PER_DAY)


def test_uniform_over_the_run_and_the_loop_flies_the_drawn_outage():
    """``out_from_day = "uniform"``: the start spread over the run's length, one draw per sample (two seeds, two
    starts); in the closed loop thruster 0 (the planner not told) delivers what it was commanded in every cycle
    that ends before the drawn start and nothing in every cycle that begins after it (the /cycles columns)."""
    sc = geojax.load_scenario("li2022-qffc", {"duration.days": 20, "faults.out_from_day": "uniform",
                                              "faults.thruster_out": 0, "faults.planner_told": False})
    assert sc.config["faults"]["out_from_day"] == 0.0 and sc.config["faults"]["out_from_spread_days"] == 20.0
    starts = []
    for seed in (1, 2):
        r = geojax.simulate(sc, seed=seed)
        start_s = np.asarray(r.records.cycles.states["faults"].out_from_s)
        assert np.all(start_s == start_s[0]) and 0 <= start_s[0] < 20 * SECONDS_PER_DAY
        table = r.cycles()
        t0 = np.asarray(table["t_s"]) - np.diff(np.asarray(table["t_s"]))[0] / 2  # cycle starts (t_s: mid-cycle)
        cycle_s = np.diff(t0)[0]
        fired, planned = np.asarray(table["fired_s_t0"]), np.asarray(table["planned_s_t0"])
        before, after = t0 + cycle_s <= start_s[0], t0 >= start_s[0]
        np.testing.assert_array_equal(fired[before], planned[before])
        assert np.all(fired[after] == 0)
        starts.append(start_s[0])
    assert starts[0] != starts[1]


def test_two_thrusters_out_of_four_lose_an_arm_and_a_scale_per_thruster():
    """Four thrusters, thrusters 0 and 2 (both of arm 0) out from day 10, the planner told: arm 1 keeps the box
    alone for 30 days and neither of arm 0's thrusters fires after the cycle that met the outage.  A scale per
    thruster, [0.9, 1, 1, 1] unaware: the first cycle's Delta-V is 0.9 of the nominal run's burn of thruster 0
    plus its burn of thruster 1 (the burns files of both runs; F t / m linear in thrust to 1e-5)."""
    r = run({"thruster_out": [0, 2], "out_from_day": 10.0}, days=30, count=4)
    table = r.cycles()
    late = np.asarray(table["t_s"]) / SECONDS_PER_DAY > 11.0
    assert r.status == 0
    assert np.all(np.asarray(table["fired_s_t0"])[late] == 0) and np.all(np.asarray(table["fired_s_t2"])[late] == 0)
    assert np.all(np.asarray(table["fired_s_t1"])[late] + np.asarray(table["fired_s_t3"])[late] > 0)

    from geojax.export import trajectory

    nominal = trajectory.run_burns(run({"planner_told": False}, days=2))
    weak = run({"thrust_scale": [0.9, 1.0, 1.0, 1.0], "planner_told": False}, days=2)
    first = nominal.cycle == 0
    dv = np.linalg.norm(nominal.dv_rtn_mps[first], axis=1)
    expected = np.sum(np.where(nominal.thruster[first] == 1, 0.9, 1.0) * dv)
    assert float(np.asarray(weak.records.cycles.dv_mps)[0]) == pytest.approx(expected, rel=1e-5)
    marked = trajectory.run_burns(weak)
    assert set(marked.status[(marked.cycle == 0) & (marked.thruster == 1)]) == {"degraded"}
    assert set(marked.status[(marked.cycle == 0) & (marked.thruster == 2)]) == {"flown"}


def test_four_thrusters_one_out_fly_the_redundant_one_at_the_same_delta_v():
    """Four thrusters, thruster 0 out from day 10 to the end, the planner told: thruster 0 fires nothing after
    the cycle that met the outage (/cycles), thruster 2 (arm 0's second) takes its burns, the box is kept for 60
    days, and the Delta-V is within 3 % of the same run without the fault (a second run: the fault's cost)."""
    lost = run({"thruster_out": 0, "out_from_day": 10.0}, days=60, count=4)
    whole = run({"enabled": True}, days=60, count=4)
    table = lost.cycles()
    late = np.asarray(table["t_s"]) / SECONDS_PER_DAY > 11.0
    assert lost.status == 0
    assert np.all(np.asarray(table["fired_s_t0"])[late] == 0) and np.all(np.asarray(table["fired_s_t2"])[late] > 0)
    dv_lost, dv_whole = float(lost.metrics["dv_per_year_mps"]), float(whole.metrics["dv_per_year_mps"])
    assert abs(dv_lost - dv_whole) <= 0.03 * dv_whole
