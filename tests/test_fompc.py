"""FOMPC (Li 2022, eqs. (40)-(42)) on the predictor model: never worse than the QFFC, masking, seeds."""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax.physics import constants as c
from geojax import scenario
from geojax.control import none
from geojax.runner.setup import params_of, uncontrolled_boundaries
from geojax.physics.propagate import MEE
from geojax.control import fompc
from geojax.physics.propagate import environment_grid, steps_per_cycle
from geojax.physics.propulsion import PRESETS_DEG, arm_limits_deg

TARGET = jnp.array([np.radians(96.0), 0.0, 0.0, 1e-4, 0.0, 3e-5])
LIMITS = arm_limits_deg(*PRESETS_DEG["normal"])
ANNEALING = fompc.Annealing(chains=4, iterations=32)


@pytest.fixture(scope="module")
def windows():
    # The natural drift of the mean elements over 12 days of li2022, from the uncontrolled reference.
    sc = scenario.load("li2022")
    n = steps_per_cycle(sc.step_s)
    h = c.SIDEREAL_DAY_S / n
    env = environment_grid(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s, h, ANNEALING.n_max + 2, n)
    _, mean = jax.jit(lambda p, e: uncontrolled_boundaries(p, e, h, MEE))(params_of(sc, none.CONTROLLER), env)
    return mean, n * h


def start_states(n, seed=0):
    # Mean states around the station: in-plane errors of a few thousandths of a degree, inclination
    # anywhere within 1.5 Delta i_max of its target.
    rng = np.random.default_rng(seed)
    dx = rng.uniform(-1, 1, (n, 6)) * np.array([5e-5, 1e-9, 1e-5, 1e-5, 1.2e-4, 1.2e-4])
    return TARGET + jnp.asarray(dx)


def plan_batch(windows, x0, keys):
    ref_mean, cycle_s = windows
    return _plans(x0, keys, ref_mean, cycle_s)


@jax.jit
@functools.partial(jax.vmap, in_axes=(0, 0, None, None))
def _plans(x0, key, ref_mean, cycle_s):
    return fompc.plan(key, x0, ref_mean, TARGET, 0.3, LIMITS, cycle_s, 0.0, fompc.MpcParams(), ANNEALING)


def cost_of(windows, fractions, x0, mpc=fompc.MpcParams()):
    ref_mean, cycle_s = windows
    return _cost(fractions, x0, ref_mean, cycle_s, mpc)


@jax.jit
def _cost(fractions, x0, ref_mean, cycle_s, mpc):
    return fompc.horizon_cost(fractions, x0, ref_mean, TARGET, 0.3, LIMITS, cycle_s, 0.0, mpc)


@pytest.mark.slow
def test_fompc_cost_is_never_above_the_qffc(windows):
    x0 = start_states(16)
    keys = jax.random.split(jax.random.key(1), 16)
    plans = plan_batch(windows, x0, keys)
    assert bool(jnp.all(plans.cost <= plans.cost_qffc))
    # Re-evaluated independently of the annealing's bookkeeping: the returned sequence and w = 1.
    costs = jax.vmap(lambda w, x: cost_of(windows, w, x))(plans.fractions, x0)
    np.testing.assert_allclose(costs, plans.cost, rtol=1e-12)
    costs_qffc = jax.vmap(lambda x: cost_of(windows, jnp.ones(ANNEALING.n_max), x))(x0)
    np.testing.assert_allclose(costs_qffc, plans.cost_qffc, rtol=1e-12)
    # Letting the inclination lag within Delta i_max pays: the optimum is well below the QFFC's cost.
    assert float(jnp.median(plans.cost / plans.cost_qffc)) < 0.9
    # The first burn pair is the QFFC's solution for the fraction flown (eq. (40)).
    assert bool(jnp.all(plans.burns.feasible))


@pytest.mark.slow
def test_cycles_beyond_the_horizon_are_masked(windows):
    x0 = start_states(1, seed=2)[0]
    w = jnp.asarray(np.random.default_rng(3).uniform(0.2, 1.5, ANNEALING.n_max))
    mpc = fompc.MpcParams(horizon=jnp.asarray(3))
    changed_tail = w.at[3:].set(0.0)
    assert float(cost_of(windows, w, x0, mpc)) == float(cost_of(windows, changed_tail, x0, mpc))
    # Every N in one compiled function; J grows with N (each cycle adds a non-negative term).
    horizons = jnp.arange(1, ANNEALING.n_max + 1)
    costs = jax.jit(jax.vmap(lambda n: cost_of(windows, w, x0, fompc.MpcParams(horizon=n))))(horizons)
    assert bool(jnp.all(jnp.diff(costs) >= 0)) and float(costs[-1]) > float(costs[0])


