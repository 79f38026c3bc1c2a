"""Tuning by derivatives through rollouts (Katz 2025, eqs. (8)-(16)): ``geojax tune TUNE.toml``.

Minimise the yearly Delta-V of a scenario, with any controller, subject to the box |lambda - lambda_d| <= Delta_s,
|latitude| <= Delta_s, from many starts at once.  One module per job:

* ``spec``: the tuning file, its keys (a ``Field`` table) and ``load`` / ``from_dict``;
* ``space``: the tuned keys (any scenario key whose ``Field`` has a ``transform``, named by key or alias) and the
  unconstrained vector theta they map to;
* ``objective``: ``Problem``, the rollout of a theta, its loss and box constraints, and their derivatives;
* ``sqp`` (the default) and ``adam`` (optax): the optimisers;
* ``driver``: ``tune(spec)``, the run from every start, keeping the best point the exact law finds feasible;
* ``write``: the HDF5 file, the tuned scenario ``FILE-tuned.toml`` and the convergence figure.

Nothing here knows a controller by name: what a tuning may move, under which names and units, is what the
scenario's tables and its controller's ``fields`` declare (``geojax.control.base``).
"""

from geojax.tune.driver import (METHODS, SAMPLED_LAW_NOISE_MPS, ShortHorizonWarning, TuneResult,
                                default_margin, default_trust_radius, tune)
from geojax.tune.objective import Problem
from geojax.tune.spec import FIELDS, MIN_HORIZON_DAYS, TuneSpec, from_dict, horizon_warning, load
from geojax.tune.space import (LOG_BOUND, Tuned, fields_of, from_theta, reported, resolve, start_points, to_theta,
                               tunable, tuned)
from geojax.tune.sqp import damped_bfgs, population_hessian, qp_step
from geojax.tune.write import (TUNE_DIMS, figure, tuned_config, tuned_scenario_fault, tuned_scenario_path,
                               tuned_scenario_toml)

__all__ = [
    "FIELDS", "LOG_BOUND", "METHODS", "MIN_HORIZON_DAYS", "Problem", "SAMPLED_LAW_NOISE_MPS", "ShortHorizonWarning",
    "TUNE_DIMS", "TuneResult", "TuneSpec", "Tuned", "damped_bfgs", "default_margin", "default_trust_radius",
    "fields_of", "figure", "from_dict", "from_theta", "horizon_warning", "load", "population_hessian", "qp_step",
    "reported", "resolve", "start_points", "to_theta", "tunable", "tune", "tuned", "tuned_config",
    "tuned_scenario_fault", "tuned_scenario_path", "tuned_scenario_toml",
]
