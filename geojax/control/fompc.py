"""Fuel-optimal model predictive controller (Li 2022, Sec. 4.3, eqs. (40)-(42)).

The action of cycle k is the north-south correction u_k = |V_N|; the QFFC
turns it into the rest of the solution S_k (eq. (40)), so the in-plane
targets (longitude, eccentricity) are met every cycle and only the
inclination is allowed to lag, within Delta i_max.  Over a horizon of N cycles
the predictor model (``control.plan``) gives the burns and the inclination at
the end of each cycle, and eq. (42) scores the sequence:

    J = 1/2 sum_k [V_1k^2 + V_2k^2 + zeta_k |i_T - i_k|^2],
    zeta_k = P if |i_T - i_k| > Delta i_max else 0.

(``controller.dv_exponent`` = 1 scores V_1k + V_2k, the fuel, instead of the squares: an ablation of
the printed J, ``studies/ablation/fompc_annealing.py``.)

Choices where the paper is silent:

* u_k is searched as a fraction w_k of the QFFC's full correction of that
  cycle, u_k = w_k 2 V_s |di_k|, w_k in [0, ``fraction_max``]: the QFFC is
  w = 1 everywhere, and the annealing steps are scale-free.
* i is the MEE vector (h, k) (the one whose B rows carry the 1/2, see
  ``control.effects``); Delta i_max = 8e-5 is read in the same units.
* A cycle in which the QFFC finds no solution (S = 0) costs P Delta i_max^2 on
  top of its inclination term, so that a sequence is never preferred for
  skipping a cycle.
* Simulated annealing: ``chains`` independent Metropolis chains start at the
  QFFC sequence and move all N fractions at once by Gaussian steps whose size
  and temperature fall geometrically; temperatures are relative to the QFFC
  sequence's cost.  The best sequence met by any chain (the start included)
  is returned, so J(FOMPC) <= J(QFFC) on the model by construction.
* The horizon is padded to ``n_max`` cycles; cycles at or beyond N are masked
  out of J, so a sweep over N compiles once.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from geojax.control import burn_metrics
from geojax.control import burns as burns_mod
from geojax.control import qffc
from geojax.control.base import Controller, Sizing, Spec
from geojax.control.qffc import model_cycle

THRUSTERS = qffc.THRUSTERS
REDUNDANT_THRUSTERS = qffc.REDUNDANT_THRUSTERS
FIELDS = qffc.FIELDS


class MpcParams(NamedTuple):
    """FOMPC parameters a sweep can vary (array leaves; ``params.controller`` holds them by the same names).

    The defaults are the ``[controller]`` keys' (``qffc.FIELDS``), the one place they are declared."""

    # numpy defaults: a jnp array built at import would start JAX's backend before ``geojax.parallel`` can
    # ask for one device per core
    horizon: jnp.ndarray = np.asarray(FIELDS["horizon"].default)  # N, cycles (<= Annealing.n_max)
    di_max: jnp.ndarray = np.asarray(FIELDS["di_max"].default)  # Delta i_max, MEE (h, k)
    penalty: jnp.ndarray = np.asarray(FIELDS["penalty"].default)  # P, (m/s)^2 per unit (h, k)^2
    dv_exponent: jnp.ndarray = np.asarray(FIELDS["dv_exponent"].default)  # J sums V^dv_exponent per burn


class Annealing(NamedTuple):
    """Shape and schedule of the simulated annealing (static: hashable Python numbers); ``chains`` and
    ``iterations`` default to the ``[controller]`` keys' (``qffc.FIELDS``)."""

    n_max: int = FIELDS["horizon"].upper - 1  # horizon padding: the largest N a scenario may ask for
    chains: int = FIELDS["chains"].default
    iterations: int = FIELDS["iterations"].default
    step_start: float = 0.3  # 1-sigma move of each fraction w_k
    step_end: float = 0.01
    temperature_start: float = 0.05  # relative to the QFFC sequence's cost
    temperature_end: float = 1e-4
    fraction_max: float = 2.0


class Plan(NamedTuple):
    burns: object  # qffc.BurnPair of the current cycle
    fractions: jnp.ndarray  # [n_max] the best sequence w; w_1 is flown
    cost: jnp.ndarray  # J of the returned sequence
    cost_qffc: jnp.ndarray  # J of the QFFC sequence (w = 1)


