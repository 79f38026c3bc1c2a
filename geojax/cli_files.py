"""The CCSDS files a single run's flags name (``--oem``, ``--oem-step``, ``--oem-of``, ``--maneuvers``), for
``geojax simulate`` and ``geojax propagate`` alike: checked before the run, written after it by the run's result
(``Result.save_oem``, ``Result.save_maneuvers``); ``geojax.cli`` calls them."""

from __future__ import annotations


def check(args, scenario) -> None:
    """``--oem-step`` below the scenario's integration step is refused before the run (``ValueError``)."""
    from geojax.physics.constants import SIDEREAL_DAY_S
    from geojax.physics.propagate import steps_per_cycle

    if getattr(args, "oem_step", None) is not None:
        step_s = SIDEREAL_DAY_S / steps_per_cycle(scenario.step_s)
        if not args.oem_step >= step_s:  # NaN too
            raise ValueError(f"oem_step: must be at least the integration step, {step_s:.6g} s, got {args.oem_step:g}")


def needs_ephemeris(args, scenario) -> bool:
    """Whether the run must keep every step's state and thrust: for ``--oem``, and for ``--maneuvers`` of a
    controller that thrusts per step (a feedback law, the recovery law; its burns are read from its steps)."""
    from geojax.control.base import keeps_steps
    from geojax.runner.setup import controller_of

    return bool(getattr(args, "oem", None)) or bool(getattr(args, "maneuvers", None)) and keeps_steps(
        controller_of([scenario]))


def write(args, run) -> None:
    """Write the files the flags name from ``run`` (a ``Result``, or a cluster's ``ClusterResult``: one file per
    satellite), printing each path."""
    if getattr(args, "oem", None):
        print("wrote " + " and ".join(map(str, run.save_oem(args.oem, oem_step_s=args.oem_step,
                                                            of=getattr(args, "oem_of", None) or "truth"))))
    if getattr(args, "maneuvers", None):
        written = run.save_maneuvers(args.maneuvers)  # a cluster's: one file per satellite
        print("wrote " + " and ".join(map(str, written if isinstance(written, list) else [written])))
