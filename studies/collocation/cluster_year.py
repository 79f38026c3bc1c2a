"""A four-satellite cluster kept for a year: its least separation over a Monte Carlo of clusters, and the ΔV
price of holding non-zero e and i vectors against the lone satellite.

    python studies/collocation/cluster_year.py [--controller qffc] [--clusters 64] [--days 365.25]
        [--navigation nominal|ranging] [--set KEY=VALUE ...] [--coordinated D_MIN_KM] [--name NAME]
        [--out studies/collocation/results]

``collocation-4`` (four of the ``geo`` satellites at 19.2 deg E, e and i vectors on circles of 1.5e-4 at the same
phase), every satellite kept by ``--controller`` with Li 2022's nominal errors (H_rv = H_att = 1), ``--clusters``
clusters each with its own draws (a sweep: every sample a whole cluster); against it the same satellite flown
alone on e = i = 0 targets (``--clusters`` samples).  Per run: the least separation's percentiles over the
clusters, the fraction below the 2 km alert, the satellites' boxes, the ΔV of the cluster's satellites against
the lone one's.  ``--coordinated`` keeps each cluster in one MPC program that holds its pairs ``D_MIN_KM`` apart
(``control.mpc_cluster``; the lone satellite flies the MPC alone).  Writes ``cluster_year_<controller>.md`` and
``.json`` (or ``NAME``'s) into ``--out``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import h5py
import numpy as np

import geojax
from geojax import scenario
from geojax.sweep import load as load_sweep, run_sweep

HERE = Path(__file__).resolve().parent
SATELLITES = "ABCD"


# Two stations' ranging for a satellite at 19.2 deg E (the filter of ``li2022-qffc-ranging`` with stations that
# see the slot): Betzdorf (Luxembourg) and Hartebeesthoek (South Africa), a north-south baseline.
RANGING = """
[navigation]
model = "ekf"
filter_forces = "loop"
snc_mps2_per_rthz = 1e-9
initial_sigma_r_m = 100.0
initial_sigma_v_mps = 0.01

[[navigation.stations]]
lat_deg = 49.69
lon_deg = 6.33
alt_m = 300.0
mask_deg = 5.0
measurements = ["range"]
range_sigma_m = 5.0
cadence_s = 43200.0
pass_s = 7200.0
phase_s = 0.0

[[navigation.stations]]
lat_deg = -25.89
lon_deg = 27.69
alt_m = 1400.0
mask_deg = 5.0
measurements = ["range"]
range_sigma_m = 5.0
cadence_s = 43200.0
pass_s = 7200.0
phase_s = 0.0
"""


def with_ranging(folder: Path, name: str, text: str) -> Path:
    """A scenario file of ``text`` with two stations' ranging into the filter (``RANGING``)."""
    cut = text.index("[duration]")
    path = folder / f"{name}.toml"
    path.write_text(text[:cut] + RANGING + "\n" + text[cut:])
    return path


def sweep_file(folder: Path, name: str, base: str, controller: str, clusters: int, days: float,
               errors: bool = True, settings: tuple[str, ...] = ()) -> Path:
    """A sweep of ``clusters`` repetitions of ``base``; ``settings`` are ``KEY=VALUE`` lines added to its ``[set]``
    (VALUE as TOML writes it), for both the cluster and the lone satellite."""
    path = folder / f"{name}.toml"
    path.write_text(f'name = "{name}"\nscenario = "{base}"\ncontrollers = ["{controller}"]\nrepetitions = {clusters}\n'
                    f'seed = 2026\n[set]\n"duration.days" = {days}\n' +
                    ('"errors.h_rv" = 1.0\n"errors.h_att" = 1.0\n' if errors else
                     '"errors.sigma3_dv_pct" = 6.0\n"errors.sigma3_att_deg" = 0.3\n') +  # the filter's: 2 %, 0.1 deg
                    "".join(f'"{k.strip()}" = {v.strip()}\n' for k, v in (line.split("=", 1) for line in settings)))
    return path


def lone_text() -> str:
    """``collocation-4``'s satellite alone, on e = i = 0 targets."""
    text = scenario.read_text("collocation-4")
    cut, duration = text.index("# The cluster"), text.index("[duration]")
    return text[:cut].replace('name = "collocation-4"', 'name = "lone"') + text[duration:]


