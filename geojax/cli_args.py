"""The arguments of the ``geojax`` command line, the scenario keys they set and the output paths they name
(checked before a run); ``geojax.cli`` runs the commands and prints."""

from __future__ import annotations

import argparse

import geojax

FORCE_HELP = ("replace the files the command writes (results, OEM, tuned scenario) where they exist (default: "
              "refused, exit 2, before anything runs; a sweep's --resume continues its file instead); figures are "
              "redrawn in place either way")
DAYS_HELP = ("duration in solar days (default: the scenario's); the run is that many sidereal-day cycles, "
             "rounded (20 days: 20 cycles), the same in propagate, bound and simulate (a sweep file sets it as "
             "\"duration.days\" in [set], a tuning file as days)")
SET_HELP = ("set a scenario key, as a sweep file's [set] does: a dotted KEY (thrusters.beta_max_deg, "
            "errors.h_rv, name) and a TOML VALUE (60.0, true, [0.1, 0, 0], \"text\"; a bare word is a string); "
            "repeatable; a key a flag of its own also sets (--days) is refused")


def set_values(items: list[str]) -> dict:
    """The ``--set KEY=VALUE`` items as ``{KEY: value}``, each VALUE read as a TOML value (a bare word that is not
    one: a string); ``ValueError`` naming the item at fault."""
    import tomllib

    values = {}
    for item in items:
        key, equals, text = item.partition("=")
        key = key.strip()
        if not equals or not key or not text.strip():
            raise ValueError(f"--set {item!r}: must be KEY=VALUE, e.g. thrusters.beta_max_deg=60")
        if key in values:
            raise ValueError(f"--set {key}: given twice")
        try:
            values[key] = tomllib.loads(f"value = {text}")["value"]
        except tomllib.TOMLDecodeError:
            values[key] = text.strip()
    return values


def overrides(args) -> dict:
    """The scenario keys the command's flags and ``--set`` items set (a key set both ways is refused)."""
    names = {"days": "duration.days", "step": "integration.step_s", "controller": "controller.kind",
             "horizon": "controller.horizon", "h_rv": "errors.h_rv", "h_att": "errors.h_att",
             **{flag: f"errors.{flag}" for flag in ("sigma3_r_m", "sigma3_v_mps", "sigma3_att_deg", "sigma3_dv_pct")}}
    flags = {key: getattr(args, flag) for flag, key in names.items() if getattr(args, flag, None) is not None}
    given = set_values(getattr(args, "set", []))
    for key in given.keys() & flags.keys():
        flag = next(f for f, k in names.items() if k == key)
        raise ValueError(f"--set {key}: also given as --{flag.replace('_', '-')}; give one")
    return {**given, **flags}


def check_outputs(args, *files) -> None:
    """Output paths are checked before any computation (a run never finds out after an hour that it cannot save),
    and a results file that exists is refused without ``--force`` (a sweep's ``--resume`` continues it instead);
    ``files``: more paths the command writes (a tuning's scenario)."""
    from geojax.store import check_output_file, check_output_folder

    replace = args.force or args.command == "sweep"  # a sweep's file and parts: run_sweep, which knows --resume
    named = [(name, getattr(args, name, None)) for name in ("out", "oem", "maneuvers")]
    for name, path in [*named, *(("out", f) for f in files)]:
        if path:
            check_output_file(path, name, replace)
    for flag in ("oem_step", "oem_of"):
        if getattr(args, flag, None) is not None and not getattr(args, "oem", None):
            raise ValueError(f"{flag}: needs --oem FILE")
    if getattr(args, "plots", None):
        check_output_folder(args.plots)


