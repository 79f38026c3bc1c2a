"""The controller protocol (docs/design.md: controllers and parts): data plus pure functions, in the optax manner.

A ``Controller`` is three things kept apart.  Its **protocol**, the pure functions the one closed loop
(``geojax.loop.simulate``) calls: ``init(params, context) -> state`` once; ``plan(params, state, estimate,
context, key) -> (plan, state)`` once per cycle, from the on-board ``Estimate`` (never the truth); ``thrust(params,
plan, t, spacecraft, environment) -> Thrust`` once per integration step; optionally ``record(plan) -> {name:
array}`` (per-cycle records: ``"solved"`` counts cycles without a solution) and ``metrics`` (what it says of a
run from its records, ``control.burn_metrics`` for the planners), ``reference_cycles`` (> 0: the loop provides the uncontrolled reference that many boundaries ahead,
Li 2022 eqs. (24)-(27)) and ``surrogate`` (a smooth stand-in for derivatives, ``geojax.tune``; its sharpness the
leaf ``params.controller[SURROGATE_TEMPERATURE]``).  Its **spec** (``Spec``), what it asks of a scenario, read at
load: its ``[controller]`` keys (a field with a ``transform`` is tunable), its checks, the thrusters it flies and
the keys it leaves unread (each honoured or refused), the bound's geometry.  Its **sizing** (``Sizing``), how
the orchestration batches and compiles it; the bytes of its per-cycle records come from ``jax.eval_shape``.

A new controller is one module under ``control/`` defining ``SPEC`` and ``make(tables) -> Controller`` and one
line in ``control.REGISTRY``; or, in a user's script, a ``Controller`` passed to ``geojax.simulate`` / ``sweep``
/ ``tune`` (or named ``"package.module:NAME"``).  No controller name is compared inside the traced loop.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, Mapping, NamedTuple

import jax.numpy as jnp

from geojax.physics.dynamics import Thrust, no_thrust


# The keys only the robotic arms read (Li 2022 eq. (1); ``physics.propulsion.arm_limits``; the fuel bound's
# "arms" geometry), and those only a planned burn reads (``control.burns``: its shortest duration and the
# attitude error of its direction, Li 2022 eq. (47), given absolute or as multiples; the absolute key first, so
# that a refusal names the key the file gave).
ARM_LIMIT_KEYS = ("thrusters.beta_max_deg", "thrusters.beta_min_deg", "thrusters.alpha_max_deg",
                  "thrusters.alpha_min_deg")
BURN_KEYS = ("thrusters.min_burn_s", "errors.sigma3_dv_pct", "errors.sigma3_att_deg", "errors.h_att", "errors.att_axes",
             "errors.att_shared", "errors.att_known")

# The ``params.controller`` leaf holding a surrogate's temperature (``geojax.tune`` anneals it).
SURROGATE_TEMPERATURE = "temperature"


class Estimate(NamedTuple):
    """What the controller knows at the start of a cycle (from the orbit-determination fix)."""

    fix_mee: jnp.ndarray  # [6] osculating MEE (p m, f, g, h, k, L rad) of the fix, L continuous with the truth
    mean: jnp.ndarray  # [6] mean (lon rad, drift rad/s, e_x, e_y, i_x, i_y); zeros without a reference
    mass_kg: jnp.ndarray  # [] on-board mass (the propellant gauge is taken as exact)
    t_s: jnp.ndarray  # [] cycle start, s since the start of the run
    # {quantity: what a further state of the loop tells the controller} (``StateModel.estimate``, ``geojax.states``):
    # ``states[states.base.WHEEL_MOMENTUM]`` the measured wheel momentum [3], N m s, body axes, where the loop
    # carries the wheels (the quantities a part tells: ``states.base.QUANTITIES``)
    states: dict = {}


@dataclasses.dataclass(frozen=True)
class Spec:
    """What a controller asks of a scenario, read at load before anything is traced: its keys, its checks, the
    thrusters it flies, what it leaves unread, and what the tools around the loop take from it."""

    fields: Mapping[str, Any] = dataclasses.field(default_factory=dict)  # the ``[controller]`` keys (``params.Field``)
    validate: Callable | None = None  # ``validate(config)``: checks across tables, ``ValueError`` naming the key
    # (count, why): the thrusters it flies, which ``thrusters.count`` must equal (None: not checked).
    thrusters: tuple[int, str] | None = None
    redundant_thrusters: int | None = None  # a count it also takes (e.g. 4: two per arm, the planner allocating)
    redundant_why: str = "two per arm, the planner flying one of each"
    unread: tuple[str, ...] = ()  # keys of other tables its rollout never reads: refused at any value but the default
    tuned_fields: tuple[str, ...] = ()  # what a tuning moves when its file names no ``parameters``
    # The thruster geometry of the fuel bound when ``thrusters.layout`` is unset (``geojax.bound.directions``).
    bound_geometry: str = "arms"
    # Whether a single run keeps its per-step records; None: a feedback law (no reference) keeps them.
    keeps_steps: bool | None = None
    # ``needs(config) -> {quantity: why}``: what it plans with that a part must tell (``states.base.QUANTITIES``,
    # read from ``Estimate.states``), checked at load against the parts the scenario turns on; None: nothing
    needs: Callable | None = None


@dataclasses.dataclass(frozen=True)
class Sizing:
    """How the orchestration runs a controller (``geojax.lanes``, ``geojax.compilation``): never read by the loop.

    The per-cycle records a lane stacks are not declared: ``geojax.lanes`` takes them from ``jax.eval_shape``
    of the loop.  What cannot be known without compiling is stated, each measured in the controller's module."""

    lanes_cpu: int = 128  # samples per CPU device per call, measured on one pinned core
    # The working set per lane beside the stacked records, bytes: XLA's ``memory_analysis`` of the compiled batch
    # on the CPU (temporaries, arguments).  The default is twice the QFFC's, for a controller that does not say.
    working_bytes: int = 32_000
    # LLVM's optimization level for a single sample's closed loop (``compilation.ONE_SAMPLE_OPTIONS``): 0 for a
    # feedback law or a planner of a few small kernels, 1 for one that solves a program every cycle (its
    # arithmetic runs 2-3x slower unoptimized; docs/speed.md).  A batch keeps XLA's defaults.
    one_sample_opt_level: int = 0