def _finished(path: Path, spec: Path) -> bool:
    """Whether ``path`` is a finished sweep of the sweep file ``spec`` as it reads now."""
    if not path.exists():
        return False
    with h5py.File(path) as f:
        return f.attrs.get("config_toml", None) == spec.read_text()


def metrics(path: Path) -> dict:
    with h5py.File(path) as f:
        return {k: np.asarray(v[()], float).reshape(-1) for k, v in f["metrics"].items()} | {
            "status": np.asarray(f["status/code"][()]).reshape(-1)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--controller", default="qffc")
    parser.add_argument("--clusters", type=int, default=64)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--navigation", choices=("nominal", "ranging"), default="nominal",
                        help="Li's nominal Gaussian fixes, or two stations' ranging into the filter")
    parser.add_argument("--set", dest="settings", action="append", default=[], metavar="KEY=VALUE",
                        help="a scenario key for every satellite and the lone one, e.g. controller.e_max=1e-4 "
                             "(the MPC's windows within the separation); repeatable")
    parser.add_argument("--coordinated", type=float, metavar="D_MIN_KM",
                        help="the cluster in one MPC program holding every pair this far apart (controller mpc)")
    parser.add_argument("--name", help="the results files' name (by default cluster_year_CONTROLLER[_ranging])")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    if any("=" not in line for line in args.settings):
        parser.error("--set takes KEY=VALUE")
    if args.coordinated is not None and args.controller != "mpc":
        parser.error("--coordinated: the coordinated program is the MPC's (--controller mpc)")
    together = () if args.coordinated is None else (
        "collocation.coordinated=true", f"collocation.min_separation_km={args.coordinated}")
    label = args.controller + ("" if args.navigation == "nominal" else "_ranging")
    name = args.name or f"cluster_year_{label}"
    work = args.out / name
    work.mkdir(parents=True, exist_ok=True)
    ranging = args.navigation == "ranging"
    base = str(with_ranging(work, "cluster_scenario", scenario.read_text("collocation-4"))) if ranging else \
        "collocation-4"
    lone_path = (with_ranging(work, "lone_satellite", lone_text()) if ranging else work / "lone_satellite.toml")
    if not ranging:
        lone_path.write_text(lone_text())
    cluster, lone = work / "cluster.h5", work / "lone.h5"
    for path, spec in ((cluster, sweep_file(work, "cluster", base, args.controller, args.clusters, args.days,
                                            not ranging, (*args.settings, *together))),
                       (lone, sweep_file(work, "lone", str(lone_path), args.controller, args.clusters, args.days,
                                         not ranging, tuple(args.settings)))):
        if not _finished(path, spec):  # a finished sweep of the same file is read again, not flown again
            run_sweep(load_sweep(spec), path, resume=Path(f"{path}.parts").exists(), force=path.exists())
    wall_s = 0.0
    for path in (cluster, lone):  # the sweeps' own times (a finished one read again costs nothing)
        with h5py.File(path) as f:
            wall_s += float(f.attrs["wall_s"])
    c, s = metrics(cluster), metrics(lone)
    sep = c["min_separation_km"]
    dv_cluster = np.concatenate([c[f"dv_per_year_mps_{k}"] for k in SATELLITES])
    worst = int(np.argmin(sep))
    pair = ["A_B", "A_C", "A_D", "B_C", "B_D", "C_D"][int(c["min_separation_pair"][worst])]
    near = sep < np.percentile(sep, 50) - 1.0  # the clusters of the low mode, if any
    held = {k: int(np.sum(c[f"status_{k}"] == 0)) if f"status_{k}" in c else None for k in SATELLITES}
    data = {
        "controller": args.controller, "clusters": args.clusters, "days": args.days, "wall_s": wall_s,
        "geojax_version": geojax.__version__,
        "command": f"python studies/collocation/cluster_year.py --controller {args.controller} "
                   f"--clusters {args.clusters} --days {args.days:g}" +
                   ("" if not ranging else " --navigation ranging") +
                   "".join(f" --set {line}" for line in args.settings) + (f" --name {args.name}" if args.name else "") +
                   ("" if args.coordinated is None else f" --coordinated {args.coordinated:g}"),
        "settings": args.settings,
        "navigation": args.navigation,
        "min_estimated_separation_km": float(c["min_estimated_separation_km"].min()),
        "max_separation_error_km": float(c["max_separation_error_km"].max()),
        "min_separation_km": {"min": float(sep.min()), "p5": float(np.percentile(sep, 5)),
                              "p50": float(np.percentile(sep, 50)), "p95": float(np.percentile(sep, 95))},
        "below_alert_fraction": float(np.mean(sep < c["alert_km"])),
        "worst": {"day": float(c["min_separation_day"][worst]), "pair": pair,
                  "clusters_1km_below_median": int(np.sum(near)),
                  "their_days": sorted({round(float(d), 1) for d in c["min_separation_day"][near]})},
        "clusters_held": int(np.sum(c["status"] == 0)),
        "max_abs_dlon_deg": float(c["max_abs_dlon_deg"].max()), "max_abs_dlat_deg": float(c["max_abs_dlat_deg"].max()),
        "dv_cluster_mean_mps": float(dv_cluster.mean()), "dv_cluster_std_mps": float(dv_cluster.std()),
        "dv_lone_mean_mps": float(s["dv_per_year_mps"].mean()), "dv_lone_std_mps": float(s["dv_per_year_mps"].std()),
        "lone_held": int(np.sum(s["status"] == 0)), "satellites_held": held,
    }
    data["dv_price_percent"] = (100 * (data["dv_cluster_mean_mps"] / data["dv_lone_mean_mps"] - 1)
                                if data["dv_lone_mean_mps"] > 0 else float("nan"))  # a run too short to burn
    (args.out / f"{name}.json").write_text(json.dumps(data, indent=1))
    m = data["min_separation_km"]
    lines = [f"# collocation-4 for {args.days:g} days under {args.controller.upper()}, {args.clusters} clusters"
             + (", ranging" if ranging else ""), "",
             f"`{data['command']}` ({wall_s / 60:.0f} min, geojax {geojax.__version__}); "
             + ("Li's nominal errors (H_rv = H_att = 1)" if not ranging else
                "each satellite's orbit determined by its own filter on two stations' 5 m ranging twice a day "
                "(Betzdorf, Hartebeesthoek), burns flown with 2 % and 0.1° execution errors") +
             ", every cluster its own draws.", "",
             "| quantity | value |", "|---|---:|",
             f"| least separation, every cluster (km) | {m['min']:.3f} |",
             f"| percentiles 5 / 50 / 95 over the clusters (km) | {m['p5']:.3f} / {m['p50']:.3f} / {m['p95']:.3f} |",
             f"| the least, when and between which pair | day {data['worst']['day']:.2f}, {pair} |",
             f"| clusters more than 1 km below the median, and on which days | "
             f"{data['worst']['clusters_1km_below_median']}, days {', '.join(map(str, data['worst']['their_days']))} |",
             f"| clusters closer than the 2 km alert | {data['below_alert_fraction']:.1%} |",
             f"| the least separation seen from the estimates at cycle starts (km) | "
             f"{data['min_estimated_separation_km']:.3f} |",
             f"| the largest error of that separation (km) | {data['max_separation_error_km']:.4f} |",
             f"| clusters whose four satellites kept their boxes | {data['clusters_held']} of {args.clusters} |",
             f"| largest longitude / latitude excursion (deg) | {data['max_abs_dlon_deg']:.4f} / "
             f"{data['max_abs_dlat_deg']:.4f} |",
             f"| ΔV per satellite, cluster (m/s/yr) | {data['dv_cluster_mean_mps']:.2f} ± {data['dv_cluster_std_mps']:.2f} |",
             f"| ΔV, the satellite alone on e = i = 0 (m/s/yr) | {data['dv_lone_mean_mps']:.2f} ± "
             f"{data['dv_lone_std_mps']:.2f} ({data['lone_held']} of {args.clusters} held) |",
             f"| the price of the separation | {data['dv_price_percent']:+.1f} % |", "",
             "The linearised closed form of the targets alone: neighbours a·1.5e-4·√2 = 8.94 km, opposite "
             "satellites a·3e-4 = 12.65 km apart at least (`relative_motion.md`); the controllers' errors and the "
             "forces' pull on the vectors between burns take the rest."]
    if args.clusters < 64:
        lines += ["", f"{args.clusters} clusters, not the study's 64: the run's time on 2 shared CPU cores. The "
                  f"full study: `{data['command'].replace(f'--clusters {args.clusters}', '--clusters 64')}`."]
    (args.out / f"{name}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
