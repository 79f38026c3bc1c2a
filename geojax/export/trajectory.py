"""A single rollout's ephemeris (truth or estimate, with covariance) as a CCSDS OEM and its burns: ``save_oem``.

For operations and for a cross-check in another tool (Orekit, GMAT, STK).

**States.**  A run made with ``simulate(..., ephemeris=True)`` (``geojax simulate --oem`` makes it) kept the true
ECI state at every integration step start (``export.recorder``); the OEM holds every ``stride``-th of them
(``oem_step_s``: the largest whole number of integration steps within it, default 1) and the run's end, with
INTERPOLATION = LAGRANGE of degree ``INTERPOLATION_DEGREE``: through every other state of a 3-day run (1795 s
apart) it gives back the states between to 2.2 mm where its nodes span no burn's start or end, and to 7 m across
one (the thrust's jump; ``tests/test_ccsds.py``), as the file's comment says.  A run without it has only its per-cycle records: the true osculating ``boundary`` = (lon, a,
f, g, h, k) at each cycle start (``control.predictor.boundary_elements``: lon is the mean longitude l = L - 2 f sin
L + 2 g cos L less the Earth angle), which ``cycle_states`` inverts exactly (Newton on L, then p = a (1 - f**2 -
g**2)) with the Earth angle there; that OEM holds one state per sidereal day and the end, not nodes to interpolate
(no INTERPOLATION).

**Estimate and covariance** (``of="estimate"``).  With a navigation filter (``navigation.model = "ekf"``) the
filter's estimate at the same step starts (after the previous step's measurement updates), and in either OEM the
filter's covariance of its ECI position and velocity at each state's epoch (COVARIANCE blocks, turned into the
OEM's frame).  Without a filter the controller is told the Gaussian fix at each cycle start (``loop.simulate``:
the truth plus ``normal(fold_in(key, k), (2, 6))[0]`` scaled by Li 2022's 1-sigma): the estimate OEM holds
those fixes, one per cycle, each with its diagonal covariance; there is no estimate between them.

**Frame and time.**  geojax's ECI is the mean equator and equinox of the scenario epoch
(``physics.ephemeris``).  ``frame="EME2000"`` (the default, what Orekit, GMAT and STK read without
configuration) turns it to the mean equator and equinox of J2000.0 by the IAU 1976 precession of the epoch
(``ephemeris.precession_from_j2000``, the rotation geojax itself applies to DE421's ICRF positions);
``frame="MOD"`` writes it as it is, REF_FRAME = MOD with REF_FRAME_EPOCH = the scenario epoch (a reader that
takes MOD as mean *of date* would be off by the 50"/yr precession since the epoch).  Epochs are geojax's TT
(``time_system="TT"``) or UTC by the leap seconds of ``physics.time`` (default).

**Burns.**  A planner's records (``control.burns.record``) give each burn's firing start in its cycle, firing
time and unit velocity increment in RSW (= CCSDS RTN: radial, transverse, normal), attitude errors included;
a burn's Delta-V is the rocket equation over its firing time from the mass left by the burns before it, at
the thrust and Isp of the scenario.  A feedback law (the recovery law of ``controller.recovery`` included) thrusts
per step: a run with ``ephemeris=True`` recorded the thrust held over every step (``recorder.THRUST_COLUMNS``),
and each run of consecutive steps that fire with the same thrust vector in RSW is one burn (``step_burns``: the
recovery law's along-track arc of a cycle, or its out-of-plane arc about a node; a law that turns its thrust
every step has a burn per step), spanning those steps at the level flown (the duration is the span, the
Delta-V the rocket equation over it from the mass at its start); a run without a controller has an empty burn
list.  With the faults part (``states.faults``) the list holds every burn the plan fired, each as flown by its
thruster: ``status`` says whether it flew as planned (``flown``), not at all (``missed``: drawn lost or its thruster
out; duration and Delta-V 0), shorter (``cut``: an outage began within it) or at a lower thrust (``degraded``:
``faults.thrust_scale`` below 1), and ``planned_s`` the firing time commanded beside it; its direction is the one
flown (a stuck arm's frozen one, ``faults.stuck_arm``).  The burns as a CCSDS
message: ``export.maneuvers`` (the burns flown).
"""

from __future__ import annotations

