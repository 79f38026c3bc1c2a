"""The controller protocol (docs/design.md: controllers and parts): data plus pure functions, in the optax manner.

A controller is a ``Controller(init, plan, thrust)`` of pure functions that the
one closed loop (``geojax.loop.simulate``) calls:

* ``init(params, context) -> controller_state``: once, before the first cycle
  (``context`` is the first cycle's ``CycleContext``);
* ``plan(params, controller_state, estimate, context, key) -> (plan, controller_state)``:
  once per control cycle, from the on-board ``Estimate`` (never the true state);
* ``thrust(params, plan, t, state, environment) -> Thrust``: once per
  integration step; ``t`` is the step's start (s since the start of the run),
  ``state`` the true ``SpacecraftState`` and ``environment`` a ``StepEnvironment``
  (a feedback law reads its sensors here; a planner flies its plan).

``params`` is the sample's ``geojax.params.Params`` pytree: the controller's own
settings are ``params.controller`` (a dict of SI array leaves named by
``fields``), and everything else (thrusters, station, errors) is there too.

Optional parts: ``fields`` declares the keys of the scenario's ``[controller]``
table (TOML key, unit conversion, bounds, tuning transform: ``params.Field``);
``lanes_cpu``, ``lane_bytes`` and ``lane_bytes_per_cycle`` tell the orchestration how wide
to batch it (``geojax.lanes``: the width measured on one CPU core, and the memory model that sizes a
GPU's batch); ``keeps_steps`` whether a single run keeps per-step records; ``bound_geometry`` the
thruster geometry ``geojax bound`` assumes for it; ``reference_cycles`` > 0 asks the loop for the shared uncontrolled reference and
the mean-element estimate it enables (Li 2022 eqs. (24)-(27)), that many cycle
boundaries from the cycle's start on; ``record(plan) -> {name: array}`` adds
per-cycle records (a ``"solved"`` bool counts cycles without a solution, the
burn records of ``control.burns`` feed the burn metrics); ``surrogate`` is a
smooth stand-in used for derivatives (``geojax.tune``): its sharpness, where it has one, is the leaf
``params.controller[SURROGATE_TEMPERATURE]``, which the tuner anneals (the exact law ignores it);
``plan_cluster(params, controller_state, estimate, context, key, min_separation_m) -> (plan,
controller_state)`` plans a cluster's satellites together, once per cycle (every argument with a leading
satellite axis but the separation to keep, m []): a cluster's loop (``loop.cluster``) calls it in place of
each satellite's ``plan`` when ``[collocation] coordinated`` asks (the coordinated MPC, ``control.mpc_cluster``).

What a tuning may move is declared here too: a field with a ``transform`` is tunable (named by its key,
``"controller.k_h_per_km2_s"``, or its ``alias``, ``"k_h"``), and its ``unit`` labels the figures.  The
tuner (``geojax.tune``) reads nothing else of a controller.

What a registered controller's module declares beside ``FIELDS`` and ``make`` (read at load, by
``geojax.scenario``, so that every key of a scenario is honoured or refused): ``THRUSTERS``, the thrusters it
flies and why (``(2, "Li 2022's two robotic arms, one burn each per cycle")``), which ``thrusters.count``
must then equal; and ``UNREAD``, the keys of the other tables its rollout never reads (``ARM_LIMIT_KEYS``
for a law that does not fly the arms), each refused at any value but its default.  A module without them
(the null controller, a user's) is not checked.

No controller name is compared inside the traced loop: the loop only calls
these functions.  A new controller is one module under ``control/`` that
defines ``FIELDS`` and ``make(tables) -> Controller`` and one line in
``control.REGISTRY`` -- or, in a user's own script, a ``Controller`` passed to
``geojax.simulate`` / ``sweep`` / ``tune`` directly.
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
BURN_KEYS = ("thrusters.min_burn_s", "errors.sigma3_dv_pct", "errors.sigma3_att_deg", "errors.h_att", "errors.att_yaw", "errors.att_pitch",
             "errors.att_shared", "errors.att_known")

# The ``params.controller`` leaf holding a surrogate's temperature (``geojax.tune`` anneals it).
SURROGATE_TEMPERATURE = "temperature"


class Estimate(NamedTuple):
    """What the controller knows at the start of a cycle (from the orbit-determination fix)."""

    fix_mee: jnp.ndarray  # [6] osculating MEE (p m, f, g, h, k, L rad) of the fix, L continuous with the truth
    mean: jnp.ndarray  # [6] mean (lon rad, drift rad/s, e_x, e_y, i_x, i_y); zeros without a reference
    mass_kg: jnp.ndarray  # [] on-board mass (the propellant gauge is taken as exact)
    t_s: jnp.ndarray  # [] cycle start, s since the start of the run
    # {name: what a further state of the loop tells the controller} (``StateModel.estimate``, ``geojax.states``):
    # ``states["wheels"]`` the measured wheel momentum [3], N m s, body axes, where the loop carries the wheels
    states: dict = {}


@dataclasses.dataclass(frozen=True, eq=False)
class Controller:
    """A controller: pure functions and what the loop must know about them (static under ``jit``).

    Compared and hashed by identity, so a compiled rollout is reused for as long as the same
    ``Controller`` object is passed (the factories of ``control.REGISTRY`` return the same object for
    the same static settings).
    """

    init: Callable
    plan: Callable
    thrust: Callable
    fields: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    reference_cycles: int = 0
    record: Callable | None = None
    surrogate: Any = None  # a Controller, or None: the controller is its own surrogate
    # The ``fields`` a tuning moves when its file names no ``parameters`` (each with a ``transform``).
    tuned_fields: tuple[str, ...] = ()
    # How wide to batch it (``geojax.lanes``).  Samples per CPU device per compiled call, measured on one pinned
    # core; the step is also compiled for this many lanes on every platform (``physics.propagate.for_lanes``), so a
    # wider batch gives the same numbers bit for bit.
    lanes_cpu: int = 128
    # Working memory per lane, bytes: XLA's ``memory_analysis`` of the compiled batch on the CPU (temporaries,
    # arguments and outputs per lane), split into what a run needs whatever its length and what each cycle adds
    # (the stacked ``CycleRecord``s).  These defaults are twice the QFFC's (li2022, 64 lanes, 10 and 40 cycles:
    # 15.6 and 21.3 kB per lane), for a user's controller that does not say.
    lane_bytes: int = 32_000
    lane_bytes_per_cycle: int = 400
    # LLVM's optimization level for a single sample's closed loop (XLA's ``xla_backend_optimization_level``, beside
    # ``compilation.ONE_SAMPLE_OPTIONS``; a batch keeps XLA's defaults).  What ``geojax simulate`` waits for is that
    # program's compilation, and a feedback law's or a planner's cycle is a few small kernels whose run time the
    # loop's own overhead sets: unoptimized code (0) saves more compiling than it costs a year's run.  A controller
    # that solves a program every cycle spends its run time in arithmetic, which runs 2-3x slower unoptimized: it
    # says 1 (measured in ``docs/speed.md``).
    one_sample_opt_level: int = 0
    # Whether a single run keeps its per-step records (``geojax simulate``'s ``/steps/`` and the ground-track
    # figures): a feedback law has no plan to record per cycle, so its story is in the steps.  None: a controller
    # without the predictor's reference (``reference_cycles == 0``: a feedback law) keeps them.
    keeps_steps: bool | None = None
    # The thruster geometry of the fuel bound when the scenario's ``thrusters.layout`` is unset
    # (``geojax.bound.directions.GEOMETRIES``): Li's two robotic arms, or a gimbal that points anywhere.
    bound_geometry: str = "arms"
    # The plan of a whole cluster at once (the module's docstring), or None: each satellite plans alone.
    plan_cluster: Callable | None = None


def keeps_steps(controller: Controller) -> bool:
    """Whether a single run of ``controller`` keeps its per-step records (``Controller.keeps_steps``)."""
    return controller.reference_cycles == 0 if controller.keeps_steps is None else controller.keeps_steps


def stateless_init(params, context):
    """``init`` of a controller with no memory between cycles."""
    return jnp.zeros(())


def no_plan(params, controller_state, estimate, context, key):
    """``plan`` of a feedback law: nothing is planned; the thrust is computed per step."""
    return jnp.zeros(()), controller_state


def coast(params, plan, t, state, environment) -> Thrust:
    """``thrust`` of the null controller."""
    return no_thrust()
