"""Monte Carlo sweeps: a grid over scenario parameters x repetitions x controllers (docs/design.md "Contracts", "Scale").

A sweep file names a base scenario, fixed overrides, a grid of values for
any scenario keys given by dotted paths (``thrusters.beta_max_deg``,
``controller.horizon``, ``errors.h_rv``, ``station.lon_deg``,
``spacecraft.srp_area_m2``, ``orbit.L_rad``, ...), the controllers, the
repetitions and optional Monte Carlo dispersions of the initial state:

    name = "fig9"
    scenario = "li2022-qffc"
    controllers = ["qffc", "fompc"]
    repetitions = 20
    seed = 0
    cycles = false             # true: also keep per-cycle records (/cycles/<name> [controller, grid..., reps, cycle])
    lanes = 1024               # optional: samples per device per compiled call (default: the platform's, geojax.lanes)
    [set]                      # fixed overrides, any scenario key
    "thrusters.alpha_max_deg" = 90.0
    [grid]                     # one axis per key, in this order; none: the repetitions alone
    "thrusters.beta_max_deg" = [45.0, 50.0, 60.0, 70.0, 80.0, 90.0]
    [dispersion]               # optional: 1-sigma Gaussian errors of each sample's initial state
    mee_1sigma = [0.1, 1e-6, 1e-6, 1e-6, 1e-6, 1e-5]   # p (km), f, g, h, k, L (rad)
    offset_ecef_1sigma_km = [1.0, 1.0, 1.0]             # position offset along ECEF x, y, z

A grid axis ``"epoch.utc" = ["2027-01-01T12:00:00", ...]`` (dates, not numbers) flies the same slot from
each date: the base scenario moved as ``scenario.started_at`` moves it (``geojax.sweep.epochs`` says how, and
why the points of one epoch share their environment in every compiled call).

Every grid point is a scenario loaded with its values, so every range and
check of ``geojax.scenario`` applies and every key that becomes an array leaf
of ``params.Params`` (or changes the initial state or the force model) can be
swept; keys that set the compiled loop's shape (step, duration, dynamics,
epoch, the FOMPC's annealing size, a thrust law) cannot, and say so.  Each
controller compiles once (the FOMPC's horizon padded to the largest N of the
sweep); a sweep that varies the initial state or the forces runs each sample's
own predictor reference inside the batch.  The batch is
vmapped and spread over as many local devices as it fills (a device left only
padding would compile its copy for nothing), each running one compiled call of
the platform's width (``geojax.lanes``: the controller's measured width on a
CPU, the widest batch that fits an accelerator's memory; ``lanes = N`` in the
file or ``--lanes N`` fixes it), so memory does not grow with the sweep and a
sample's numbers do not depend on the width.  Sample
``j`` of a controller (grid point ``j // reps``, repetition ``j % reps``) draws
its errors and annealing from ``fold_in(key(seed), j)`` and its dispersion from
``fold_in(fold_in(key(seed), j), DISPERSION_STREAM)``: the same draws for both
controllers (a paired comparison) and independent of the chunk size, the device
count and the resume point.

Each finished chunk is saved at once to ``OUT.parts/`` (written to a temporary
name and renamed, so a kill leaves either the whole chunk or nothing); when
every chunk is in, the HDF5 file is written atomically and the parts removed.
``resume=True`` picks up the saved chunks (with the cut they were made with).
The file's ``wall_s`` and ``compile_s`` count the last run only; ``compile_s`` is the time spent waiting for
the controllers' set-up (their shared arrays and the predictor's reference run) and compilation, which run
at once, each controller in a thread of its own (a Ray cluster's: the longest of its workers').
"""

from geojax.sweep.spec import DISPERSION_FIELDS, DISPERSION_STREAM, MAX_SAMPLES, Sweep, load, prepare_check, _scenario  # noqa: F401
from geojax.sweep.batch import ChunkRunner, default_chunk, lane_plan  # noqa: F401
from geojax.sweep.run import ray_nodes, run_sweep, saved_samples  # noqa: F401