def test_inclination_penalty_is_eq42(windows):
    # A sequence that makes no north-south correction leaves i outside Delta i_max: P |i_T - i_k|^2 per cycle.
    x0 = TARGET.at[4].add(1e-4)
    lazy = float(cost_of(windows, jnp.zeros(ANNEALING.n_max), x0))
    free = float(cost_of(windows, jnp.zeros(ANNEALING.n_max), x0, fompc.MpcParams(penalty=jnp.asarray(0.0))))
    assert lazy - free > 6 * 0.5 * 1e8 * (1e-4) ** 2 * 0.5  # six cycles, each at least ~1e-4 off


@pytest.mark.slow
def test_same_key_same_plan_other_key_other_search(windows):
    x0 = start_states(1, seed=4).repeat(16, 0)
    keys = jnp.concatenate([jnp.stack([jax.random.key(7)] * 8), jnp.stack([jax.random.key(8)] * 8)])
    plans = plan_batch(windows, x0, keys)
    np.testing.assert_array_equal(plans.fractions[0], plans.fractions[7])
    assert not np.array_equal(plans.fractions[0], plans.fractions[8])


def test_warm_start_repeats_the_last_planned_cycle_whatever_the_padding():
    """The shifted plan drops w_1 and repeats w_N; with the horizon padded (n_max > N) the padded, never
    optimised values must not leak in, so padding to 10 warm-starts like planning over exactly N."""
    w = jnp.array([0.5, 0.8, 1.2, 0.9, 7.0, 7.0, 7.0])  # N = 4, padded to 7 with junk
    np.testing.assert_array_equal(fompc.shifted(w, 4), [0.8, 1.2, 0.9, 0.9, 0.9, 0.9, 0.9])
    np.testing.assert_array_equal(fompc.shifted(w[:4], 4), [0.8, 1.2, 0.9, 0.9])
    np.testing.assert_array_equal(fompc.shifted(w, 1), jnp.full(7, 0.5))


@pytest.mark.slow
def test_dv_exponent_one_scores_the_fuel_of_each_cycle(windows):
    """With ``dv_exponent`` = 1 and no penalty, J is half the sum over the horizon of V_1k + V_2k, the burns
    the QFFC model plans cycle by cycle (``qffc.model_cycle``, the model J is built on): a second,
    independent sum over the same cycles."""
    from geojax.control import qffc
    ref_mean, cycle_s = windows
    x0 = start_states(1, seed=5)[0]
    w = jnp.asarray(np.random.default_rng(6).uniform(0.2, 1.5, ANNEALING.n_max))
    mpc = fompc.MpcParams(horizon=jnp.asarray(4), penalty=jnp.asarray(0.0), dv_exponent=jnp.asarray(1.0))
    x, fuel = x0, 0.0
    for k in range(4):
        _, burns, x = qffc.model_cycle(x, ref_mean[k:k + 3], TARGET, 0.3, LIMITS, cycle_s, 0.0, w[k])
        fuel += float(jnp.sum(burns.v_mps))
    np.testing.assert_allclose(float(cost_of(windows, w, x0, mpc)), 0.5 * fuel, rtol=1e-12)
    squares = float(cost_of(windows, w, x0, mpc._replace(dv_exponent=jnp.asarray(2.0))))
    assert squares < 0.5 * fuel  # every V < 1 m/s: the squares are smaller


def test_burn_power_is_the_power_whether_the_batch_gate_is_open_or_shut():
    """``burn_power`` skips the general power for a batch whose exponents are all 2; checked against numpy's
    power (a second method) unbatched, under one vmap and under nested vmaps (chains sharing a sample's
    exponent, as in the annealing), with all-2 batches (the gate shut) and mixed ones (open)."""
    v = jnp.array([[0.0, 0.3, 1.7], [2.5, 1e-3, 0.9]])  # [samples, chains]
    for exponents in ([2.0, 2.0], [2.0, 1.0], [1.5, 2.0], [1.0, 1.0]):
        e = jnp.array(exponents)
        want = np.power(np.asarray(v), np.asarray(e)[:, None])
        nested = jax.jit(jax.vmap(jax.vmap(fompc.burn_power, in_axes=(0, None))))(v, e)
        np.testing.assert_allclose(nested, want, rtol=1e-15, atol=0)
        flat = jax.vmap(fompc.burn_power)(v[:, 1], e)
        np.testing.assert_allclose(flat, want[:, 1], rtol=1e-15, atol=0)
    assert float(fompc.burn_power(jnp.asarray(3.0), jnp.asarray(2.0))) == 9.0
    # derivatives are the power's: e v^(e - 1) in v, v^e log v in the exponent
    dv, de = jax.vmap(jax.grad(fompc.burn_power, argnums=(0, 1)))(jnp.array([3.0, 3.0]), jnp.array([2.0, 1.5]))
    np.testing.assert_allclose(dv, [6.0, 1.5 * 3.0**0.5], rtol=1e-14)
    np.testing.assert_allclose(de, [9.0 * np.log(3.0), 3.0**1.5 * np.log(3.0)], rtol=1e-14)