import csv
import datetime as dt
import math
from pathlib import Path
from typing import NamedTuple

import jax
import numpy as np

from geojax.export.oem import Covariance, Metadata, write_oem
from geojax.physics.constants import G0_MPS2
from geojax.physics.elements import mee_to_cartesian
from geojax.physics.ephemeris import precession_from_j2000
from geojax.physics.frames import earth_rotation_angle_rad
from geojax.physics.propagate import DYNAMICS, steps_per_cycle
from geojax.physics.time import TT_MINUS_TAI_S, tai_minus_utc_s

FRAMES = ("EME2000", "MOD")
TIME_SYSTEMS = ("UTC", "TT")
OF = ("truth", "estimate")
INTERPOLATION_DEGREE = 8  # Lagrange through 9 states (the module's docstring: what it gives back)
ACROSS_BURNS = ("Interpolate within coast arcs and burns: across a burn's start or end (the burn list) the thrust's "
                "jump makes a Lagrange interpolation err by metres.")
J2000_TT = dt.datetime(2000, 1, 1, 12)  # J2000.0 as a TT calendar date
BURN_COLUMNS = ("cycle", "thruster", "start_utc", "start_tt_s", "duration_s", "dv_mps", "dv_r_mps", "dv_t_mps",
                "dv_n_mps")
FAULT_BURN_COLUMNS = ("status", "planned_duration_s")  # after BURN_COLUMNS where the faults part rode the loop


class Burns(NamedTuple):
    """A run's fired burns [m], in time order."""

    cycle: np.ndarray  # [m] int, control cycle from 0
    thruster: np.ndarray  # [m] int from 1 (Li 2022: 1 fires southwards, 2 northwards; with thrusters.count = 4,
    # 3 and 4 their arms' redundant ones)
    start_tt_s: np.ndarray  # [m] TT seconds since J2000.0 at which it starts firing
    duration_s: np.ndarray  # [m] firing time (a burn suspended in the Earth's shadow spans longer; a feedback
    # law's: the span of its steps, fired at their level)
    dv_rtn_mps: np.ndarray  # [m, 3] Delta-V along R, T, N (held fixed in RTN through the burn)
    mass_kg: np.ndarray  # [m] the propellant it used
    status: np.ndarray | None = None  # [m] str, one of states.base.BURN_STATUSES, where a part says (the faults)
    planned_s: np.ndarray | None = None  # [m] the firing time commanded, there


def burns_flown(burns: Burns) -> Burns:
    """The burns of ``burns`` that fired (a missed one left out)."""
    keep = burns.duration_s > 0
    return Burns(*(None if x is None else np.asarray(x)[keep] for x in burns))


class States(NamedTuple):
    """What an OEM holds: epochs, ECI states and the covariance where there is one."""

    t_tt_s: np.ndarray  # [n] TT seconds since J2000.0
    rv: np.ndarray  # [n, 6] ECI (r m, v m/s)
    covariance: np.ndarray | None  # [n, 6, 6] m^2, m^2/s, m^2/s^2 (NaN where none: the run's end)
    what: str  # the data comment: what the states are
    interpolable: bool  # step states (nodes to interpolate), not one per cycle


