"""The reaction wheels over a transfer (``geojax.transfer.wheels``): frames, integration, unloading and the boom's
dumping tilt, each against a closed form or a conservation law; the bad input of the new keys."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import transfer
from geojax.physics import constants as c
from geojax.transfer import boom, steering, wheels

PARAMS = wheels.WheelParams(jnp.asarray(50.0), jnp.asarray(0.8), jnp.asarray(0.0), jnp.asarray(0.01))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_body_frame_turns_the_boom_thrust_onto_the_direction_flown(seed):
    """Closed form: at theta2 = 90 deg the boom's thrust in body axes, turned by the body's offsets
    (``body_to_rsw``), is the rollout's flown direction ``steering.direction_rsw`` at azimuth offset + theta1 +
    90 deg and elevation offset + theta3, to rounding; the rotation is orthonormal."""
    rng = np.random.default_rng(seed)
    body = jnp.asarray(rng.uniform(-0.6, 0.6, 2))
    theta = jnp.asarray([rng.uniform(-np.pi / 2, 0.0), np.pi / 2, rng.uniform(-0.26, 0.26)])
    rotation = wheels.body_to_rsw(body, theta[0])
    np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(rotation @ boom.thrust_direction_body(theta),
                               steering.direction_rsw(body[0] + theta[0] + np.pi / 2, body[1] + theta[2]), atol=1e-14)


def _circular(radius_m, steps, step_s):
    """r, v [steps + 1, 3] of a circular equatorial orbit and its rate n."""
    n = math.sqrt(c.MU_EARTH_M3_S2 / radius_m**3)
    phase = n * step_s * np.arange(steps + 1)
    r = radius_m * np.stack([np.cos(phase), np.sin(phase), 0 * phase], -1)
    v = radius_m * n * np.stack([-np.sin(phase), np.cos(phase), 0 * phase], -1)
    return jnp.asarray(r), jnp.asarray(v), n


def _integrate(torque_body_nm, params, inertia, radius_m=42164.0e3, steps=1440, step_s=60.0):
    """The wheels stepped with a constant body torque over a circular orbit, the body on the orbit frame."""
    r, v, n = _circular(radius_m, steps, step_s)
    zero2, theta1 = jnp.zeros(2), jnp.asarray(-0.5)
    state = wheels.initial(r[0], v[0], zero2, theta1, inertia)

    def one(state, k):
        state, frame = wheels.start(state, (r[k], v[k], zero2, theta1), inertia, params, jnp.asarray(True))
        held = state.h_body_nms
        return wheels.add(state, frame, r[k], torque_body_nm, jnp.zeros(3), 0.0, inertia, c.MU_EARTH_M3_S2, step_s,
                          jnp.asarray(True)), held

    final, history = jax.lax.scan(one, state, jnp.arange(steps + 1))  # h at the start of steps 0 .. steps
    return final, np.asarray(history)[1:], n, steps * step_s


def test_a_body_fixed_torque_on_a_circular_orbit_is_the_closed_form():
    """Closed form (Euler's law in inertial axes): a torque fixed in the orbit frame, (tau_R, tau_S, tau_W), on a
    body that turns with it at n leaves in the wheels, in the frame's axes at time t, the integral of
    tau_R R(s) + tau_S S(s) + tau_W W over [0, t]: tau_W t along W (secular) and (tau_R sin nt + tau_S (1 - cos nt),
    -tau_R (1 - cos nt) + tau_S sin nt) / n in the plane (bounded, amplitude 2 |tau| / n).  The wheels start empty
    with the body's orbit-rate momentum I n W in H (an anisotropic inertia: the I omega term must cancel).  The
    step's torque held in the axes of its start: the in-plane error is first order in n dt (0.44 % here)."""
    torque = jnp.asarray([0.01, -0.02, 0.003])
    inertia = jnp.asarray([2000.0, 3000.0, 4000.0])
    params = PARAMS._replace(capacity_nms=jnp.asarray(1e9))
    final, history, n, t = _integrate(torque, params, inertia)
    times = 60.0 * np.arange(1, history.shape[0] + 1)
    nt = n * times
    tr, ts, tw = np.asarray(torque)
    expected = np.stack([(tr * np.sin(nt) + ts * (1 - np.cos(nt))) / n,
                         (-tr * (1 - np.cos(nt)) + ts * np.sin(nt)) / n, tw * times], -1)
    amplitude = 2 * np.hypot(tr, ts) / n
    assert np.abs(history[:, :2] - expected[:, :2]).max() <= 0.01 * amplitude
    np.testing.assert_allclose(history[:, 2], expected[:, 2], rtol=1e-12)
    assert float(final.rcs_dumps) == 0.0
    np.testing.assert_allclose(np.max(np.abs(history), axis=0), final.max_abs_nms, rtol=1e-12, atol=1e-12)


def test_thrusters_unload_at_the_threshold_and_conserve_the_momentum():
    """Conservation of angular momentum: a constant torque along the orbit normal puts tau t into body and wheels;
    the attitude thrusters take it out whenever a wheel passes 80 % of 50 N m s, so what they emptied plus what
    the wheels hold at the end is tau t (to rounding), each unloading was between 40 N m s and 40 N m s plus a
    step's impulse, and no wheel ever held more than that."""
    tau, step_s, steps = 0.05, 60.0, 1440
    final, history, n, t = _integrate(jnp.asarray([0.0, 0.0, tau]), PARAMS, jnp.asarray([2000.0] * 3), steps=steps,
                                      step_s=step_s)
    dumps = int(final.rcs_dumps)
    assert dumps >= math.floor(tau * t / (40.0 + tau * step_s))
    # the last scan step added one more step's impulse after its start: tau (t + dt) in all
    held = np.linalg.norm(np.asarray(final.h_total_eci_nms) - 2000.0 * n * np.array([0.0, 0.0, 1.0]))
    assert float(final.rcs_dumped_nms) + held == pytest.approx(tau * (t + step_s), rel=1e-9)
    assert 40.0 * dumps < float(final.rcs_dumped_nms) <= (40.0 + tau * step_s) * dumps + 1e-9
    assert float(np.max(final.max_abs_nms)) <= 40.0 + tau * step_s + 1e-9


def test_the_dumping_tilt_makes_the_law_torque_within_its_limit():
    """Closed form of the law (module docstring): with the wrist on the thrust line (r = rho u) the tilt's torque
    r x F s is -(1 - exp(-k T)) h_perp / T, the momentum across the line taken toward zero over the firing time
    T; where that asks more than sin(delta_max), the tilt is scaled back to it; no tilt (exactly s = 0, cos = 1)
    at a limit of 0, without firing, or with the wrist on the centre of mass."""
    u = jnp.asarray([0.6, 0.8, 0.0])
    lever = -0.5 * u
    h = jnp.asarray([3.0, -1.0, 2.0])
    force, firing_s = 0.5, 120.0
    params = PARAMS._replace(dump_angle_max_rad=jnp.radians(60.0))
    tilt, cos = wheels.dump_tilt(h, u, lever, force, firing_s, params)
    h_perp = h - jnp.dot(h, u) * u
    wanted = -(1 - math.exp(-0.01 * firing_s)) * h_perp / firing_s
    np.testing.assert_allclose(jnp.cross(lever, force * tilt), wanted, atol=1e-15)
    assert float(jnp.dot(tilt, u)) == pytest.approx(0.0, abs=1e-15)
    assert float(cos) == pytest.approx(math.sqrt(1 - float(jnp.dot(tilt, tilt))), rel=1e-15)
    small = PARAMS._replace(dump_angle_max_rad=jnp.radians(2.0))
    tilt2, _ = wheels.dump_tilt(h, u, lever, force, firing_s, small)
    assert float(jnp.linalg.norm(tilt2)) == pytest.approx(math.sin(math.radians(2.0)), rel=1e-12)
    np.testing.assert_allclose(tilt2 / jnp.linalg.norm(tilt2), tilt / jnp.linalg.norm(tilt), atol=1e-14)
    for args in ((h, u, lever, force, firing_s, PARAMS), (h, u, lever, force, 0.0, params),
                 (h, u, 0.0 * lever, force, firing_s, params)):
        none, one = wheels.dump_tilt(*args)
        assert np.all(np.asarray(none) == 0.0) and float(one) == 1.0


@pytest.mark.parametrize("key, value, message", [
    ("attitude.wheel_capacity_nms", -50.0, "attitude.wheel_capacity_nms: must be > 0"),
    ("attitude.dump_angle_max_deg", 95.0, "attitude.dump_angle_max_deg: must be >= 0 and < 90"),
    ("attitude.rcs_dump_fraction", 0.0, "attitude.rcs_dump_fraction: must be > 0"),
    ("attitude.dump_gain_per_s", float("inf"), "attitude.dump_gain_per_s: must be a finite number"),
])
def test_bad_wheel_keys_name_the_key(key, value, message):
    with pytest.raises(ValueError, match=message):
        transfer.load("ma2023-boom", {key: value})


def test_the_quadrilateral_has_no_line_to_tilt():
    with pytest.raises(ValueError, match="attitude.dump_angle_max_deg: only the boom layout"):
        transfer.load("ma2023-quadrilateral", {"attitude.dump_angle_max_deg": 10.0})