@dataclasses.dataclass(frozen=True, eq=False)
class Controller:
    """A controller: the protocol's pure functions, its ``Spec`` and its ``Sizing`` (static under ``jit``).

    Compared and hashed by identity, so a compiled rollout is reused for as long as the same ``Controller``
    object is passed (the factories of ``control.REGISTRY`` return the same object for the same settings).
    """

    init: Callable
    plan: Callable
    thrust: Callable
    spec: Spec = Spec()
    reference_cycles: int = 0
    record: Callable | None = None
    surrogate: Any = None  # a Controller, or None: the controller is its own surrogate
    sizing: Sizing = Sizing()
    # The plan of a whole cluster at once, or None: each satellite plans alone.  ``plan_cluster(params,
    # controller_state, estimate, context, key, min_separation_m) -> (plan, controller_state)``, every argument with
    # a leading satellite axis but the separation to keep (m, []): a cluster's loop (``loop.cluster``) calls it in
    # place of each satellite's ``plan`` where ``[collocation] coordinated`` asks (``control.mpc_cluster``).
    plan_cluster: Callable | None = None
    # Its own metrics of a run, or None: the thrusters' duty per axis.  ``metrics(params, cycles, run_s, own) ->
    # {name: scalar}`` over the loop's ``CycleRecord`` stacked over cycles (its ``record`` s in ``cycles.controller``),
    # ``own`` [n_cycles] bool the cycles it flew itself (``control.recovery`` flies the others); the planners that
    # fly ``control.burns`` say their burns' (``control.burn_metrics.metrics``).
    metrics: Callable | None = None

    @property
    def fields(self) -> Mapping[str, Any]:
        """The ``[controller]`` keys (``spec.fields``), the one part of the spec the loop's set-up reads."""
        return self.spec.fields


def keeps_steps(controller: Controller) -> bool:
    """Whether a single run of ``controller`` keeps its per-step records (``Spec.keeps_steps``)."""
    keeps = controller.spec.keeps_steps
    return controller.reference_cycles == 0 if keeps is None else keeps


def stateless_init(params, context):
    """``init`` of a controller with no memory between cycles."""
    return jnp.zeros(())


def no_plan(params, controller_state, estimate, context, key):
    """``plan`` of a feedback law: nothing is planned; the thrust is computed per step."""
    return jnp.zeros(()), controller_state


def coast(params, plan, t, state, environment) -> Thrust:
    """``thrust`` of the null controller."""
    return no_thrust()