def save_oem(result, path: str | Path, *, oem_step_s: float | None = None, of: str = "truth",
             frame: str = "EME2000", time_system: str = "UTC", object_name: str | None = None,
             object_id: str | None = None, xml: bool | None = None, burns_csv: bool = True,
             covariance: bool = True) -> list[Path]:
    """Write a single rollout's states as a CCSDS OEM at ``path`` (XML where it ends in ``.xml``, or as ``xml``
    says; else KVN) and, for a planner, its burns beside it as ``STEM-burns.csv`` (``BURN_COLUMNS``; the
    columns are described in docs/results-files.md).

    ``oem_step_s``: the states' spacing in s, as the largest whole number of integration steps within it
    (default: every step; a run made without ``ephemeris=True`` has the cycle starts only, and a finer spacing is
    refused); ``of``: "truth" or "estimate" (the filter's, or the Gaussian fix's); ``covariance``: the filter's
    covariance blocks where there is one; ``frame``: EME2000 or MOD (of the scenario epoch); ``time_system``: UTC
    or TT; ``object_name`` / ``object_id``: default the scenario's name.  Returns the paths written.
    """
    from geojax import __version__
    from geojax.runner.report import scenario_of

    if frame not in FRAMES:
        raise ValueError(f"frame: must be one of {', '.join(FRAMES)}, got {frame!r}")
    if time_system not in TIME_SYSTEMS:
        raise ValueError(f"time_system: must be one of {', '.join(TIME_SYSTEMS)}, got {time_system!r}")
    if of not in OF:
        raise ValueError(f"oem_of: must be one of {', '.join(OF)}, got {of!r}")
    sc = scenario_of(result)
    states = oem_states(result, oem_step_s, of)
    rv = states.rv
    to_frame = np.eye(3)
    if frame == "EME2000":
        to_frame = np.asarray(precession_from_j2000(sc.epoch_tt_s))  # J2000 -> epoch; its transpose back, on rows
    six = np.kron(np.eye(2), to_frame)
    rv = rv @ six
    epochs = [calendar(t, time_system) for t in states.t_tt_s]
    epoch_text = calendar(sc.epoch_tt_s, time_system)
    path = Path(path)
    burns = run_burns(result)
    written_burns = path.with_name(f"{path.stem}-burns.csv") if burns is not None and burns_csv else None
    covariances = ()
    if covariance and states.covariance is not None:
        covariances = tuple(Covariance(epoch, six.T @ p @ six / 1e6) for epoch, p in zip(epochs, states.covariance)
                            if np.all(np.isfinite(p)))
    comments = (f"geojax {__version__}: scenario {sc.name}, controller {sc.controller}, "
                f"{'seed ' + str(result.seed) if result.seed is not None else 'a given key'}",)
    frame_note = (f"REF_FRAME EME2000: geojax's ECI (mean equator and equinox of {epoch_text} {time_system}) "
                  f"turned by the IAU 1976 precession" if frame == "EME2000" else
                  "REF_FRAME MOD: mean equator and equinox of REF_FRAME_EPOCH, fixed (not of date)")
    data_comments = (states.what,
                     *([f"Covariance: the filter's of its estimate of (r, v) at {len(covariances)} of the epochs"]
                       if covariances else []),
                     *([f"Burns: {written_burns.name} (RTN Delta-V, m/s)"] if written_burns else []))
    metadata = Metadata(object_name or sc.name, object_id or sc.name, frame, time_system, epochs[0], epochs[-1],
                        ref_frame_epoch=epoch_text if frame == "MOD" else None, comments=(frame_note,),
                        interpolation="LAGRANGE" if states.interpolable else None,
                        interpolation_degree=INTERPOLATION_DEGREE if states.interpolable else None)
    written = [write_oem(path, metadata, epochs, rv / 1e3, covariances=covariances, comments=comments,
                         data_comments=data_comments, xml=xml)]
    if written_burns:
        written.append(write_burns_csv(written_burns, burns))
    return written


