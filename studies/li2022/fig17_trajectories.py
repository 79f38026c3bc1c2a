"""Li 2022 Fig. 17: the (δλ, δφ) trajectories at the largest determination error the station keeping survives.

    python studies/li2022/fig17_trajectories.py [--days D]

Reads the Fig. 16 sweep (``results/fig16_h_rv.h5``; run ``fig16_h_rv.py`` first) and, per controller,
takes the largest H_rv at which every one of its repetitions kept the ±0.05° box at every step (status
0 or 1); Li's is H_rv = 800, where "the station keeping becomes unstable after H_rv exceeds 800".  The
sweep's first repetition at that level is flown again, one year, with the sweep's own key
(``fold_in(key(seed), sample index)``), keeping every step, and its sub-satellite track is drawn in the
box beside the same controller without errors (Li's Fig. 4).  The longitude and latitude half-ranges are
printed beside Li's (±0.025° QFFC, ±0.030° FOMPC; latitude "hardly changes").  The re-flown ΔV is set
beside the sweep's record of the same sample: they agree to rounding (the sweep compiled its lanes, this
one), except where the FOMPC's annealing takes another path on a last-bit difference.
Writes ``results/fig17_trajectories.png`` and ``.md``.

    python studies/li2022/fig17_trajectories.py --level 800

flies Li's own level instead, without the sweep's results file: the first repetition of each controller at
H_rv = ``--level`` of ``sweeps/fig16_h_rv.toml`` (the sweep's key for it), beside the same controller without
errors; writes ``results/fig17_at_h_rv_<level>.png`` and ``.md``.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import jax
import numpy as np

from geojax import open_results, plots, simulate, sweep
from geojax.loop.metrics import step_table

HERE = Path(__file__).parent
LI_LON_HALF_RANGE_DEG = {"qffc": 0.025, "fompc": 0.030}
LI_LEVEL = 800.0
BOX_DEG = 0.05


def largest_stable_level(ds, controller: str, mean_longitude: bool = False) -> tuple[float, int]:
    """(H_rv, its grid index): the largest level whose every repetition kept the box at every step (status 0
    or 1), or (``mean_longitude``) kept its one-cycle mean longitude within it (Li's figure of merit)."""
    if mean_longitude:
        ok = np.all(ds.max_abs_mean_dlon_deg.sel(controller=controller).values <= BOX_DEG, axis=-1)
    else:
        ok = np.all(ds.status.sel(controller=controller).values <= 1, axis=-1)  # [level, repetition]
    levels = ds["errors.h_rv"].values
    if not ok.any():
        raise SystemExit(f"{controller}: no level of the Fig. 16 sweep kept the box")
    k = int(np.flatnonzero(ok)[-1])
    return float(levels[k]), k


def fly(spec, controller: str, level: float, k: int, days: float | None):
    """The sweep's repetition 0 at grid index ``k``, one run with every step kept."""
    point = {"errors.h_rv": level, **({"duration.days": days} if days else {})}
    sc = sweep._scenario(spec, controller, point)
    key = jax.random.fold_in(jax.random.key(spec.seed), k * spec.repetitions)
    result = simulate(sc, key=key, keep_steps=True)
    steps = step_table(result.records, result.step_s, float(result.params.station["lon_rad"]))
    return result, steps


@plots.styled
def draw(tracks: dict, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(7.2, 3.6), constrained_layout=True, sharex=True, sharey=True)
    for ax, (controller, runs) in zip(axes, tracks.items()):
        for label, steps, style in runs:
            ax.plot(steps["dlon_deg"], steps["lat_deg"], style, lw=0.3, label=label)
        ax.plot([-BOX_DEG, BOX_DEG, BOX_DEG, -BOX_DEG, -BOX_DEG], [-BOX_DEG, -BOX_DEG, BOX_DEG, BOX_DEG, -BOX_DEG],
                "k--", lw=0.8, label=f"box ±{BOX_DEG}°")
        ax.set(title=controller.upper(), xlabel="δλ (deg)", ylabel="δφ (deg)", aspect="equal",
               xlim=(-1.2 * BOX_DEG, 1.2 * BOX_DEG), ylim=(-1.2 * BOX_DEG, 1.2 * BOX_DEG))
        ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.08), ncol=1, fontsize="small", frameon=False)
    return plots._save(fig, list(axes), "Li 2022 Fig. 17: at the largest stable determination error", path)


