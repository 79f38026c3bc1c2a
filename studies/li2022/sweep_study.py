"""Li 2022 Figs. 9-16: the Monte Carlo sweeps, shared by the ``fig*.py`` scripts of this folder.

Each figure script names its sweep files (``sweeps/*.toml``), the values the
paper states and a function that reads the matching finding off our results.
Running a script runs its sweeps with ``geojax.sweep`` (resumable: run it again
after an interruption and it continues), then writes into ``results/``:

* ``<sweep>.h5``: the sweep results (``geojax plot`` draws them too);
* ``<figure>.png``: ΔV per year against the swept parameter, mean and min-max
  band over the repetitions, one line per controller, unstable points crossed;
* ``<figure>.md``: the table of means ± standard deviations with the paper's
  stated values beside ours, and the paper's claims beside what we find.

``--reps R`` and ``--days D`` change the repetitions and the simulated span for
a quick look (results then go to ``<sweep>-r<R>-d<D>.h5`` and the report says so).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
import warnings
from pathlib import Path
from typing import Callable

import numpy as np

from geojax import plots, store, sweep
from geojax.loop.metrics import STATUS_LEFT_LON_BOX
from geojax.parallel import use_host_cores

HERE = Path(__file__).parent
CONTROLLERS = ("qffc", "fompc")
LI_BOX_DEG = 0.05


@dataclasses.dataclass(frozen=True)
class Summary:
    """One sweep's ΔV per year, by controller and grid value (the first and only grid axis)."""

    name: str
    x: np.ndarray  # [n] swept values
    mean: dict  # {controller: [n]} over the stable repetitions (NaN where none is stable)
    std: dict  # {controller: [n]}
    unstable: dict  # {controller: [n]} count of repetitions that left the box
    no_solution: dict  # {controller: [n]} count of repetitions with cycles the controller could not solve
    mean_lon_out: dict  # {controller: [n]} count whose one-cycle mean longitude left the box (Li's figure of merit)
    reps: int
    wall_s: float


@dataclasses.dataclass(frozen=True)
class Figure:
    name: str  # "fig09_beta_max"
    title: str
    sweeps: tuple[str, ...]  # sweep files in sweeps/, one line set each
    claims: tuple[str, ...]  # what the paper says, quoted or paraphrased
    findings: Callable[[list[Summary]], list[str]]  # what we find, one line per claim
    paper_values: dict = dataclasses.field(default_factory=dict)  # {x: {controller: m/s/yr}} stated in the text
    labels: tuple[str, ...] = ("",)  # legend prefix per sweep


def main(figure: Figure, argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=f"Li 2022 {figure.title}: sweep, table and figure")
    parser.add_argument("--reps", type=int, help="repetitions per grid point (default: the sweep file's, 20)")
    parser.add_argument("--days", type=float, help="simulated days per sample (default: one year)")
    parser.add_argument("--chunk", type=int, help="samples per saved chunk (default: geojax.sweep's)")
    parser.add_argument("--out", default=str(HERE / "results"), help="results folder (default: studies/li2022/results)")
    args = parser.parse_args(argv)
    use_host_cores()
    out = Path(args.out)
    changes = {}
    if args.reps is not None:
        changes["repetitions"] = args.reps
    if args.days is not None:
        changes["set"] = {"duration.days": args.days}
    suffix = "".join(f"-{k}{v:g}" for k, v in (("r", args.reps), ("d", args.days)) if v is not None)
    summaries, runs = [], []
    for file, label in zip(figure.sweeps, figure.labels * len(figure.sweeps) if len(figure.labels) == 1 else figure.labels):
        spec = sweep.load(HERE / "sweeps" / file, changes)
        path = out / f"{spec.name}{suffix}.h5"
        print(f"{spec.name}: {len(spec.controllers)} controllers x {spec.n_points} points x {spec.repetitions} reps "
              f"-> {path}", flush=True)
        start = time.perf_counter()
        sweep.run_sweep(spec, path, resume=True, chunk=args.chunk)
        print(f"  {time.perf_counter() - start:.0f} s this run", flush=True)
        groups, attrs = store.read_h5(path)
        summaries.append(summarise(spec.name, groups, attrs))
        runs.append((label, groups))
    param = next(iter(spec.grid))
    png = plots.plot_sweeps(runs, ["controller", param], out / f"{figure.name}{suffix}.png",
                            title=f"Li 2022 {figure.title}" + (f" ({suffix[1:]})" if suffix else ""))
    md = out / f"{figure.name}{suffix}.md"
    md.write_text(report(figure, summaries, param, suffix))
    print(md.read_text())
    print(f"wrote {md} and {png}")