def oem_states(result, oem_step_s: float | None = None, of: str = "truth") -> States:
    """The ``States`` ``save_oem`` writes (geojax ECI, SI): see the module's docstring."""
    from geojax.runner.report import scenario_of

    sc = scenario_of(result)
    eph = result.ephemeris
    n_steps = steps_per_cycle(sc.step_s)
    if oem_step_s is not None and not (math.isfinite(oem_step_s) and oem_step_s >= result.step_s):
        raise ValueError(f"oem_step: must be at least the integration step, {result.step_s:.6g} s, got {oem_step_s}")
    stride = 1 if oem_step_s is None else int(math.floor(oem_step_s / result.step_s * (1 + 1e-12)))
    filtered = _filter_on(result)
    if eph is None and (oem_step_s is not None or of == "estimate" and filtered):
        raise ValueError("oem_step: this run kept no states between its cycle starts; run it with "
                         "geojax.simulate(..., ephemeris=True)")
    if of == "estimate" and not filtered:
        t_tt_s, r, v = cycle_states(result)
        truth = np.hstack([r, v])[:-1] if eph is None else np.asarray(eph.truth, float)[:, 0]
        fix, sigma = gaussian_fixes(result, truth)
        return States(t_tt_s[:-1], fix, np.broadcast_to(np.diag(sigma**2), (len(fix), 6, 6)),
                      "The Gaussian orbit-determination fix the controller was told at each cycle start (no "
                      "navigation filter: no estimate between them); covariance: its errors' (diagonal).", False)
    if eph is None:
        t_tt_s, r, v = cycle_states(result)
        return States(t_tt_s, np.hstack([r, v]), None, "True states at each control-cycle start (one sidereal day "
                      "apart) and at the end of the run; samples of the closed loop, not nodes to interpolate "
                      "between.", False)
    n_total = eph.truth.shape[0] * n_steps
    t_steps = sc.epoch_tt_s + np.arange(n_total + 1) * result.step_s  # the loop's grid times, k n_steps step_s
    every = np.arange(0, n_total, stride)
    cov = None if eph.covariance is None else np.asarray(eph.covariance, float).reshape(n_total, 6, 6)
    spacing = (f"every {stride} integration steps" if stride > 1 else "every integration step") + \
        f" ({stride * result.step_s:.6g} s)"
    if of == "estimate":
        return States(t_steps[every], np.asarray(eph.estimate, float).reshape(n_total, 6)[every], cov[every],
                      f"The navigation filter's estimate at {spacing}, each after the measurements before it. "
                      f"{ACROSS_BURNS}", True)
    final = np.asarray(DYNAMICS[sc.dynamics].to_cartesian(np.asarray(result.final.orbit),
                                                          float(result.params.forces.mu_m3_s2)))
    ends = np.append(every, n_total)
    rv = np.vstack([np.asarray(eph.truth, float).reshape(n_total, 6)[every], final])
    if cov is not None:
        cov = np.concatenate([cov[every], np.full((1, 6, 6), np.nan)])
    return States(t_steps[ends], rv, cov, f"True states at {spacing} and at the end of the run. {ACROSS_BURNS}",
                  True)


def _filter_on(result) -> bool:
    from geojax.states import navigation

    return navigation.NAME in result.records.cycles.states


def gaussian_fixes(result, truth_rv) -> tuple[np.ndarray, np.ndarray]:
    """(fixes [n, 6], their 1-sigma [6]): the orbit-determination fix the loop drew at each of the n cycle starts
    from the true ``truth_rv`` [n, 6] there (``navigation.fix``'s errors, the same draws from the run's seed), ECI
    m and m/s."""
    if result.seed is None:
        raise ValueError("oem_of: estimate: this Result was made with a key, not a seed; its fixes cannot be drawn")
    errors = result.params.errors
    sigma = np.repeat([float(errors["sigma3_r_m"]) / 3, float(errors["sigma3_v_mps"]) / 3], 3)
    noise = np.asarray(_fix_noise(jax.random.key(result.seed), len(truth_rv)))
    return truth_rv + sigma * noise, sigma


@jax.jit
def _cycle_noise(key, k):
    return jax.random.normal(jax.random.fold_in(key, k), (2, 6))[0]


def _fix_noise(key, n_cycles: int):
    """[n_cycles, 6] the fix's N(0, 1) draws: row 0 of normal(fold_in(key, k), (2, 6)), as the loop draws them."""
    return jax.vmap(_cycle_noise, in_axes=(None, 0))(key, np.arange(n_cycles))


