"""Burns planned around the tracking passes (``geojax.control.around_passes``, ``controller.around_passes``): the
pass test against a brute-force sampling of the schedule, the least clear shift against a search of every
candidate, the moved pair's correction against its closed form (eq. (29) at the moved nodes)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import scenario
from geojax.control import around_passes, qffc
from geojax.control.effects import R_SYNC_M
from geojax.navigation.schedule import overlaps_pass, schedule, time_in_passes_s, tracking_weight
from geojax.physics.constants import SIDEREAL_DAY_S
from geojax.physics.propulsion import PRESETS_DEG, arm_limits_deg

DAY_S = 86400.0


def _tracks(times_s, plan):
    """``tracking_weight`` > 0 at each time (numpy, no outages): the schedule's definition, sampled."""
    return np.mod(np.asarray(times_s)[..., None] - np.asarray(plan.phase_s), np.asarray(plan.cadence_s)) < np.asarray(
        plan.pass_s)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_window_meets_a_pass_where_the_sampled_schedule_tracks_in_it(seed):
    """Independent: the closed forms of ``overlaps_pass`` and ``time_in_passes_s`` against the schedule sampled every
    second over the window
    (no outages), for random windows and schedules (passes of 10 min to 6 h, cadence 6-24 h); the sampling is
    ``tracking_weight``'s own at a few times."""
    rng = np.random.default_rng(seed)
    overlaps, inside = jax.jit(overlaps_pass), jax.jit(time_in_passes_s)
    for _ in range(40):
        cadence = rng.uniform(6, 24) * 3600.0
        plan = schedule(cadence, rng.uniform(600.0, min(6 * 3600.0, cadence)), rng.uniform(-DAY_S, DAY_S))
        start = rng.uniform(0.0, 3 * DAY_S)
        length = rng.uniform(0.0, 0.9 * (cadence - float(plan.pass_s)) + 1.0)
        sampled = _tracks(start + np.arange(0.0, length, 1.0), plan)
        assert bool(overlaps(start, start + length, plan)) == bool(np.any(sampled))
        assert float(inside(start, start + length, plan)) == pytest.approx(np.sum(sampled), abs=2.0)
        few = start + rng.uniform(0.0, 2 * DAY_S, 16)
        np.testing.assert_array_equal(_tracks(few, plan)[:, 0], np.asarray(tracking_weight(few, plan)) > 0)


def test_the_shift_is_the_least_that_clears_every_pass():
    """Brute force: over random node angles, the shift ``node_shift_rad`` picks keeps both burns' windows (with the
    margin) out of both stations' passes (sampled every 10 s), and no candidate of smaller |shift| does; where no
    candidate clears them, the one it picks leaves the least burn time in them; with no pass in the way the nodes
    stay (shift 0)."""
    stations = jax.tree_util.tree_map(lambda *x: jnp.stack(x), schedule(DAY_S / 2, 7200.0, 3000.0),
                                      schedule(DAY_S / 2, 7200.0, 3600.0))
    rng = np.random.default_rng(7)
    shift_of = jax.jit(around_passes.node_shift_rad)
    windows = jax.jit(around_passes.burn_windows_s)
    cycle_s, margin = 86164.1, 900.0
    burn_s = jnp.asarray([1500.0, 900.0])
    for _ in range(30):
        l2, l_start, t0 = rng.uniform(0, 2 * np.pi), rng.uniform(0, 2 * np.pi), rng.uniform(0, 10 * DAY_S)
        shift, clear = shift_of(l2, l_start, t0, cycle_s, burn_s, margin, stations)

        def meets(delta):
            l_rad = jnp.asarray([l2 + delta - np.pi, l2 + delta])
            start, stop = windows(l_rad, l_start, t0, cycle_s, burn_s)
            times = np.concatenate([np.arange(a - margin, b + margin, 10.0) for a, b in zip(start, stop)])
            return bool(np.any(_tracks(times, stations)))

        assert bool(clear)
        assert not meets(float(shift))
        smaller = [d for d in around_passes.SHIFTS_RAD if abs(d) < abs(float(shift)) - 1e-12]
        assert all(meets(d) for d in smaller)
    # passes 11.5 h of every 12 h: nothing clears; the shift loses the least burn time to them (sampled every 10 s)
    busy = stations._replace(pass_s=jnp.asarray([41400.0, 41400.0]))
    for _ in range(5):
        l2, l_start, t0 = rng.uniform(0, 2 * np.pi), rng.uniform(0, 2 * np.pi), rng.uniform(0, 10 * DAY_S)
        shift, clear = shift_of(l2, l_start, t0, cycle_s, burn_s, 0.0, busy)

        def lost(delta):
            l_rad = jnp.asarray([l2 + delta - np.pi, l2 + delta])
            start, stop = windows(l_rad, l_start, t0, cycle_s, burn_s)
            return sum(10.0 * np.sum(np.any(_tracks(np.arange(a, b, 10.0), busy), -1)) for a, b in zip(start, stop))

        assert not bool(clear)
        assert lost(float(shift)) <= min(lost(d) for d in around_passes.SHIFTS_RAD) + 40.0
    far = jax.tree_util.tree_map(lambda x: x[:1], stations)._replace(pass_s=jnp.asarray([1.0]),
                                                                     phase_s=jnp.asarray([0.5]))
    shift, _ = shift_of(1.0, 0.0, 10.0 * 86164.1, cycle_s, jnp.asarray([0.0, 0.0]), 0.0, far)
    assert float(shift) == 0.0


