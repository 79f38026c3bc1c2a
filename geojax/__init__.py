"""geojax: closed-loop GEO station keeping in JAX (float64): thousands of rollouts at once, differentiable.

The public API (shapes and units in each docstring):

* ``load_scenario(name_or_path, overrides=None, controller=None) -> Scenario``: a shipped scenario by name
  (``available_scenarios()``) or a TOML file, validated; ``overrides`` maps dotted keys to values.
* ``simulate(scenario, seed=0, controller=None, keep_steps=None) -> Result``: one closed-loop rollout;
  ``Result.metrics`` (units in the names), ``Result.status`` (``STATUS_MEANINGS``), ``Result.records``;
  ``Result.save(path)`` writes the file ``geojax simulate --out`` writes, ``summary()`` the lines it prints,
  ``plot(folder)`` the figures of ``--plots`` (so do ``uncontrolled.propagate_scenario``, ``bound.bound`` and
  ``transfer.run``'s results, for ``propagate``, ``bound`` and ``transfer``).
* ``simulate_batch(scenario, params, seeds=...) -> Result``: a batch in one compiled call (leading axis on
  every leaf); ``prepare_params(scenario, n)`` gives n copies of a scenario's ``Params`` to edit.
* ``load_sweep`` / ``run_sweep``: Monte Carlo sweeps to HDF5, resumable (``ray=``: on a Ray cluster);
  ``open_results`` reads any results file as an ``xarray.Dataset`` (named dimensions, coordinates, units),
  ``read_results`` as plain arrays.
* ``load_tuning`` / ``tune_gains``: gains tuned by derivatives through rollouts.
* ``Controller`` (``init``, ``plan``, ``thrust``), its ``Spec`` (its ``Field`` declarations, checks, thrusters)
  and ``Sizing`` (its width), ``Thrust``, ``Params``: to write a controller of one's own (see the README); ``StateModel`` (``init``, ``step``, ``summary``,
  ``metrics``, optional ``cycle``, ``thrust``, ``estimate``, ``columns``) and ``Part`` (its keys, leaves and
  descriptions): a part of one's own the loop carries, ``simulate(..., states=(model,))`` (docs/python.md).
"""

import jax

from geojax.arithmetic import use_separate_roundings as _use_separate_roundings  # noqa: E402

from geojax.small_loops import use_small_loops as _use_small_loops  # noqa: E402

_use_separate_roundings()  # no fused multiply-adds: the same last bit at every width (geojax.arithmetic)
_use_small_loops()  # a small loop compiled as one function, not launched kernel by kernel (geojax.small_loops)
jax.config.update("jax_enable_x64", True)

from geojax.compilation import use_default as _use_compilation_cache  # noqa: E402

_use_compilation_cache()  # compiled programs kept between runs (geojax.compilation; off: GEOJAX_NO_CACHE=1)

__version__ = "0.2.0"

from geojax.control.base import Controller, Estimate, Sizing, Spec  # noqa: E402
from geojax.physics.dynamics import SpacecraftState, Thrust  # noqa: E402
from geojax.loop.metrics import STATUS_MEANINGS  # noqa: E402
from geojax.runner.rollout import Result, prepare_params, simulate, simulate_batch  # noqa: E402
from geojax.loop.simulate import CycleContext, StepEnvironment  # noqa: E402
from geojax.params import LOG, Field, Params  # noqa: E402
from geojax.scenario import Scenario  # noqa: E402
from geojax.states.base import CycleStart, Part, StateModel, StepContext, ThrustContext  # noqa: E402
from geojax.scenario import available as available_scenarios  # noqa: E402
from geojax.scenario import load as load_scenario  # noqa: E402
from geojax.results import open_results  # noqa: E402
from geojax.store import read_h5 as read_results  # noqa: E402
from geojax.sweep import load as load_sweep  # noqa: E402
from geojax.sweep import run_sweep  # noqa: E402

__all__ = [
    "Controller", "CycleContext", "CycleStart", "Estimate", "Field", "LOG", "Params", "Part", "Result",
    "STATUS_MEANINGS", "Scenario", "Sizing", "Spec", "SpacecraftState", "StateModel", "StepContext", "StepEnvironment", "Thrust",
    "ThrustContext", "available_scenarios", "load_scenario", "load_sweep",
    "load_tuning", "open_results", "prepare_params", "read_results", "run_sweep", "simulate", "simulate_batch", "tune_gains",
    "tuning_from_dict",
]

# The tuner (optax, SciPy's optimisers: a second of a command's start-up) is imported when first asked for.
_LAZY = {"tuning_from_dict": ("geojax.tune", "from_dict"), "load_tuning": ("geojax.tune", "load"),
         "tune_gains": ("geojax.tune", "tune")}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        module, attribute = _LAZY[name]
        return getattr(importlib.import_module(module), attribute)
    raise AttributeError(f"module 'geojax' has no attribute {name!r}")