def summarise(name: str, groups, attrs) -> Summary:
    dv = np.asarray(groups["metrics"]["dv_per_year_mps"])  # [controller, n, reps]
    status = np.asarray(groups["status"]["code"])
    controllers = [c.decode() for c in groups["grid"]["controller"]]
    x = next(v for k, v in groups["grid"].items() if k != "controller")
    unstable = status >= STATUS_LEFT_LON_BOX  # left the longitude or latitude box, diverged, or ran dry
    stable = np.where(unstable, np.nan, dv)
    with warnings.catch_warnings():  # a point whose every repetition is unstable has no mean
        warnings.simplefilter("ignore", RuntimeWarning)
        mean, std = np.nanmean(stable, axis=-1), np.nanstd(stable, axis=-1)
    by = lambda a: {c: a[i] for i, c in enumerate(controllers)}  # noqa: E731
    return Summary(name, np.asarray(x), by(mean), by(std), by(np.sum(unstable, axis=-1)),
                   by(np.sum(np.asarray(groups["metrics"]["cycles_without_solution"]) > 0, axis=-1)),
                   by(np.sum(np.asarray(groups["metrics"]["max_abs_mean_dlon_deg"]) > LI_BOX_DEG, axis=-1)),
                   dv.shape[-1], float(attrs["wall_s"]))


def report(figure: Figure, summaries: list[Summary], param: str, suffix: str) -> str:
    lines = [f"# Li 2022 {figure.title}", ""]
    if suffix:
        lines += [f"Quick run ({suffix[1:]}): not the paper's 20 one-year repetitions.", ""]
    command = f"python studies/li2022/{figure.name}.py" + (f" {_flags(suffix)}" if suffix else "")
    lines += [f"`{command}`; sweep files `studies/li2022/sweeps/"
              f"{{{','.join(figure.sweeps)}}}`. ΔV per year (m/s/yr), mean ± standard deviation over the "
              "repetitions that stayed in the ±0.05° box; 'unstable' counts the repetitions that left it in longitude "
              "or latitude at any step, diverged or ran out of propellant (status 2 to 5), "
              "'no sol.' those with cycles the controller could not solve.", ""]
    for s in summaries:
        lines += [f"## {s.name} ({s.reps} repetitions, {s.wall_s:.0f} s wall)", "",
                  f"| {param} | QFFC | unstable / no sol. | FOMPC | unstable / no sol. | Li 2022 QFFC | Li 2022 FOMPC |",
                  "|---:|---:|---:|---:|---:|---:|---:|"]
        for j, x in enumerate(s.x):
            paper = figure.paper_values.get(float(x), {})
            cells = []
            for c in CONTROLLERS:
                cells += [_mean_std(s.mean[c][j], s.std[c][j]), f"{s.unstable[c][j]} / {s.no_solution[c][j]}"]
            cells += [str(paper.get(c, "")) for c in CONTROLLERS]
            lines.append(f"| {x:g} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += ["## The paper's claims and what we find", "", "| Li 2022 | geojax |", "|---|---|"]
    lines += [f"| {claim} | {found} |" for claim, found in zip(figure.claims, figure.findings(summaries), strict=True)]
    return "\n".join(lines) + "\n"


def _flags(suffix: str) -> str:
    parts = [p for p in suffix.split("-") if p]
    return " ".join(f"--{'reps' if p[0] == 'r' else 'days'} {p[1:]}" for p in parts)


def _mean_std(mean: float, std: float) -> str:
    return "–" if not np.isfinite(mean) else f"{mean:.2f} ± {std:.2f}"


# Helpers the figure scripts use to read findings off the summaries.

def value_at(s: Summary, controller: str, x: float) -> float:
    return float(s.mean[controller][np.argmin(np.abs(s.x - x))])


def first_unstable(s: Summary, controller: str, mean_longitude: bool = False) -> str:
    """The smallest grid value with a repetition out of the box (status 2 to 5), or with ``mean_longitude``
    whose one-cycle mean longitude left Li's +-0.05 deg (the criterion before status moved into the rollout)."""
    bad = s.x[(s.mean_lon_out if mean_longitude else s.unstable)[controller] > 0]
    return "none" if bad.size == 0 else f"{bad.min():g}"


def relative_change(s: Summary, controller: str, reference_x: float) -> np.ndarray:
    """ΔV at each grid value relative to that at ``reference_x`` (fraction)."""
    return s.mean[controller] / value_at(s, controller, reference_x) - 1.0


def yaw_limit_figure(which: str) -> Figure:
    """Figs. 11 and 12 (α_max, α_min): the same study by the symmetry of the arms (Li 2022, Sec. 5.1)."""
    number = {"max": 11, "min": 12}[which]

    def findings(summaries):
        (s,) = summaries
        out = []
        for c in CONTROLLERS:
            unstable = s.x[s.unstable[c] > 0]
            above = relative_change(s, c, 90.0)[s.x >= 45]
            out.append(f"{c.upper()}: unstable at α_{which} = {', '.join(f'{x:g}' for x in unstable) or 'none'}; "
                       f"from 45° up ΔV within {100 * np.nanmax(np.abs(above)):.1f} % of α_{which} = 90°")
        return [" ; ".join(out)]

    return Figure(
        f"fig{number}_alpha_{which}", f"Fig. {number} (α_{which})", (f"fig{number}_alpha_{which}.toml",),
        (f"a restricted range of small α_{which} where the controllers cannot operate stably; outside it the "
         "influence declines fast and is negligible from 45°",),
        findings,
    )