@pytest.mark.slow
def test_the_moved_pair_corrects_the_inclination_along_its_line():
    """Closed form: two burns on the line through l_2 + Delta change the inclination vector only along that line;
    with |V_N| = cos(Delta) 2 V_s |di| (``model_cycle``'s choice) eq. (29) holds for the in-plane rows (the drift row
    shifted by the V_DT raise, as at eq. (31)'s nodes) and the inclination rows are di's projection on the line."""
    limits = arm_limits_deg(*PRESETS_DEG["normal"])
    rng = np.random.default_rng(11)
    scale = np.array([2e-4, 2e-9, 1.5e-5, 1.5e-5, 2.5e-5, 2.5e-5])
    dx = jnp.asarray(rng.uniform(-1, 1, (60, 6)) * scale)
    l_start = jnp.asarray(rng.uniform(0, 2 * np.pi, 60))
    solve = jax.jit(jax.vmap(lambda d, l0, delta: qffc.solve(
        d, l0, limits, v_n_mps=jnp.cos(delta) * qffc.full_correction_mps(d), node_shift_rad=delta),
        in_axes=(0, 0, None)))
    for shift_deg in (10.0, -25.0):
        _check_moved_pair(solve(dx, l_start, np.radians(shift_deg)), dx, l_start, np.radians(shift_deg))


def _check_moved_pair(sol, dx, l_start, delta):
    keep = np.asarray(sol.feasible)
    assert keep.mean() > 0.9
    np.testing.assert_allclose(sol.l_rad[:, 1], jnp.arctan2(dx[:, 5], dx[:, 4]) + delta, atol=1e-12)
    achieved = np.asarray(jax.vmap(qffc.effect)(sol, l_start))[keep]
    expected = np.asarray(dx.at[:, 1].add(-3 / R_SYNC_M * sol.vdt_raise_mps))[keep]
    np.testing.assert_allclose(achieved[:, :4], expected[:, :4], rtol=1e-9, atol=1e-15)
    line = np.stack([np.cos(sol.l_rad[:, 1]), np.sin(sol.l_rad[:, 1])], -1)[keep]
    projection = np.sum(np.asarray(dx)[keep, 4:] * line, -1, keepdims=True) * line
    np.testing.assert_allclose(achieved[:, 4:], projection, rtol=1e-9, atol=1e-15)


def test_around_passes_needs_stations():
    for name in ("li2022-qffc", "li2022-fompc"):
        with pytest.raises(ValueError, match="controller.around_passes: plans the burns around the stations' passes"):
            scenario.load(name, {"controller.around_passes": True})
    for kind in ("qffc", "fompc"):
        sc = scenario.load("li2022-qffc-ranging", {"controller.around_passes": True, "controller.kind": kind})
        assert sc.config["controller"]["around_passes"]