def parser() -> argparse.ArgumentParser:
    """Every command, its arguments and their help; ``args.command`` names the command given (None: none)."""
    top = argparse.ArgumentParser(
        prog="geojax",
        description="Closed-loop station keeping of electric-propulsion GEO satellites in JAX.",
    )
    top.add_argument("--version", action="version", version=f"geojax {geojax.__version__}")
    sub = top.add_subparsers(dest="command", metavar="COMMAND")
    common = argparse.ArgumentParser(add_help=False)  # every command: -q / -v
    talk = common.add_mutually_exclusive_group()
    talk.add_argument("-q", "--quiet", action="store_true", help="print only the files written (and errors)")
    talk.add_argument("-v", "--verbose", action="store_true",
                      help="also print compilation times, devices and where each number comes from")
    common.add_argument("--no-cache", action="store_true",
                        help="compile every program afresh and keep none (default: compiled programs are kept in "
                             "$GEOJAX_CACHE_DIR or the user's cache folder and reused by later runs; "
                             "GEOJAX_NO_CACHE=1 does the same as this flag)")

    writes = argparse.ArgumentParser(add_help=False)  # every command that writes results files
    writes.add_argument("--force", action="store_true", help=FORCE_HELP)

    sets = argparse.ArgumentParser(add_help=False)  # every command that runs one scenario
    sets.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", dest="set", help=SET_HELP)

    def command(name, writing: bool = True, scenario: bool = False, **kw):
        parents = [common, *([writes] if writing else []), *([sets] if scenario else [])]
        return sub.add_parser(name, parents=parents, **kw)

    demo = command("demo", help="li2022 for one year, without control and with the QFFC: summaries, figures")
    demo.add_argument("--out", default="geojax-demo", help="folder for the figures and HDF5 files (default: geojax-demo)")

    prop = command("propagate", scenario=True, help="uncontrolled propagation; one-cycle mean elements per sidereal day")
    prop.add_argument("scenario", help="a shipped scenario name (see 'geojax scenarios') or a .toml path")
    prop.add_argument("--days", type=float, help=DAYS_HELP)
    prop.add_argument("--step", type=float, help="integration step in s, rounded to a whole number per sidereal day")
    prop.add_argument("--out", help="write the per-cycle mean elements to this HDF5 file")
    prop.add_argument("--plots", help="folder for the figure (NAME-uncontrolled.png)")
    prop.add_argument("--oem", metavar="FILE", help="write the free drift's true state at every integration step and "
                      "the end as a CCSDS OEM 2.0, as simulate --oem does (from the closed loop with the null "
                      "controller, the same steps: one more run)")
    prop.add_argument("--oem-step", type=float, metavar="SECONDS", help="with --oem: the states' spacing, as the "
                      "largest whole number of integration steps within SECONDS (default: every step)")
    prop.add_argument("--maneuvers", metavar="FILE", help="write the CCSDS OPM 2.0 simulate --maneuvers writes: the "
                      "initial state and no maneuver block (the free drift fires nothing)")

    bnd = command("bound", scenario=True, help="the least Delta-V that holds the scenario's box with its thrusters (a linear program), "
                                "re-simulated in the closed loop")
    bnd.add_argument("scenario", help="a shipped scenario name or a .toml path (its thrusters, box, forces, epoch)")
    bnd.add_argument("--days", type=float, help=DAYS_HELP)
    bnd.add_argument("--step", type=float, help="integration step in s, rounded to a whole number per sidereal day")
    bnd.add_argument("--slot-steps", type=int, default=4,
                     help="integration steps per thrust slot (thrust constant in RSW over a slot; default 4: 1 h)")
    bnd.add_argument("--thrusters", choices=("arms", "gimbal", "fixed4", "axes"),
                     help="thruster geometry: Li's two arms, Katz's gimbal, Gazzino's four fixed NE/NW/SE/SW thrusters, "
                          "Katz's per-axis pairs (default: the controller's, Spec.bound_geometry: axes for a "
                          "discrete lyapunov law, gimbal for another lyapunov or a zone_nssk scenario, else arms)")
    bnd.add_argument("--acquisition-days", type=float, default=0.0,
                     help="hold the box from this day on (a start the thrusters cannot hold at once; default 0)")
    bnd.add_argument("--free-end", action="store_true",
                     help="no end condition (the free end: the plan may end anywhere in the box); default: periodic, "
                          "the plan ends where it started, x(T) = x(0) (Gazzino 2016), a steady state's Delta-V")
    bnd.add_argument("--out", help="write /metrics, /rounds and the per-slot /slots to this HDF5 file")
    bnd.add_argument("--plots", help="folder for the figure of the plan and the flown box (NAME-bound.png)")

    sim = command("simulate", scenario=True, help="closed-loop station keeping (any controller); summary, metrics, status, HDF5")
    sim.add_argument("scenario", help="a scenario, e.g. li2022-qffc, li2022-fompc, or a .toml path; one without a "
                     "controller (kind none, e.g. li2022 or geo) runs uncontrolled, with every file a controlled run has")
    sim.add_argument("--controller", help="override controller.kind (qffc, fompc, lyapunov, ...)")
    sim.add_argument("--horizon", type=int, help="FOMPC prediction horizon N in cycles, 1-10 (default: the scenario's)")
    sim.add_argument("--days", type=float, help=DAYS_HELP)
    sim.add_argument("--step", type=float, help="integration step in s, rounded to a whole number per sidereal day")
    sim.add_argument("--seed", type=int, default=0, help="seed of the orbit-determination and attitude errors (default 0)")
    sim.add_argument("--h-rv", type=float, help="orbit-determination error H_rv, a multiple of Li 2022's nominal "
                     "3-sigma per component, 0.3 m and 5e-5 m/s (eq. 48; 0: none; default: the scenario's)")
    sim.add_argument("--h-att", type=float, help="attitude error H_att of the burns, a multiple of Li 2022's nominal "
                     "3-sigma, 0.05 deg in yaw and pitch (eq. 48; 0: none; default: the scenario's)")
    sim.add_argument("--sigma3-r-m", type=float, metavar="M", help="orbit-determination position error, 3-sigma per "
                     "component in m (errors.sigma3_r_m: sets H_rv; with --sigma3-v-mps, 0 where not given)")
    sim.add_argument("--sigma3-v-mps", type=float, metavar="MPS", help="orbit-determination velocity error, 3-sigma "
                     "per component in m/s (errors.sigma3_v_mps)")
    sim.add_argument("--sigma3-att-deg", type=float, metavar="DEG", help="attitude error of the burns, 3-sigma in yaw "
                     "and pitch in deg (errors.sigma3_att_deg: sets H_att)")
    sim.add_argument("--sigma3-dv-pct", type=float, metavar="PCT", help="magnitude (thrust level) error of each burn, "
                     "3-sigma in %% of the planned (errors.sigma3_dv_pct; a planner's burns)")
    sim.add_argument("--out", help="write /metrics and /cycles to this HDF5 file")
    sim.add_argument("--plots", help="folder for the figures: the run's (NAME.png, NAME-station-keeping.png; a feedback "
                                     "law's NAME-ground-track.png, NAME-thrust.png), then "
                                     "each carried part's (NAME-wheels.png; NAME-navigation-error.png, "
                                     "NAME-navigation-consistency.png)")
    sim.add_argument("--oem", metavar="FILE", help="write the true state at every integration step and the end as a "
                     "CCSDS OEM 2.0 (EME2000, UTC; LAGRANGE interpolation metadata; with the navigation filter its "
                     "covariance blocks; XML where FILE ends in .xml, else KVN) and a planner's burns as FILE's "
                     "stem + -burns.csv (start, firing time, RTN Delta-V), for operations, Orekit, GMAT or STK")
    sim.add_argument("--oem-step", type=float, metavar="SECONDS", help="with --oem: the states' spacing, as the "
                     "largest whole number of integration steps within SECONDS (default: every step)")
    sim.add_argument("--oem-of", choices=("truth", "estimate"), help="with --oem: the true ephemeris (default) or the "
                     "estimated one: the navigation filter's, or without one the Gaussian fix at each cycle start")
    sim.add_argument("--maneuvers", metavar="FILE", help="write the burns flown as a CCSDS OPM 2.0 (KVN): the initial "
                     "state and one maneuver block per burn (MAN_EPOCH_IGNITION, MAN_DURATION, MAN_DELTA_MASS, "
                     "MAN_REF_FRAME = RTN, MAN_DV_1..3); a planner's planned Delta-V in each block's COMMENT; a "
                     "feedback law's (the recovery law's) burns are its runs of steps firing the same thrust; "
                     "none without a controller")

    tune = command("tune", help="tune controller gains by gradients through the rollout (Katz 2025)")
    tune.add_argument("file", help="a tuning file (TOML; its keys: geojax.tune.spec)")
    tune.add_argument("--out", required=True, help="results file (HDF5): /iterations per iteration, /best, /metrics; "
                      "the tuned scenario is written beside it as FILE-tuned.toml")

    swp = command("sweep", help="Monte Carlo sweep over scenario parameters x repetitions x controllers; HDF5")
    swp.add_argument("file", help="a sweep file (TOML; see geojax.sweep for the keys)")
    swp.add_argument("--out", required=True, help="results file (HDF5); chunks are kept in FILE.h5.parts/ until done")
    swp.add_argument("--resume", action="store_true", help="continue an interrupted sweep into the same --out")
    swp.add_argument("--chunk", type=int, help="samples per saved chunk (default: one compiled batch of the widest "
                     "controller on every local device, or with --ray on a cluster with GPUs an even share per GPU "
                     "worker, at most one GPU batch; a resumed sweep keeps its cut)")
    swp.add_argument("--lanes", type=int, help="samples per device in one compiled call (default: the platform's, "
                     "128 QFFC / 32 FOMPC / 8 MPC per CPU core, on a GPU the widest batch its memory holds, up to "
                     "65536); the results do not depend on it; one that cannot fit is refused")
    swp.add_argument("--ray", nargs="?", const="local", metavar="ADDRESS",
                     help="run the chunks as Ray tasks: alone, on a Ray instance started here; 'auto', HOST:PORT or "
                     "ray://HOST:PORT, on a running cluster (pip install \"geojax[ray]\"); same results as a local run")
    swp.add_argument("--workers", type=int, help="with --ray: worker processes (default one per GPU of a GPU node "
                     "and one per CPU node, each using its share of the node's cores)")

    plot = command("plot", writing=False, help="draw the figures of a results file (simulate, propagate, sweep, tune, bound, transfer)")
    plot.add_argument("file", help="an HDF5 file written by geojax")
    plot.add_argument("--out", help="folder for the figures (default: next to the file)")
    plot.add_argument("--format", choices=("png", "pdf", "svg"), default="png", help="figure format (default png)")
    plot.add_argument("--dpi", type=int, default=150, help="resolution of PNG figures (default 150)")

    xfer = command("transfer", scenario=True, help="GTO-GEO low-thrust transfer, gimbaled boom or quadrilateral layout (Ma & Kong 2023)")
    xfer.add_argument("scenario", help="a shipped transfer (ma2023-boom, ma2023-quadrilateral) or a .toml path")
    xfer.add_argument("--days", type=float, help="time limit in solar days (default: the scenario's); the transfer "
                      "stops earlier when it reaches GEO (not sidereal-day cycles: a transfer has no control cycle)")
    xfer.add_argument("--out", help="write /metrics and the daily /records to this HDF5 file")
    xfer.add_argument("--plots", help="folder for the figure of the orbit and mass against time (NAME.png)")

    scen = command("scenarios", writing=False, help="list the shipped scenarios, or print one's TOML")
    scen.add_argument("--show", metavar="NAME", help="print the TOML of the shipped scenario NAME")
    return top
