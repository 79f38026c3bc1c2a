"""A run's manoeuvres as a CCSDS Orbit Parameter Message (OPM 2.0, CCSDS 502.0-B-2 sec. 3, KVN): ``save_maneuvers``.

The OPM's state is the run's initial true state (the OEM's frame and time system, ``export.trajectory``), its
spacecraft parameters the initial mass, and one maneuver block per burn flown (``trajectory.run_burns``: a
planner's, in time order): MAN_EPOCH_IGNITION (the firing start), MAN_DURATION (the firing time; a burn
suspended in the Earth's shadow spans longer), MAN_DELTA_MASS (the propellant, negative), MAN_REF_FRAME = RTN and
MAN_DV_1..3 (the Delta-V delivered, km/s, held fixed in RTN through the burn).  The plan is marked beside what
was flown: each block's COMMENT gives its cycle, thruster and the planned Delta-V (RSW = RTN, without the
attitude errors), and a burn planned but not fired (shorter than the minimum burn, or in a cycle without a
solution) is a COMMENT of the header, not a maneuver block.  A feedback law's burns (the recovery law's included)
are its steps' thrust (``trajectory.step_burns``, a run with ``ephemeris=True``), MAN_DURATION their span at the
level flown; a run without a controller writes the initial state and no maneuver block.  The Delta-V is as commanded: the thrust and Isp of
the scenario along the directions flown (attitude errors included); a navigation model's execution errors
(``states.navigation``) are not in it, so with one the blocks' sum differs from the delivered ``dv_mps`` by
them.  Written here for the reason the OEM is (``export.oem``); ``tests/test_ccsds.py`` reads it back with
``ccsds-ndm``.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path

import numpy as np

from geojax.export.oem import state_fields

VERSION = "2.0"
FEEDBACK = ("a feedback law thrusts per step: each burn is a run of consecutive steps firing the same thrust vector "
            "in RTN, MAN_DURATION their span (the thrust below full level: Delta-V / duration its acceleration)")


def save_maneuvers(result, path: str | Path, *, frame: str = "EME2000", time_system: str = "UTC",
                   object_name: str | None = None, object_id: str | None = None,
                   created: dt.datetime | None = None) -> Path:
    """Write a single rollout's burns as a KVN OPM at ``path`` (atomically); returns the path.  ``frame``,
    ``time_system``, ``object_name`` and ``object_id`` as for ``trajectory.save_oem`` (the initial state's; the
    manoeuvres are in RTN).  ``ValueError`` for a feedback law's run made without ``ephemeris=True`` (its burns
    are read from its steps' thrust)."""
    from geojax import __version__
    from geojax.export import trajectory
    from geojax.runner.report import scenario_of
    from geojax.physics.ephemeris import precession_from_j2000
    from geojax.physics.propagate import DYNAMICS

    if frame not in trajectory.FRAMES:
        raise ValueError(f"frame: must be one of {', '.join(trajectory.FRAMES)}, got {frame!r}")
    if time_system not in trajectory.TIME_SYSTEMS:
        raise ValueError(f"time_system: must be one of {', '.join(trajectory.TIME_SYSTEMS)}, got {time_system!r}")
    sc = scenario_of(result)
    burns = trajectory.run_burns(result)
    if burns is not None:
        burns = trajectory.burns_flown(burns)
    if burns is None:
        raise ValueError(f"maneuvers: controller {sc.controller} thrusts per step; its burns are read from the steps "
                         f"of a run made with geojax.simulate(..., ephemeris=True)")
    rv = np.asarray(DYNAMICS[sc.dynamics].to_cartesian(np.asarray(result.params.initial.orbit),
                                                       float(result.params.forces.mu_m3_s2)))
    if frame == "EME2000":
        rv = rv @ np.kron(np.eye(2), np.asarray(precession_from_j2000(sc.epoch_tt_s)))
    calendar = lambda t: trajectory.calendar(t, time_system)  # noqa: E731
    created = (created or dt.datetime.now(dt.timezone.utc)).strftime("%Y-%m-%dT%H:%M:%S")
    planner = "burns" in result.records.cycles.controller
    lines = [f"CCSDS_OPM_VERS = {VERSION}",
             f"COMMENT geojax {__version__}: scenario {sc.name}, controller {sc.controller}, "
             f"{'seed ' + str(result.seed) if result.seed is not None else 'a given key'}",
             f"COMMENT {len(burns.cycle)} burns flown, one maneuver block each; Delta-V as commanded (thrust and "
             f"Isp of the scenario along the directions flown, attitude errors included)",
             *([] if planner else [f"COMMENT {FEEDBACK if len(burns.cycle) else 'no burn was flown'}"]),
             *(f"COMMENT {line}" for line in (unflown(result) if planner else ())),
             f"CREATION_DATE = {created}", "ORIGINATOR = geojax",
             f"OBJECT_NAME = {object_name or sc.name}", f"OBJECT_ID = {object_id or sc.name}", "CENTER_NAME = EARTH",
             f"REF_FRAME = {frame}", *([f"REF_FRAME_EPOCH = {calendar(sc.epoch_tt_s)}"] if frame == "MOD" else []),
             f"TIME_SYSTEM = {time_system}", "COMMENT the true state at the start of the run",
             f"EPOCH = {calendar(sc.epoch_tt_s)}",
             *(f"{key} = {value}" for key, value in zip(("X", "Y", "Z", "X_DOT", "Y_DOT", "Z_DOT"),
                                                        state_fields(rv / 1e3), strict=True)),
             f"MASS = {float(result.params.initial.mass_kg):.6f}"]
    planned = planned_rtn_mps(result) if planner else None
    for i in range(len(burns.cycle)):
        k, thruster = int(burns.cycle[i]), int(burns.thruster[i])
        dv_kmps = burns.dv_rtn_mps[i] / 1e3
        if planner:
            plan = planned[k, (thruster - 1) % 2]  # thrusters k + 1 and k + 3 on arm k (``control.burns``)
            said = (f"planned Delta-V RTN {plan[0]:.9f} {plan[1]:.9f} {plan[2]:.9f} m/s (attitude errors not "
                    f"included)")
        else:
            said = "thrust per step of the feedback law, at the level flown over the span"
        lines += [f"COMMENT flown burn {i + 1}: cycle {k}, thruster {thruster}; {said}",
                  f"MAN_EPOCH_IGNITION = {calendar(burns.start_tt_s[i])}",
                  f"MAN_DURATION = {burns.duration_s[i]:.6f}",
                  f"MAN_DELTA_MASS = {-burns.mass_kg[i]:.9f}", "MAN_REF_FRAME = RTN",
                  *(f"MAN_DV_{axis + 1} = {dv_kmps[axis]:.15f}" for axis in range(3))]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".partial")
    partial.write_text("\n".join(lines) + "\n")
    partial.replace(path)
    return path


def planned_rtn_mps(result) -> np.ndarray:
    """[n_cycles, 2, 3] the Delta-V each cycle's plan asked of each thruster, RSW (= RTN), m/s."""
    return np.asarray(result.records.cycles.controller["burns"].dv_rsw_mps, float)


def unflown(result) -> list[str]:
    """One line per burn planned (V > 0) but not fired: its cycle, thruster and planned Delta-V."""
    rec = result.records.cycles.controller
    v_mps, fired_s = np.asarray(rec["burns"].v_mps, float), np.asarray(rec["fired_s"], float)
    feasible = np.asarray(rec["burns"].feasible, bool)
    planned = planned_rtn_mps(result)
    return [f"planned, not flown: cycle {k}, thruster {j + 1}, Delta-V RTN {' '.join(f'{x:.9f}' for x in planned[k, j])}"
            f" m/s ({'shorter than the minimum burn' if feasible[k] else 'no solution that cycle'})"
            for k, j in zip(*np.nonzero((v_mps > 0) & (fired_s <= 0)), strict=True)]