@pytest.mark.slow  # two closed loops with the filter (a compilation each); the planner's parts are checked above
@pytest.mark.parametrize("kind", ["qffc", "fompc"])
def test_the_planner_flies_its_whole_burns_around_long_passes(kind):
    """The loop's check: passes of 4 h twice a day placed over the QFFC's burns (from 17000 s, where the unplanned
    burns of this draw fall), burns forbidden in them, no execution errors, 4 days of li2022-qffc-ranging.  Without
    the planner the passes cut the burns (the Delta-V delivered falls short of the plan's V_1 + V_2); with
    ``controller.around_passes`` every cycle delivers its plan (to 1e-3) and no burn's window meets a pass.  The QFFC
    and the FOMPC (its flown cycle moved, at the annealing's north-south fraction)."""
    from geojax.runner import rollout

    base = {"duration.days": 4, "navigation.burns_during_passes": False, "errors.sigma3_dv_pct": 0.0,
            "errors.sigma3_att_deg": 0.0, "navigation.stations[0].pass_s": 14400.0,
            "navigation.stations[1].pass_s": 14400.0, "navigation.stations[0].phase_s": 17000.0,
            "navigation.stations[1].phase_s": 17000.0}
    ratios = {}
    for around in (False, True):
        sc = scenario.load("li2022-qffc-ranging", {**base, "controller.around_passes": around, "controller.kind": kind})
        cycles = rollout.simulate(sc, 0).records.cycles
        planned = np.sum(np.asarray(cycles.controller["burns"].v_mps), axis=-1)
        ratios[around] = np.asarray(cycles.dv_mps) / np.maximum(planned, 1e-12)
        if around:
            stations = jax.tree_util.tree_map(lambda *x: jnp.stack(x), *(schedule(
                s["cadence_s"], s["pass_s"], s["phase_s"]) for s in sc.config["navigation"]["stations"]))
            burn_s = np.asarray(cycles.controller["fired_s"])  # [cycle, burn]
            start = np.arange(len(burn_s))[:, None] * SIDEREAL_DAY_S + np.asarray(cycles.controller["start_s"])
            meets = np.asarray(overlaps_pass(start[..., None], (start + burn_s)[..., None], stations))
            assert np.any(burn_s > 0) and not np.any(meets)
    assert np.min(ratios[False]) < 0.5
    np.testing.assert_allclose(ratios[True], 1.0, atol=1e-3)


PASSES_PART = '''
import jax.numpy as jnp
import geojax
from geojax.navigation.schedule import Schedule
from geojax.states.base import STATION_PASSES

# an operations team's pass plan: 4 h twice a day from 17000 s (over the QFFC's burns of li2022-qffc, seed 0)
PLAN = Schedule(jnp.array([43082.0]), jnp.array([14400.0]), jnp.array([17000.0]), jnp.zeros((1, 0, 2)))


def tell(params, state, told):
    return told._replace(states={**told.states, STATION_PASSES: PLAN})


MODEL = geojax.StateModel("ops_passes", lambda params, r, v, env, fm: jnp.zeros(()),
                          lambda params, state, ctx: (state, ()), lambda params, start, end, steps: (),
                          lambda params, cycles, n_steps, run_s: ({}, jnp.asarray(False)), estimate=tell)
PART = geojax.Part("ops_passes", model=MODEL, tells=lambda table: (STATION_PASSES,))
'''


def test_a_part_of_ones_own_that_tells_the_passes_serves_the_planner(tmp_path, monkeypatch):
    """The planner names no part: a part of one's own (no filter) that tells ``station_passes`` (an operator's pass
    plan) lets ``controller.around_passes`` load and plan, and no burn's window meets a pass, checked against the
    plan by ``overlaps_pass`` (without the planner every burn of these 3 days meets one); the scenario without the
    part is refused, naming what would tell the passes."""
    import geojax
    from geojax.runner import rollout

    (tmp_path / "ops_passes.py").write_text(PASSES_PART)
    monkeypatch.syspath_prepend(str(tmp_path))
    text = scenario.read_text("li2022-qffc").replace("[controller]", "[controller]\naround_passes = true", 1)
    (tmp_path / "told.toml").write_text('states = ["ops_passes:PART"]\n' + text)
    import ops_passes

    def meets(sc):
        cycles = rollout.simulate(sc, 0).records.cycles
        burn_s = np.asarray(cycles.controller["fired_s"])
        start = np.arange(len(burn_s))[:, None] * SIDEREAL_DAY_S + np.asarray(cycles.controller["start_s"])
        assert np.all(burn_s > 0)
        return np.asarray(overlaps_pass(start[..., None], (start + burn_s)[..., None], ops_passes.PLAN))

    assert not np.any(meets(geojax.load_scenario(str(tmp_path / "told.toml"), {"duration.days": 3})))
    assert np.all(meets(geojax.load_scenario("li2022-qffc", {"duration.days": 3})))
    (tmp_path / "untold.toml").write_text(text)
    with pytest.raises(ValueError, match=r"which no part of this scenario tells: set navigation.model = \"ekf\""):
        geojax.load_scenario(str(tmp_path / "untold.toml"))
