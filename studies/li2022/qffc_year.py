"""One year of QFFC station keeping on li2022 (normal limits), beside Li 2022 Table 2.

    python studies/li2022/qffc_year.py [--limits normal|weak|strong] [--out studies/li2022/results]

Runs the li2022-qffc scenario with the arm limits of Table 1 and writes a
Markdown table beside the paper's numbers and the station-keeping figure.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from geojax import plots, run, scenario
from geojax.propulsion import PRESETS_DEG


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limits", choices=sorted(PRESETS_DEG), default="normal")
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = parser.parse_args()
    beta_max, beta_min, alpha_max, alpha_min = PRESETS_DEG[args.limits]
    sc = scenario.load("li2022-qffc", {
        "duration.days": args.days, "thrusters.beta_max_deg": beta_max, "thrusters.beta_min_deg": beta_min,
        "thrusters.alpha_max_deg": alpha_max, "thrusters.alpha_min_deg": alpha_min,
    })
    result = run.simulate_scenario(sc)
    m, c = result.metrics, result.cycles
    after = slice(3, None)  # after acquisition
    rows = [
        ("ΔV per year (m/s/yr)", f"{m['dv_per_year_mps']:.1f}", "60.2"),
        ("burns per thruster per orbit", f"{m['burns_per_thruster_per_orbit']:.3f}", "0.997"),
        ("burns in total", f"{int(m['burns_total'])}", "728"),
        ("max abs(mean λ − 96°) after 3 cycles (°)", f"{np.max(np.abs(c['lon_deg'][after] - 96)):.4f}", "≈ 0.013"),
        ("max norm(mean e − e_T)", f"{m['max_abs_de']:.2e}", "≈ 1.1e-4"),
        ("max norm(mean i − i_T), (h, k), after 3 cycles",
         f"{np.max(np.hypot(c['ix'][after] - 0.0, c['iy'][after] - 3e-5)):.2e}", "–"),
        ("mean pitch β̄, eq. (46) (°)", f"{m['mean_beta_deg']:.1f}", "at the 70° ceiling most of the time"),
        ("cycles with no QFFC solution", f"{int(m['cycles_without_solution'])}", "–"),
        ("wall time, 1 CPU sample (s)", f"{result.wall_s:.1f}", "0.09 s per orbit (Fortran)"),
    ]
    lines = [f"# li2022, QFFC, {args.limits} limits, {len(c['t_s'])} cycles", "",
             "`python studies/li2022/qffc_year.py`; no orbit or attitude errors.", "",
             "| quantity | geojax | Li 2022 (Table 2, Sec. 5.1) |", "|---|---|---|"]
    lines += [f"| {a} | {b} | {p} |" for a, b, p in rows]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"qffc_year_{args.limits}.md").write_text("\n".join(lines) + "\n")
    plots.plot_station_keeping(c, result.reference, result.target, out / f"qffc_year_{args.limits}.png",
                               f"li2022, QFFC, {args.limits} limits")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