def cycle_states(result) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t_tt_s [n + 1], r_eci_m [n + 1, 3], v_eci_mps [n + 1, 3]): the true state at each of the n cycle starts
    (from the ``boundary`` records) and at the end (``result.final``), geojax ECI."""
    from geojax.runner.report import scenario_of

    sc = scenario_of(result)
    boundary = np.asarray(result.records.cycles.boundary, dtype=float)
    n_cycles = len(boundary)
    n_steps = steps_per_cycle(sc.step_s)
    # the loop's environment grid times, start + (2 k n_steps) (step_s / 2), the same numbers
    t_tt_s = sc.epoch_tt_s + np.arange(n_cycles + 1) * n_steps * result.step_s
    angle = np.asarray(_earth_angle_rad(t_tt_s[:-1], sc.epoch_tt_s, sc.tt_minus_ut1_s))
    mu = float(result.params.forces.mu_m3_s2)
    r, v = (np.asarray(x) for x in mee_to_cartesian(mee_of_boundary(boundary, angle), mu))
    final = np.asarray(DYNAMICS[sc.dynamics].to_cartesian(np.asarray(result.final.orbit), mu))
    return t_tt_s, np.vstack([r, final[:3]]), np.vstack([v, final[3:]])


# Compiled, as in the loop's environment grid: the same numbers (run eagerly they differ by 6e-12 rad, 0.2 mm
# along the orbit, XLA's rounding of the day count differing from NumPy's).
_earth_angle_rad = jax.jit(earth_rotation_angle_rad)


def mee_of_boundary(boundary, earth_angle_rad, iterations: int = 8) -> np.ndarray:
    """MEE [..., 6] (p, f, g, h, k, L) of boundary records [..., 6] (lon, a, f, g, h, k) at Earth angles [...]:
    ``predictor.boundary_elements`` inverted.  Newton on L - 2 f sin L + 2 g cos L = lon + angle (its derivative
    1 - 2 f cos L - 2 g sin L >= 1 - 2 e; e < 0.1 converges to rounding in a few iterations)."""
    lon, a, f, g, h, k = np.moveaxis(np.asarray(boundary, dtype=float), -1, 0)
    mean_lon = lon + earth_angle_rad
    true_lon = mean_lon
    for _ in range(iterations):
        residual = true_lon - 2 * f * np.sin(true_lon) + 2 * g * np.cos(true_lon) - mean_lon
        true_lon = true_lon - residual / (1 - 2 * f * np.cos(true_lon) - 2 * g * np.sin(true_lon))
    return np.stack([a * (1 - f * f - g * g), f, g, h, k, true_lon], axis=-1)


def run_burns(result) -> Burns | None:
    """The burns a run fired (``Burns``), in time order: a planner's from its records (as flown where the faults
    part rode the loop: missed burns left out, cut ones as cut, degraded ones at the level delivered), a feedback
    law's from the thrust of every step (``step_burns``: a run with ``ephemeris=True``); none without a
    controller; None for a feedback law's run without its steps' thrust."""
    from geojax.runner.report import scenario_of

    rec = result.records.cycles.controller
    sc = scenario_of(result)
    if not {"fired_s", "start_s", "directions_rsw"} <= set(rec):
        if result.ephemeris is not None:
            return step_burns(result.ephemeris.thrust, sc.epoch_tt_s, result.step_s)
        if sc.controller == "none" and "recovering" not in rec:
            return step_burns(np.zeros((0, 6)), sc.epoch_tt_s, result.step_s)
        return None
    fired_s, start_s = np.asarray(rec["fired_s"], float), np.asarray(rec["start_s"], float)
    directions = np.asarray(rec["directions_rsw"], float)
    flying = np.asarray(rec["thrusters"]) if "thrusters" in rec else np.broadcast_to(np.arange(2), fired_s.shape)
    planned = fired_s > 0
    level = np.ones(fired_s.shape)
    status = commanded_s = None
    for part in getattr(result, "parts", ()):  # a part that changes what flies (``states.faults``) says how
        if part.flown_burns is not None:
            fired_s, directions, level, status, commanded_s = part.flown_burns(result, fired_s, directions, flying)
    cycle_s = steps_per_cycle(sc.step_s) * result.step_s
    cycle = np.broadcast_to(np.arange(len(fired_s))[:, None], fired_s.shape)
    order = np.lexsort((start_s.ravel(), cycle.ravel()))
    order = order[planned.ravel()[order]]
    duration = fired_s.ravel()[order]
    thrusters = result.params.thrusters
    exhaust_mps = float(thrusters["isp_s"]) * G0_MPS2
    flow_kg_s = float(thrusters["thrust_n"]) / exhaust_mps  # at full thrust
    full_s = level.ravel()[order] * duration  # the firing time at full thrust of the same impulse
    mass_before = float(result.params.initial.mass_kg) - flow_kg_s * (np.cumsum(full_s) - full_s)
    used_kg = flow_kg_s * full_s
    dv = exhaust_mps * np.log(mass_before / (mass_before - used_kg))
    return Burns(cycle.ravel()[order], flying.ravel()[order] + 1,
                 sc.epoch_tt_s + cycle.ravel()[order] * cycle_s + start_s.ravel()[order], duration,
                 dv[:, None] * directions.reshape(-1, 3)[order], used_kg,
                 None if status is None else status.ravel()[order],
                 None if commanded_s is None else commanded_s.ravel()[order])


def step_burns(thrust, epoch_tt_s: float, step_s: float) -> Burns:
    """The burns of the thrust held over each step (``thrust`` [n_cycles, n_steps, 6] or [n, 6],
    ``recorder.THRUST_COLUMNS``): each run of consecutive firing steps with the same thrust vector in RSW (and the
    same thrust and Isp) is one burn, from its first step's start over its steps' span; its Delta-V the rocket
    equation step by step (the mass at each step's start), along the steps' direction, and its propellant theirs.
    Thruster 1 (one thruster along the commanded direction)."""
    thrust = np.asarray(thrust, float)
    n_steps = thrust.shape[1] if thrust.ndim == 3 else 1
    thrust = thrust.reshape(-1, 6)
    level_rsw, thrust_n, isp_s, mass_kg = thrust[:, :3], thrust[:, 3], thrust[:, 4], thrust[:, 5]
    firing = np.any(level_rsw != 0, axis=1) & (thrust_n > 0)
    same = np.zeros_like(firing)
    same[1:] = firing[1:] & firing[:-1] & np.all(thrust[1:, :5] == thrust[:-1, :5], axis=1)
    first = np.flatnonzero(firing & ~same)
    burn = np.cumsum(firing & ~same) - 1  # the burn of each firing step
    exhaust_mps = isp_s * G0_MPS2
    level = np.linalg.norm(level_rsw, axis=1)
    used_kg = np.where(firing, level * thrust_n / exhaust_mps * step_s, 0.0)
    dv_mps = np.where(firing, exhaust_mps * np.log(mass_kg / np.where(firing, mass_kg - used_kg, 1.0)), 0.0)
    per_step = dv_mps[:, None] * level_rsw / np.where(level > 0, level, 1.0)[:, None]
    steps = np.flatnonzero(firing)
    dv_rtn, mass, span = (np.zeros((len(first), 3)), np.zeros(len(first)), np.zeros(len(first)))
    np.add.at(dv_rtn, burn[steps], per_step[steps])
    np.add.at(mass, burn[steps], used_kg[steps])
    np.add.at(span, burn[steps], step_s)
    return Burns(first // n_steps, np.ones(len(first), int), epoch_tt_s + first * step_s, span, dv_rtn, mass)


def write_burns_csv(path: Path, burns: Burns) -> Path:
    """The burn list as CSV (``BURN_COLUMNS``: start in UTC ISO 8601 and TT seconds since J2000.0, firing time
    s, Delta-V magnitude and RTN components m/s; with the faults part, ``FAULT_BURN_COLUMNS``: each burn's status
    and its firing time commanded); written atomically."""
    partial = path.with_name(path.name + ".partial")
    with partial.open("w", newline="") as handle:
        out = csv.writer(handle)
        marked = burns.status is not None
        out.writerow(BURN_COLUMNS + (FAULT_BURN_COLUMNS if marked else ()))
        for i in range(len(burns.cycle)):
            dv = burns.dv_rtn_mps[i]
            out.writerow([int(burns.cycle[i]), int(burns.thruster[i]), calendar(burns.start_tt_s[i], "UTC"),
                          f"{burns.start_tt_s[i]:.6f}", f"{burns.duration_s[i]:.6f}",
                          f"{np.linalg.norm(dv):.9f}", *(f"{x:.9f}" for x in dv),
                          *((burns.status[i], f"{burns.planned_s[i]:.6f}") if marked else ())])
    partial.replace(path)
    return path


def calendar(t_tt_s: float, time_system: str = "UTC") -> str:
    """ISO 8601 calendar date of TT seconds since J2000.0, in TT or in UTC (``physics.time``'s leap seconds;
    the inverse of ``time.tt_seconds_from_utc`` outside a leap second), to the microsecond."""
    tt = J2000_TT + dt.timedelta(seconds=float(t_tt_s))
    if time_system == "TT":
        return tt.strftime("%Y-%m-%dT%H:%M:%S.%f")
    guess = tt - dt.timedelta(seconds=TT_MINUS_TAI_S + tai_minus_utc_s((tt - dt.timedelta(seconds=70)).date()))
    utc = tt - dt.timedelta(seconds=TT_MINUS_TAI_S + tai_minus_utc_s(guess.date()))
    return utc.strftime("%Y-%m-%dT%H:%M:%S.%f")