def at_level(level: float, days: float | None, out: Path) -> None:
    """Li's Fig. 17 at his own H_rv: each controller's first repetition at ``level`` beside no errors."""
    spec = sweep.load(HERE / "sweeps" / "fig16_h_rv.toml")
    grid = list(spec.grid["errors.h_rv"])
    if level not in grid:
        raise SystemExit(f"--level: must be one of the Fig. 16 grid's H_rv {grid}, got {level:g}")
    k = grid.index(level)
    rows, tracks = [], {}
    for controller in ("qffc", "fompc"):
        clean, clean_steps = fly(spec, controller, 0.0, 0, days)
        noisy, noisy_steps = fly(spec, controller, level, k, days)
        m, m0 = noisy.metrics, clean.metrics
        rows.append(f"| {controller.upper()} | {level:g} | ±{float(m['dlon_half_range_deg']):.4f}° "
                    f"(Li ±{LI_LON_HALF_RANGE_DEG[controller]:.3f}°) | ±{float(m0['dlon_half_range_deg']):.4f}° | "
                    f"{float(m['max_abs_mean_dlon_deg']):.4f}° | ±{float(m['dlat_half_range_deg']):.4f}° | "
                    f"±{float(m0['dlat_half_range_deg']):.4f}° | {float(m['dv_per_year_mps']):.2f} | {int(noisy.status)} |")
        print(rows[-1], flush=True)
        tracks[controller] = [(f"H_rv = {level:g}", noisy_steps, "C3-"), ("no errors", clean_steps, "C0-")]
    name = f"fig17_at_h_rv_{level:g}"
    figure = draw(tracks, out / f"{name}.png")
    lines = [f"# Li 2022 Fig. 17 at Li's level, H_rv = {level:g}", "",
             f"`python studies/li2022/fig17_trajectories.py --level {level:g}`: the first repetition of each "
             f"controller at H_rv = {level:g} of `sweeps/fig16_h_rv.toml` (its key), "
             f"{f'{days:g} days' if days else 'one year'}, every step kept, beside the same "
             "controller without errors. Half-ranges: half of (max − min) of the osculating sub-satellite point, "
             "acquisition included; mean δλ: the largest one-cycle mean longitude offset (Li's measure).", "",
             "| controller | H_rv | δλ half-range | δλ without errors | largest mean δλ | δφ half-range | "
             "δφ without errors | ΔV (m/s/yr) | status |", "|---|---|---|---|---|---|---|---|---|", *rows, "",
             "Li: \"the control accuracy of the longitude has risen to ±0.025° for the QFFC and ±0.030° for the "
             "FOMPC. However, that of the latitude hardly changes\".", ""]
    (out / f"{name}.md").write_text("\n".join(lines))
    print(f"wrote {figure} and {out / f'{name}.md'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, help="simulated days (default: the sweep's, one year)")
    parser.add_argument("--level", type=float, help="fly this H_rv of the Fig. 16 grid (Li's: 800), no sweep file")
    parser.add_argument("--out", default=str(HERE / "results"))
    args = parser.parse_args()
    out = Path(args.out)
    if args.level is not None:
        at_level(args.level, args.days, out)
        return
    results_file = out / "fig16_h_rv.h5"
    if not results_file.is_file():
        raise SystemExit(f"{results_file}: not found; run `python studies/li2022/fig16_h_rv.py` first")
    ds = open_results(results_file)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "fig16.toml").write_text(ds.attrs["config_toml"])
        spec = sweep.load(Path(tmp) / "fig16.toml")
    rows, tracks = [], {}
    for controller in ("qffc", "fompc"):
        clean, clean_steps = fly(spec, controller, 0.0, 0, args.days)
        m0 = clean.metrics
        for criterion, mean_longitude in (("every step", False), ("mean longitude (Li's)", True)):
            level, k = largest_stable_level(ds, controller, mean_longitude)
            noisy, noisy_steps = fly(spec, controller, level, k, args.days)
            recorded = float(ds.dv_per_year_mps.sel(controller=controller).values[k, 0])
            m = noisy.metrics
            rows.append(f"| {controller.upper()} | {criterion} | {level:g} (Li: {LI_LEVEL:g}) | "
                        f"±{float(m['dlon_half_range_deg']):.4f}° (Li ±{LI_LON_HALF_RANGE_DEG[controller]:.3f}°) | "
                        f"±{float(m0['dlon_half_range_deg']):.4f}° | ±{float(m['dlat_half_range_deg']):.4f}° | "
                        f"±{float(m0['dlat_half_range_deg']):.4f}° | {float(m['dv_per_year_mps']):.2f} "
                        f"(sweep record {recorded:.2f}) | {int(noisy.status)} |")
            print(rows[-1], flush=True)
            if not mean_longitude:
                tracks[controller] = [(f"H_rv = {level:g}", noisy_steps, "C3-"), ("no errors", clean_steps, "C0-")]
    figure = draw(tracks, out / "fig17_trajectories.png")
    lines = ["# Li 2022 Fig. 17: trajectories at the largest stable determination error", "",
             "`python studies/li2022/fig17_trajectories.py`: per controller, the largest H_rv of the Fig. 16 sweep "
             "at which every repetition kept the ±0.05° box at every step (and, second row, kept its one-cycle mean "
             "longitude in it, Li's measure); its first repetition flown again for "
             "one year with the sweep's key, every step kept; beside it the same controller without errors "
             "(Li's Fig. 4). Half-ranges are half of (max − min) of the osculating sub-satellite point over the "
             "whole run, acquisition included.", "",
             "| controller | stable by | largest stable H_rv | δλ half-range there | δλ without errors | "
             "δφ half-range there | δφ without errors | ΔV (m/s/yr) | status |", "|---|---|---|---|---|---|---|---|---|",
             *rows, "",
             "The figure shows the every-step level. Status 2: the sub-satellite point left ±0.05° at some step "
             "(the mean longitude, Li's measure, did not).", "",
             "Li: \"the control accuracy of the longitude has risen to ±0.025° for the QFFC and ±0.030° for the "
             "FOMPC. However, that of the latitude hardly changes\".", ""]
    (out / "fig17_trajectories.md").write_text("\n".join(lines))
    print(f"wrote {figure} and {out / 'fig17_trajectories.md'}")


if __name__ == "__main__":
    main()
