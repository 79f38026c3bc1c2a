"""The wheels' momentum (``geojax.states.momentum``) and the loop's extension point (``geojax.states.base``).

Independent checks: the bit-for-bit numbers of main's code where no state is carried (a second checkout run in
a subprocess); the SRP-offset torque's momentum against a separate quadrature of the SRP force (issue 41's
check, within 2 %); the gravity-gradient momentum against the closed-form solutions of the body-frame equation;
the conservation of the total angular momentum without torque (with the closed-form rotation in body axes);
bad input refused with one line naming the key.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import cli, scenario
from geojax.loop import setup
from geojax.loop.metrics import STATUS_MEANINGS, STATUS_WHEELS_SATURATED
from geojax.loop.rollout import rollout_fn, simulate
from geojax.loop.simulate import simulate as closed_loop
from geojax.physics import constants as c
from geojax.physics.ephemeris import sun_position_eci_m
from geojax.physics.frames import earth_rotation_angle_rad
from geojax.states.base import StateModel

ROOT = Path(__file__).resolve().parents[1]
# main just before the further states existed (5657130 added them): the numbers every run without them must keep
BASELINE_COMMIT = "5657130^"
DAYS = 4
N_RATE = 2 * np.pi / c.SIDEREAL_DAY_S  # GEO mean motion, rad/s

# Runs the same short rollouts with whatever geojax is on PYTHONPATH and writes every metric, the status and
# every cycle record (but the further states', absent on main) to an .npz: the padded loop (``simulate``) for the
# QFFC with errors and the plain scan (``rollout_fn``, what sweeps and tunings run) for Katz's continuous law.
SNIPPET = r"""
import sys, jax, numpy as np
import geojax
from geojax import scenario
from geojax.loop import setup
from geojax.loop.rollout import rollout_fn, simulate

def flat(tree, prefix, out):
    if hasattr(tree, "_fields"):
        for k in tree._fields:
            if k != "states":
                flat(getattr(tree, k), f"{prefix}.{k}", out)
    elif isinstance(tree, dict):
        for k, v in tree.items():
            flat(v, f"{prefix}.{k}", out)
    elif tree is not None:
        out[prefix] = np.asarray(tree)
    return out

out = {}
sc = scenario.load("li2022-qffc", {"duration.days": DAYS, "errors.h_rv": 1.0, "errors.h_att": 1.0})
r = simulate(sc, seed=3)
flat(r.records, "qffc.records", out)
flat(r.metrics, "qffc.metrics", out)
out["qffc.status"] = np.asarray(r.status)
batch = setup.prepare([scenario.load("katz2025-continuous", {"duration.days": DAYS})])
params = jax.tree_util.tree_map(lambda x: x[0], batch.params)
_, records, metrics = jax.jit(rollout_fn(batch))(params, jax.random.key(5))
flat(records, "katz.records", out)
flat(metrics, "katz.metrics", out)
np.savez(sys.argv[1], **out)
""".replace("DAYS", str(DAYS))


def _run_snippet(pythonpath, path):
    env = {**os.environ, "PYTHONPATH": str(pythonpath)}
    subprocess.run([sys.executable, "-c", SNIPPET, str(path)], env=env, check=True, timeout=900)
    with np.load(path) as data:
        return {k: data[k] for k in data.files}


def _baseline_checkout(folder: Path) -> Path:
    """``geojax/`` of ``BASELINE_COMMIT`` extracted into ``folder`` (skips where the clone has no history)."""
    if not (ROOT / ".git").exists():
        pytest.skip("not a git checkout: no baseline commit to compare against")
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", BASELINE_COMMIT, "geojax"], capture_output=True)
    if archive.returncode != 0:
        pytest.skip(f"baseline {BASELINE_COMMIT} not in this clone: {archive.stderr.decode().strip()}")
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive.stdout, check=True)
    return folder


def test_no_state_is_bit_for_bit_mains_numbers(tmp_path):
    """Without ``attitude.wheels`` every record, metric and status is main's before the states existed, bit for
    bit (padded and plain loops): the same snippet run on this checkout and on ``BASELINE_COMMIT``'s geojax."""
    ours = _run_snippet(ROOT, tmp_path / "ours.npz")
    (tmp_path / "baseline").mkdir()
    mains = _run_snippet(_baseline_checkout(tmp_path / "baseline"), tmp_path / "main.npz")
    assert sorted(ours) == sorted(mains)
    differ = [k for k in mains if not np.array_equal(ours[k], mains[k], equal_nan=True)]
    assert not differ, differ
    assert any(k.startswith("qffc.records.cycles.controller") for k in ours)


