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
from geojax.navigation.schedule import overlaps_pass, schedule, tracking_weight
from geojax.physics.propulsion import PRESETS_DEG, arm_limits_deg

DAY_S = 86400.0


def _tracks(times_s, plan):
    """``tracking_weight`` > 0 at each time (numpy, no outages): the schedule's definition, sampled."""
    return np.mod(np.asarray(times_s)[..., None] - np.asarray(plan.phase_s), np.asarray(plan.cadence_s)) < np.asarray(
        plan.pass_s)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_window_meets_a_pass_where_the_sampled_schedule_tracks_in_it(seed):
    """Independent: the closed form of ``overlaps_pass`` against the schedule sampled every second over the window
    (no outages), for random windows and schedules (passes of 10 min to 6 h, cadence 6-24 h); the sampling is
    ``tracking_weight``'s own at a few times."""
    rng = np.random.default_rng(seed)
    overlaps = jax.jit(overlaps_pass)
    for _ in range(40):
        cadence = rng.uniform(6, 24) * 3600.0
        plan = schedule(cadence, rng.uniform(600.0, min(6 * 3600.0, cadence)), rng.uniform(-DAY_S, DAY_S))
        start = rng.uniform(0.0, 3 * DAY_S)
        length = rng.uniform(0.0, 0.9 * (cadence - float(plan.pass_s)) + 1.0)
        sampled = _tracks(start + np.arange(0.0, length, 1.0), plan)
        assert bool(overlaps(start, start + length, plan)) == bool(np.any(sampled))
        few = start + rng.uniform(0.0, 2 * DAY_S, 16)
        np.testing.assert_array_equal(_tracks(few, plan)[:, 0], np.asarray(tracking_weight(few, plan)) > 0)


def test_the_shift_is_the_least_that_clears_every_pass():
    """Brute force: over random node angles, the shift ``node_shift_rad`` picks keeps both burns' windows (with the
    margin) out of both stations' passes (sampled every 10 s), and no candidate of smaller |shift| does; with no
    pass in the way the nodes stay (shift 0)."""
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
    far = jax.tree_util.tree_map(lambda x: x[:1], stations)._replace(pass_s=jnp.asarray([1.0]),
                                                                     phase_s=jnp.asarray([0.5]))
    shift, _ = shift_of(1.0, 0.0, 10.0 * 86164.1, cycle_s, jnp.asarray([0.0, 0.0]), 0.0, far)
    assert float(shift) == 0.0


@pytest.mark.parametrize("shift_deg", [10.0, -25.0])
def test_the_moved_pair_corrects_the_inclination_along_its_line(shift_deg):
    """Closed form: two burns on the line through l_2 + Delta change the inclination vector only along that line;
    with |V_N| = cos(Delta) 2 V_s |di| (``model_cycle``'s choice) eq. (29) holds for the in-plane rows (the drift row
    shifted by the V_DT raise, as at eq. (31)'s nodes) and the inclination rows are di's projection on the line."""
    limits = arm_limits_deg(*PRESETS_DEG["normal"])
    rng = np.random.default_rng(11)
    scale = np.array([2e-4, 2e-9, 1.5e-5, 1.5e-5, 2.5e-5, 2.5e-5])
    dx = jnp.asarray(rng.uniform(-1, 1, (60, 6)) * scale)
    l_start = jnp.asarray(rng.uniform(0, 2 * np.pi, 60))
    delta = np.radians(shift_deg)
    sol = jax.jit(jax.vmap(lambda d, l0: qffc.solve(
        d, l0, limits, v_n_mps=np.cos(delta) * qffc.full_correction_mps(d), node_shift_rad=delta)))(dx, l_start)
    keep = np.asarray(sol.feasible)
    assert keep.mean() > 0.9
    np.testing.assert_allclose(sol.l_rad[:, 1], jnp.arctan2(dx[:, 5], dx[:, 4]) + delta, atol=1e-12)
    achieved = np.asarray(jax.vmap(qffc.effect)(sol, l_start))[keep]
    expected = np.asarray(dx.at[:, 1].add(-3 / R_SYNC_M * sol.vdt_raise_mps))[keep]
    np.testing.assert_allclose(achieved[:, :4], expected[:, :4], rtol=1e-9, atol=1e-15)
    line = np.stack([np.cos(sol.l_rad[:, 1]), np.sin(sol.l_rad[:, 1])], -1)[keep]
    projection = np.sum(np.asarray(dx)[keep, 4:] * line, -1, keepdims=True) * line
    np.testing.assert_allclose(achieved[:, 4:], projection, rtol=1e-9, atol=1e-15)


def test_around_passes_needs_stations_and_the_qffc():
    for name, message in (("li2022-qffc", "controller.around_passes: plans the burns around the stations' passes"),
                          ("li2022-fompc", "controller.around_passes: the fompc controller does not plan around")):
        with pytest.raises(ValueError, match=message):
            scenario.load(name, {"controller.around_passes": True})
    assert scenario.load("li2022-qffc-ranging", {"controller.around_passes": True}).config["controller"]["around_passes"]