def horizon_cost(fractions, x0, ref_windows, target, l_start_rad, limits, cycle_s, vdt_estimate, mpc: MpcParams):
    """J of eq. (42) for fractions [n_max] from the mean state x0 [6]; ref_windows [n_max + 2, 7]."""
    n_max = fractions.shape[0]

    def one(x, k):
        window = jax.lax.dynamic_slice_in_dim(ref_windows, k, 3)
        _, burns, after = model_cycle(x, window, target, l_start_rad, limits, cycle_s, vdt_estimate, fractions[k],
                                        anchor=k.astype(float))
        di = jnp.hypot(target[4] - after[4], target[5] - after[5])
        zeta = jnp.where(di > mpc.di_max, mpc.penalty, 0.0)
        cost = (burn_power(burns.v_mps[0], mpc.dv_exponent) + burn_power(burns.v_mps[1], mpc.dv_exponent)
                + zeta * di**2 + jnp.where(burns.feasible, 0.0, mpc.penalty * mpc.di_max**2))
        return after, 0.5 * jnp.where(k < mpc.horizon, cost, 0.0)

    _, costs = jax.lax.scan(one, x0, jnp.arange(n_max))
    return jnp.sum(costs)


def _power(v, exponent):
    """v ** exponent, the square and the identity by multiplication (exactly the same numbers)."""
    return jnp.where(exponent == 2.0, v * v, jnp.where(exponent == 1.0, v, v**exponent))


@jax.custom_jvp
@jax.custom_batching.custom_vmap
def burn_power(v, exponent):
    """A burn's term in J, V ** ``dv_exponent`` (``_power``), with the general power skipped for a whole
    batch whose exponents are all 2 (eq. (42) as printed, the default): the power is about 6 % of the
    annealing where the square is one multiplication.  ``exponent`` is a per-sample parameter, so a
    per-sample ``cond`` would turn into a select that computes both; the test runs once per batch instead,
    at the vmap that batches the exponent (a vmap over chains, which shares it, passes the gate outward)."""
    return jax.lax.cond(exponent == 2.0, lambda v, e: v * v, _power, v, exponent)


@burn_power.def_vmap
def _burn_power_batched(axis_size, in_batched, v, exponent):
    v_batched, exponent_batched = in_batched
    if not exponent_batched:  # one exponent for this batch: the same gate, for an enclosing vmap
        return burn_power(v, exponent), True
    v = v if v_batched else jnp.broadcast_to(v, (axis_size, *v.shape))
    exponent = exponent.reshape((axis_size,) + (1,) * (v.ndim - 1))
    return jax.lax.cond(jnp.all(exponent == 2.0), lambda v, e: v * v, _power, v, exponent), True


@burn_power.defjvp
def _burn_power_tangent(primals, tangents):
    return burn_power(*primals), jax.jvp(jnp.power, primals, tangents)[1]  # the power's, in v and the exponent


def plan(key, x0, ref_windows, target, l_start_rad, limits, cycle_s, vdt_estimate, mpc: MpcParams,
         annealing: Annealing = Annealing(), warm_start=None) -> Plan:
    """Solve eq. (41) by simulated annealing from the QFFC sequence; the burns of the first cycle.

    ``warm_start`` [n_max] (the previous cycle's best sequence, shifted by one
    cycle) starts every chain but the first, which starts at the QFFC's w = 1.
    """
    limits = qffc.arm_trig(limits)  # once per plan, not per candidate cycle
    cost = lambda w: horizon_cost(w, x0, ref_windows, target, l_start_rad, limits, cycle_s, vdt_estimate, mpc)  # noqa: E731
    n, chains, iters = annealing.n_max, annealing.chains, annealing.iterations
    w0 = jnp.ones(n)
    j0 = cost(w0)
    scale = jnp.maximum(j0, 1e-12)
    decay = lambda start, end, i: start * (end / start) ** (i / max(iters - 1, 1))  # noqa: E731

    def step(carry, i):
        w, j, best_w, best_j = carry
        k_move, k_accept = jax.random.split(jax.random.fold_in(key, i))
        move = decay(annealing.step_start, annealing.step_end, i) * jax.random.normal(k_move, (chains, n))
        proposal = jnp.clip(w + move, 0.0, annealing.fraction_max)
        j_new = jax.vmap(cost)(proposal)
        temperature = scale * decay(annealing.temperature_start, annealing.temperature_end, i)
        u = jax.random.uniform(k_accept, (chains,))
        accept = (j_new <= j) | (u < jnp.exp(-(j_new - j) / temperature))
        w = jnp.where(accept[:, None], proposal, w)
        j = jnp.where(accept, j_new, j)
        better = j_new < best_j
        return (w, j, jnp.where(better[:, None], proposal, best_w), jnp.where(better, j_new, best_j)), None

    if warm_start is None:
        w_start, j_start = jnp.tile(w0, (chains, 1)), jnp.full(chains, j0)
    else:
        w_start = jnp.concatenate([w0[None], jnp.tile(warm_start, (chains - 1, 1))])
        j_start = jnp.concatenate([j0[None], jnp.full(chains - 1, cost(warm_start))])
    start = (w_start, j_start, w_start, j_start)
    (_, _, best_w, best_j), _ = jax.lax.scan(step, start, jnp.arange(iters))
    w_star = best_w[jnp.argmin(best_j)]
    _, burns, _ = model_cycle(x0, ref_windows[:3], target, l_start_rad, limits, cycle_s, vdt_estimate, w_star[0])
    return Plan(burns, w_star, jnp.min(best_j), j0)