def _wheels(days=DAYS, **attitude):
    overrides = {"duration.days": days, "attitude.wheels": True}
    overrides.update({f"attitude.{k}": v for k, v in attitude.items()})
    return scenario.load("li2022", overrides)


def test_srp_offset_along_the_array_axis_grows_momentum_at_d_times_the_perpendicular_force():
    """Issue 41's check.  An SRP force F acting at d along the orbit normal n_hat on a nadir-pointing body, no
    dumping: the inertial angular momentum grows by tau = d n_hat x F, whose secular part is d |F_perp| per second
    (F_perp: F less its component along n_hat).  Expected: a separate quadrature (60 s trapezoid) of d n_hat x F
    over the run, F = -P (1 + eta) A (1 AU / rho)^2 rho_hat from the Sun's position and the station's circular
    orbit (January: no eclipse); the body inertia is made negligible (1 kg m^2), so |h_w| = |H|."""
    d_m = 0.1
    sc = _wheels(srp_offset_array_m=[d_m, 0.0, 0.0], inertia_kg_m2=[1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
    result = simulate(sc)
    cycles = result.records.cycles.states["wheels"]
    run_s = len(cycles.end_nms) * c.SIDEREAL_DAY_S

    t = np.arange(0.0, run_s + 1.0, 60.0)
    station_rad = np.radians(sc.station_lon_deg)
    theta = station_rad + np.asarray(earth_rotation_angle_rad(sc.epoch_tt_s + t, sc.epoch_tt_s, sc.tt_minus_ut1_s))
    radius_m = 42164.16e3
    r = radius_m * np.stack([np.cos(theta), np.sin(theta), np.zeros_like(t)], axis=-1)
    sun = np.asarray(sun_position_eci_m(jnp.asarray(sc.epoch_tt_s + t), sc.epoch_tt_s))
    rho = sun - r
    dist = np.linalg.norm(rho, axis=-1, keepdims=True)
    craft = sc.config["spacecraft"]
    force = -sc.config["forces"]["srp_pressure_n_m2"] * (1 + craft["reflectivity"]) * craft["srp_area_m2"] * (
        c.AU_M / dist) ** 2 * rho / dist
    normal = np.array([0.0, 0.0, 1.0])  # the station's orbit is equatorial to 1e-3
    torque = d_m * np.cross(normal, force)
    expected = np.sum((torque[1:] + torque[:-1]) / 2 * np.diff(t)[:, None], axis=0)

    got = np.linalg.norm(cycles.end_nms[-1] - cycles.start_nms[0])
    assert got == pytest.approx(np.linalg.norm(expected), rel=0.02)
    f_perp = np.linalg.norm(force[:, :2], axis=-1)
    assert result.metrics["wheel_momentum_per_day_nms"] == pytest.approx(d_m * np.mean(f_perp) * c.SECONDS_PER_DAY,
                                                                          rel=0.02)
    # The torque is perpendicular to the normal: the pitch wheel (body y, the anti-normal) stores none of it but
    # what the osculating normal's wobble (inclination 1e-4) leaves, parts in 1e4.
    assert np.max(np.abs(cycles.max_abs_nms[:, 1])) < 1e-4 * np.max(cycles.max_abs_nms)
    assert result.metrics["srp_torque_impulse_nms"] == pytest.approx(
        np.sum((np.linalg.norm(torque[1:], axis=-1) + np.linalg.norm(torque[:-1], axis=-1)) / 2 * np.diff(t)),
        rel=0.02)
    assert result.metrics["gravity_gradient_impulse_nms"] < 1e-9


def _mean_motion(sc):
    """The orbit's angular rate |r x v| / r^2 at the start (the closed forms' n)."""
    from geojax.physics.elements import mee_to_cartesian
    r, v = (np.asarray(x) for x in mee_to_cartesian(jnp.asarray(sc.initial_mee), sc.force_model.mu_m3_s2))
    return np.linalg.norm(np.cross(r, v)) / np.dot(r, r)


def test_gravity_gradient_of_principal_axes_is_zero_and_of_a_product_of_inertia_the_closed_form():
    """At nadir, r_b = (0, 0, -r), so tau_gg = 3 mu / r^5 (r_b x I r_b) = 3 n^2 (-I_yz, I_xz, 0): zero for
    principal axes; with I_xz alone a constant pitch torque and omega x I omega = 0, so h_y = 3 n^2 I_xz t
    (secular, the roll and yaw wheels none); with I_yz alone the body-frame equation dh/dt = tau - omega x (I omega
    + h), omega = (0, -n, 0), reads dh_x/dt = f + n h_z, dh_z/dt = -n h_x with f = -3 n^2 I_yz - n^2 I_yz: from
    rest, h_x = (f/n) sin(nt), h_z = (f/n)(cos(nt) - 1) (bounded: the cyclic momentum of a product of inertia)."""
    principal = simulate(_wheels(days=1), keep_steps=True)
    assert principal.metrics["gravity_gradient_impulse_nms"] < 1e-9
    # No torque; what the wheels hold is the change of I omega as the orbit rate n varies on the (e ~ 1e-4)
    # orbit, about 2 e n I_yy = 1e-4 N m s.
    assert principal.metrics["max_wheel_momentum_nms"] < 2 * 1e-3 * N_RATE * 7925.0

    i_xz = 500.0
    sc = _wheels(days=2, inertia_kg_m2=[85866.7, 7925.0, 83566.7, 0.0, i_xz, 0.0])
    n = _mean_motion(sc)
    got = simulate(sc, keep_steps=True).records.steps.states["wheels"].h_nms.reshape(-1, 3)
    t = np.arange(len(got)) * (c.SIDEREAL_DAY_S / 96)
    np.testing.assert_allclose(got[:, 1], 3 * n**2 * i_xz * t, rtol=1e-3, atol=1e-3 * 3 * n**2 * i_xz * t[-1])
    assert np.max(np.abs(got[:, [0, 2]])) < 1e-3 * np.max(np.abs(got[:, 1]))

    i_yz = 500.0
    sc = _wheels(days=1, inertia_kg_m2=[85866.7, 7925.0, 83566.7, 0.0, 0.0, i_yz])
    n = _mean_motion(sc)
    got = simulate(sc, keep_steps=True).records.steps.states["wheels"].h_nms.reshape(-1, 3)
    t = np.arange(len(got)) * (c.SIDEREAL_DAY_S / 96)
    f = -4 * n**2 * i_yz
    amplitude = abs(f / n)
    np.testing.assert_allclose(got[:, 0], f / n * np.sin(n * t), atol=2e-3 * amplitude)
    np.testing.assert_allclose(got[:, 2], f / n * (np.cos(n * t) - 1), atol=2e-3 * amplitude)
    # (the pitch wheel: only the change of I_yy n with the orbit rate, 1e-4 N m s, as for principal axes)
    np.testing.assert_allclose(got[:, 1], 0.0, atol=2e-3 * amplitude)


def test_without_torque_the_total_momentum_is_conserved_and_turns_in_body_axes():
    """No torque (principal axes, no offset): the inertial H = I omega + h_w is constant, so |h_w + I omega| is
    (conservation law), and in body axes a momentum in the orbit plane turns at -n about y: h_x = h_x0 cos(nt) +
    h_z0 sin(nt), h_z = h_z0 cos(nt) - h_x0 sin(nt) (the closed form of dh/dt = -omega x h)."""
    h0 = np.array([10.0, 0.0, 20.0])
    sc = _wheels(days=2, initial_momentum_nms=h0.tolist())
    n = _mean_motion(sc)
    got = simulate(sc, keep_steps=True).records.steps.states["wheels"].h_nms.reshape(-1, 3)
    t = np.arange(len(got)) * (c.SIDEREAL_DAY_S / 96)
    i_omega = np.array([0.0, -n * 7925.0, 0.0])
    total = np.linalg.norm(got + i_omega, axis=1)
    np.testing.assert_allclose(total, np.linalg.norm(h0 + i_omega), rtol=1e-5)
    np.testing.assert_allclose(got[:, 0], h0[0] * np.cos(n * t) + h0[2] * np.sin(n * t), atol=1e-3 * 22.4)
    np.testing.assert_allclose(got[:, 2], h0[2] * np.cos(n * t) - h0[0] * np.sin(n * t), atol=1e-3 * 22.4)


def test_saturated_wheels_are_status_6_and_the_sample_is_kept():
    """12 N m s a day of SRP momentum (d = 0.1 m) in 5 N m s wheels: saturated within the first day, status 6
    ("wheels saturated"), every metric finite; the time above 80 % of capacity is most of the run."""
    result = simulate(_wheels(days=2, srp_offset_array_m=[0.1, 0.0, 0.0], wheel_capacity_nms=5.0))
    assert STATUS_MEANINGS[STATUS_WHEELS_SATURATED] == "wheels saturated"
    assert result.status == STATUS_WHEELS_SATURATED
    assert all(np.isfinite(v) for v in result.metrics.values())
    assert result.metrics["max_wheel_momentum_nms"] > 5.0
    assert 0.5 < result.metrics["time_above_80pct_capacity_fraction"] < 1.0
    assert "wheel_max_abs_x_nms" in result.cycles()


def _counter_init(params, r, v):
    return {"steps": jnp.zeros(()), "cycles": jnp.zeros(()), "t_s": jnp.zeros(())}


def _counter_step(params, state, ctx):
    # the step's end position is the orbit one step on: |r_end| within 1e-3 of |r| at GEO
    ratio = jnp.linalg.norm(ctx.r_end_eci_m) / jnp.linalg.norm(ctx.r_eci_m)
    return {**state, "steps": state["steps"] + 1, "t_s": state["t_s"] + ctx.step_s}, ratio


def _counter_cycle(params, state, start):
    return {**state, "cycles": state["cycles"] + 1}


def _counter_summary(params, start, end, steps):
    return {"end": end, "max_ratio_error": jnp.max(jnp.abs(steps - 1))}


COUNTER = StateModel("counter", _counter_init, _counter_step, _counter_summary, metrics=None, cycle=_counter_cycle)


@pytest.mark.parametrize("pad", [False, True])
def test_extension_point_carries_a_state_through_steps_and_cycles(pad):
    """A counting state through the loop's carry, plain and padded (``Shared.n_active``): after cycle k it has
    seen k + 1 cycle starts and (k + 1) x 96 steps, and its time is theirs; the padded slots stay zero."""
    batch = setup.prepare([scenario.load("li2022", {"duration.days": 3})], pad=pad)
    params = jax.tree_util.tree_map(lambda x: x[0], batch.params)
    _, records = jax.jit(lambda p: closed_loop(batch.controller, p, batch.shared, jax.random.key(0),
                                               step_s=batch.step_s, states=(COUNTER,)))(params)
    rec = records.cycles.states["counter"]
    k = np.arange(1, 4)
    np.testing.assert_array_equal(rec["end"]["cycles"][:3], k)
    np.testing.assert_array_equal(rec["end"]["steps"][:3], 96 * k)
    np.testing.assert_allclose(rec["end"]["t_s"][:3], k * c.SIDEREAL_DAY_S, rtol=1e-12)
    assert np.max(rec["max_ratio_error"][:3]) < 1e-3
    if pad:
        assert np.all(np.asarray(rec["end"]["steps"][3:]) == 0)


@pytest.mark.parametrize("key, value, says", [
    ("attitude.wheel_capacity_nms", -50.0, "attitude.wheel_capacity_nms: must be > 0"),
    ("attitude.inertia_kg_m2", [1e4, float("nan"), 1e4, 0, 0, 0], "attitude.inertia_kg_m2: must be a list of 6 finite"),
    ("attitude.inertia_kg_m2", [1e4, 1e3, 1e3, 0, 0, 0], "attitude.inertia_kg_m2: not a physical inertia tensor"),
    ("attitude.srp_offset_body_m", [0.1, 0.0], "attitude.srp_offset_body_m: must be a list of 3"),
])
def test_bad_input_is_refused_with_one_line_naming_the_key(tmp_path, capsys, key, value, says):
    table, name = key.split(".")
    text = scenario.read_text("li2022") + f"\n[{table}]\nwheels = true\n{name} = {json.dumps(value).replace('NaN', 'nan')}\n"
    path = tmp_path / "bad.toml"
    path.write_text(text)
    before = sorted(p.name for p in tmp_path.iterdir())
    assert cli.main(["simulate", str(path), "--out", str(tmp_path / "out.h5")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_attitude_keys_need_the_wheels_and_an_srp_offset_needs_srp():
    with pytest.raises(ValueError, match=r"attitude.wheel_capacity_nms: read only where attitude.wheels = true"):
        scenario.load("li2022", {"attitude.wheel_capacity_nms": 20.0})
    with pytest.raises(ValueError, match=r"attitude.srp_offset_array_m: an SRP torque needs SRP"):
        scenario.load("li2022", {"attitude.wheels": True, "attitude.srp_offset_array_m": [0.1, 0, 0],
                                 "forces.srp": False})
