"""One year of QFFC and FOMPC station keeping on li2022, beside Li 2022 Table 2 and Figs. 2-8.

    python studies/li2022/one_year.py [--limits normal|weak|strong] [--days 365.25] [--seed 0]
                                      [--out studies/li2022/results]

Runs li2022-qffc and li2022-fompc with the arm limits of Table 1 (no orbit or
attitude errors, as in the paper's first simulation), and writes
``one_year_<limits>.md`` (the table), ``one_year_<limits>_<controller>.png``
(the station-keeping figure of each run) and ``one_year_<limits>_ns.png``
(Figs. 7-8: half-year Delta-V_NS and mean pitch of both controllers).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from types import SimpleNamespace  # noqa: E402

import geojax  # noqa: E402
from geojax import plots, scenario  # noqa: E402
from geojax.runner.report import reference_and_target  # noqa: E402
from geojax.papers import LI2022 as PAPER  # noqa: E402  (Sec. 5.1 and Table 2, normal limits)
from geojax.physics.propulsion import PRESETS_DEG  # noqa: E402

AFTER = slice(3, None)  # after acquisition (the initial i is 2e-5 off its target)


def run_year(controller: str, limits: str, days: float, seed: int):
    beta_max, beta_min, alpha_max, alpha_min = PRESETS_DEG[limits]
    sc = scenario.load(f"li2022-{controller}", {
        "duration.days": days, "thrusters.beta_max_deg": beta_max, "thrusters.beta_min_deg": beta_min,
        "thrusters.alpha_max_deg": alpha_max, "thrusters.alpha_min_deg": alpha_min,
    })
    result = geojax.simulate(sc, seed)
    # The summaries read Li 2022's mean-longitude figure of merit under its old name.
    metrics = {k: float(v) for k, v in result.metrics.items()}
    metrics["max_abs_dlon_deg"] = metrics["max_abs_mean_dlon_deg"]
    metrics["cpu_s_per_orbit"] = result.wall_s / len(result.records.cycles.dv_mps)  # as geojax simulate reports it
    reference, target = reference_and_target(sc, len(result.records.cycles.dv_mps))
    return SimpleNamespace(metrics=metrics, cycles=result.cycles(), reference=reference, target=target,
                           wall_s=result.wall_s)


def rows(results) -> list[tuple[str, ...]]:
    q, f = results["qffc"], results["fompc"]
    saving = 1 - f.metrics["dv_per_year_mps"] / q.metrics["dv_per_year_mps"]

    def lon(r):
        return f"{np.max(np.abs(r.cycles['lon_deg'][AFTER] - r.target['lon_deg'])):.4f}"

    def di(r):
        c = r.cycles
        return f"{np.max(np.hypot(c['ix'][AFTER] - r.target['ix'], c['iy'][AFTER] - r.target['iy'])):.2e}"

    m = lambda r, k, fmt: format(r.metrics[k], fmt)  # noqa: E731
    about = lambda value: value.replace("~", "≈ ")  # noqa: E731  (read off a figure)
    return [
        ("ΔV per year (m/s/yr)", m(q, "dv_per_year_mps", ".1f"), PAPER["qffc"]["dv_per_year_mps"], m(f, "dv_per_year_mps", ".1f"), PAPER["fompc"]["dv_per_year_mps"]),
        ("FOMPC saving against the QFFC", "", "", f"{100 * saving:.1f} %", "10.0 %"),
        ("north-south ΔV, eq. (45) (m/s/yr)", f"{_per_year(q, 'dv_ns_mps'):.1f}", "–", f"{_per_year(f, 'dv_ns_mps'):.1f}", "–"),
        ("burns in total", m(q, "burns_total", ".0f"), PAPER["qffc"]["burns_total"], m(f, "burns_total", ".0f"), PAPER["fompc"]["burns_total"]),
        ("burns per thruster per orbit", m(q, "burns_per_thruster_per_orbit", ".3f"), PAPER["qffc"]["burns_per_thruster_per_orbit"],
         m(f, "burns_per_thruster_per_orbit", ".3f"), PAPER["fompc"]["burns_per_thruster_per_orbit"]),
        ("max abs(mean λ − 96°) after 3 cycles (°)", lon(q), about(PAPER["qffc"]["max_abs_mean_dlon_deg"]), lon(f),
         about(PAPER["fompc"]["max_abs_mean_dlon_deg"])),
        ("max norm(mean e − e_T)", m(q, "max_abs_de", ".2e"), about(PAPER["qffc"]["max_abs_de"]), m(f, "max_abs_de", ".2e"),
         about(PAPER["fompc"]["max_abs_de"])),
        ("max norm(mean i − i_T), MEE (h, k), after 3 cycles", di(q), "–", di(f), "Δi_max = 8e-5"),
        ("mean pitch β̄, eq. (46) (°)", m(q, "mean_beta_deg", ".1f"), "near 70° most of the time",
         m(f, "mean_beta_deg", ".1f"), "near 70° most of the time"),
        ("cycles with no solution", m(q, "cycles_without_solution", ".0f"), "–", m(f, "cycles_without_solution", ".0f"), "–"),
        ("wall s per orbit, 1 sample, incl. compilation", m(q, "cpu_s_per_orbit", ".3f"), PAPER["qffc"]["cpu_s_per_orbit"],
         m(f, "cpu_s_per_orbit", ".3f"), PAPER["fompc"]["cpu_s_per_orbit"]),
    ]


def _per_year(result, name: str) -> float:
    n = len(result.cycles["t_s"])
    return float(np.sum(result.cycles[name])) * 365.25 * 86400 / (n * 86164.0905)


@plots.styled
def plot_ns(results, path: Path, title: str) -> Path:
    """Li 2022 Figs. 7-8: Delta-V_NS per cycle and mean pitch over the first half-year, both controllers."""
    fig, axes = plt.subplots(2, 1, figsize=(10, 7), constrained_layout=True)
    for controller, style in (("qffc", "r-"), ("fompc", "b-")):
        c = results[controller].cycles
        days = np.asarray(c["t_s"]) / 86400.0
        half = days <= 182.6
        v = c["v1_mps"] + c["v2_mps"]
        beta = np.degrees(np.arcsin(np.clip(c["dv_ns_mps"] / np.where(v > 0, v, 1.0), 0, 1)))
        axes[0].plot(days[half], c["dv_ns_mps"][half], style, lw=0.8, label=controller.upper())
        axes[1].plot(days[half & (v > 0)], beta[half & (v > 0)], style, lw=0.8, label=controller.upper())
    axes[0].set(xlabel="days", ylabel="ΔV_NS per cycle (m/s), eq. (45)")
    axes[1].set(xlabel="days", ylabel="mean pitch β̄ (deg), eq. (46)")
    for a in axes:
        a.legend()
    return plots._save(fig, axes, title, path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limits", choices=sorted(PRESETS_DEG), default="normal")
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--seed", type=int, default=0, help="seed of the FOMPC's annealing")
    parser.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = parser.parse_args()
    out = Path(args.out)
    results = {}
    for controller in ("qffc", "fompc"):
        print(f"{controller}: {args.days:g} days, {args.limits} limits ...", flush=True)
        results[controller] = run_year(controller, args.limits, args.days, args.seed)
        title = f"li2022, {controller.upper()}, {args.limits} limits"
        plots.plot_station_keeping(results[controller].cycles, results[controller].reference,
                                   results[controller].target, out / f"one_year_{args.limits}_{controller}.png", title,
                                   box_half_width_deg=0.05)
    plot_ns(results, out / f"one_year_{args.limits}_ns.png", f"li2022, {args.limits} limits: Li 2022 Figs. 7-8")
    n = len(results["qffc"].cycles["t_s"])
    lines = [f"# li2022, QFFC and FOMPC, {args.limits} limits, {n} cycles", "",
             f"`python studies/li2022/one_year.py --limits {args.limits}`; no orbit or attitude errors; "
             f"FOMPC N = 6, Δi_max = 8e-5, annealing seed {args.seed}. Li 2022 values are for the normal limits.", "",
             "| quantity | QFFC geojax | QFFC Li 2022 | FOMPC geojax | FOMPC Li 2022 |", "|---|---|---|---|---|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows(results)]
    out.mkdir(parents=True, exist_ok=True)
    (out / f"one_year_{args.limits}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