def shifted(fractions, horizon):
    """A plan's sequence one cycle later (the MPC warm start): drop w_1 and repeat w_N, the last planned
    cycle.  Padded cycles at or beyond N (masked out of J, so never optimised) are not used."""
    n_max = fractions.shape[0]
    return fractions[jnp.minimum(jnp.arange(n_max) + 1, jnp.clip(horizon, 1, n_max) - 1)]


SPEC = Spec(FIELDS, None, THRUSTERS, REDUNDANT_THRUSTERS, needs=qffc.needs)  # around the passes as the QFFC's


def make(tables: list[dict]) -> Controller:
    """The FOMPC for a batch of ``[controller]`` tables: its horizon padded to their largest N (so a sweep over
    N compiles once; a single run plans over exactly its N: padded cycles are masked out of J but still
    evaluated), the annealing's size shared."""
    for key in ("chains", "iterations"):
        if len({t[key] for t in tables}) > 1:
            raise ValueError(f"controller.{key}: sets the size of the compiled annealing; one value per sweep, "
                             f"got {sorted({t[key] for t in tables})}")
    annealing = Annealing(n_max=max(t["horizon"] for t in tables), chains=tables[0]["chains"],
                          iterations=tables[0]["iterations"])
    return controller(annealing, qffc.around_passes_of(tables))


@functools.lru_cache(maxsize=None)
def controller(annealing: Annealing = Annealing(), around_passes: bool = False) -> Controller:
    """The FOMPC with a static annealing schedule; its state is the last plan's sequence, shifted (warm start).
    ``around_passes``: the flown cycle's burns moved off the passes as the QFFC's (``qffc.around_passes_plan``), at
    the annealing's north-south fraction; the horizon's later cycles are planned at eq. (31)'s nodes."""

    def init(params, context):
        return jnp.ones(annealing.n_max)

    def plan_cycle(params, warm_start, estimate, context, key):
        c = params.controller
        inputs = qffc.model_inputs(params, estimate, context)
        prediction, _, _ = model_cycle(*inputs)
        mpc = MpcParams(c["horizon"], c["di_max"], c["penalty"], c["dv_exponent"])
        planned = plan(jax.random.fold_in(key, 1), *inputs, mpc, annealing, warm_start)
        burns = planned.burns
        if around_passes:
            prediction, burns = qffc.around_passes_plan(params, estimate, context, inputs, burns,
                                                        planned.fractions[0])
        flown = burns_mod.fly(params, burns, prediction, planned.fractions[0], estimate, context, key)
        return flown, shifted(planned.fractions, c["horizon"])

    # Plans N cycles ahead: the reference at the cycle's start boundary and the n_max + 1 after it.
    # Widths and memory (``geojax.lanes``): the annealing is a wide vmap of its own (8 chains per sample), so 32 lanes
    # per CPU core reach most of its throughput (4 days, one pinned core: 2.8 simulated years/s at 8 lanes, 3.8 at 32,
    # 4.1 at 64) and a small sweep pads less; XLA's memory_analysis at 32 lanes, 10 and 40 cycles (li2022's
    # annealing): 16.7 and 22.7 kB per lane.
    return Controller(init, plan_cycle, burns_mod.thrust, SPEC, reference_cycles=annealing.n_max + 2,
                      record=burns_mod.record, metrics=burn_metrics.metrics, sizing=Sizing(lanes_cpu=32, working_bytes=16_000))
