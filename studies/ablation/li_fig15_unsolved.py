"""The Fig. 15 runs with unsolved cycles -- do the cycles go unsolved before or after the box is left?

    python studies/ablation/li_fig15_unsolved.py [--levels 300] [--sweeps fig15_h_att fig15_h_att_known]

Reads the Fig. 15 sweeps (``studies/li2022/results/<sweep>.h5``; run ``studies/li2022/fig15_h_att.py`` first),
takes every repetition at the given H_att levels whose record counts cycles without a solution, and flies it
again with the sweep's own key (``fold_in(key(seed), level index x repetitions + repetition)``, as
``studies/li2022/fig17_trajectories.py``), keeping its cycles: the first cycle whose osculating sub-satellite
longitude left the +-0.05 deg box, the first unsolved cycle, how many, and the one-cycle mean drift and longitude
offset at the first unsolved cycle.  Where every first unsolved cycle comes after the first cycle out of the
box, the unsolved cycles are a consequence of the drift walk that takes the satellite out (the mechanism
measured in ``li_attitude_error.md`` and tested in ``tests/test_attitude_error.py``), not a cause.
Writes ``studies/ablation/results/li_fig15_unsolved.md``.
"""

from __future__ import annotations

import os

os.environ.setdefault("XLA_FLAGS", f"--xla_force_host_platform_device_count={os.cpu_count() or 1}")

import argparse  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

import jax  # noqa: E402
import numpy as np  # noqa: E402

import geojax  # noqa: E402
from geojax import open_results, sweep  # noqa: E402
from geojax.physics.elements import wrap_angle  # noqa: E402

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent / "li2022" / "results"
BOX_DEG = 0.05


def spec_of(ds):
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "sweep.toml").write_text(ds.attrs["config_toml"])
        return sweep.load(Path(tmp) / "sweep.toml")


def refly(spec, controller: str, samples: list[tuple[int, int, float]]):
    """Fly (level index, repetition, H_att) ``samples`` of ``controller`` again in one batch; per-cycle arrays."""
    scenarios = [sweep._scenario(spec, controller, {"errors.h_att": level}) for _, _, level in samples]
    base = jax.random.key(spec.seed)
    keys = jax.numpy.stack([jax.random.fold_in(base, k * spec.repetitions + j) for k, j, _ in samples])
    result = geojax.simulate_batch(scenarios, keys=keys)
    c = result.records.cycles
    station = float(np.radians(scenarios[0].config["station"]["lon_deg"]))
    out = np.maximum(np.abs(np.asarray(c.dlon_min_rad)), np.abs(np.asarray(c.dlon_max_rad))) > np.radians(BOX_DEG)
    lat_out = np.maximum(np.abs(np.asarray(c.lat_min_rad)), np.abs(np.asarray(c.lat_max_rad))) > np.radians(BOX_DEG)
    mean_lon = np.degrees(np.asarray(wrap_angle(np.asarray(c.means.lon_rad) - station)))
    drift = np.degrees(np.asarray(c.means.drift_rad_s)) * 86400.0
    return {"out": out | lat_out, "solved": np.asarray(c.controller["solved"]), "mean_lon_deg": mean_lon,
            "drift_deg_day": drift, "dv": np.asarray(result.metrics["dv_per_year_mps"]),
            "status": np.asarray(result.status)}


def first(mask_row) -> int | None:
    idx = np.flatnonzero(mask_row)
    return int(idx[0]) if idx.size else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=float, nargs="+", default=[300.0])
    parser.add_argument("--sweeps", nargs="+", default=["fig15_h_att", "fig15_h_att_known"])
    parser.add_argument("--out", default=str(HERE / "results"))
    args = parser.parse_args()
    command = " ".join(["python studies/ablation/li_fig15_unsolved.py", *sys.argv[1:]])
    lines = ["# Li 2022 Fig. 15: the runs with unsolved cycles, flown again", "",
             f"`{command}`: every repetition of the Fig. 15 sweeps at H_att = "
             f"{', '.join(f'{x:g}' for x in args.levels)} whose record counts cycles without a solution, flown "
             "again with its sweep key, its cycles kept. 'Out': the first cycle (from 0) whose osculating "
             "sub-satellite point left ±0.05° in longitude or latitude; 'unsolved': the first cycle without a "
             "solution and their number; mean δλ, drift: the one-cycle mean longitude offset and drift at the first "
             "unsolved cycle. "
             "ΔV: re-flown (the sweep's record).", ""]
    verdicts = []
    for name in args.sweeps:
        path = RESULTS / f"{name}.h5"
        if not path.is_file():
            raise SystemExit(f"{path}: not found; run `python studies/li2022/fig15_h_att.py` first")
        ds = open_results(path)
        spec = spec_of(ds)
        grid = [float(x) for x in ds["errors.h_att"].values]
        lines += [f"## {name}", "", "| controller | H_att | repetition | out at cycle | first unsolved | unsolved | "
                  "mean δλ, drift there | ΔV m/s/yr | status |", "|---|---:|---:|---:|---:|---:|---|---|---:|"]
        for controller in spec.controllers:
            unsolved = ds.cycles_without_solution.sel(controller=controller).values  # [level, rep]
            samples = [(grid.index(level), int(j), level) for level in args.levels if level in grid
                       for j in np.flatnonzero(unsolved[grid.index(level)] > 0)]
            if not samples:
                lines.append(f"| {controller.upper()} | {', '.join(f'{x:g}' for x in args.levels)} | none | | | | | | |")
                verdicts.append(f"{name}, {controller.upper()}: no repetition with unsolved cycles")
                continue
            got = refly(spec, controller, samples)
            after = 0
            for i, (k, j, level) in enumerate(samples):
                out_at, unsolved_at = first(got["out"][i]), first(~got["solved"][i])
                after += out_at is not None and unsolved_at is not None and out_at <= unsolved_at
                there = "" if unsolved_at is None else (f"{got['mean_lon_deg'][i, unsolved_at]:+.4f}°, "
                                                        f"{got['drift_deg_day'][i, unsolved_at]:+.4f}°/day")
                recorded = float(ds.dv_per_year_mps.sel(controller=controller).values[k, j])
                lines.append(f"| {controller.upper()} | {level:g} | {j} | {out_at} | {unsolved_at} | "
                             f"{int((~got['solved'][i]).sum())} | {there} | {got['dv'][i]:.2f} ({recorded:.2f}) | "
                             f"{int(got['status'][i])} |")
            verdicts.append(f"{name}, {controller.upper()}: {len(samples)} repetition(s) with unsolved cycles, "
                            f"{after} of them out of the box at or before their first unsolved cycle")
        lines.append("")
    lines += ["## What the rows say", ""] + [f"- {v}." for v in verdicts]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "li_fig15_unsolved.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
