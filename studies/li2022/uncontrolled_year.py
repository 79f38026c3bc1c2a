"""One uncontrolled year of li2022 (2020): mean-element drift and its convergence with the step.

    python studies/li2022/uncontrolled_year.py [--out studies/li2022/results]

Runs the li2022 scenario for 365.25 days with MEE RK4 at several steps and
with Cartesian RK4 at 30 s (a second formulation, converged), and writes a
Markdown table of the one-year change of the mean inclination vector, the
largest excursion of the mean eccentricity vector and the mean longitude drift.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from geojax import plots, scenario
from geojax import uncontrolled as run

CASES = [("mee", 7200.0), ("mee", 3600.0), ("mee", 1800.0), ("mee", 900.0), ("mee", 300.0), ("cartesian", 30.0)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(Path(__file__).parent / "results"))
    out = Path(parser.parse_args().out)
    rows = []
    for dynamics, step in CASES:
        sc = scenario.load("li2022", {"integration.dynamics": dynamics, "integration.step_s": step})
        result = run.propagate_scenario(sc, progress=False)
        s = run.drift_summary(result.cycles, sc.days)
        rows.append((dynamics, result.step_s, s, result.wall_s))
        print(f"{dynamics:9s} {result.step_s:7.1f} s  di {s.di_deg:.6f} deg @ {s.di_direction_deg:.3f} deg  "
              f"de_max {s.de_max:.4e}  dlon {s.dlon_deg:+.5f} deg  ({result.wall_s:.1f} s)")
        if (dynamics, step) == ("mee", 900.0):
            plots.plot_cycles(run.cycles_table(result.cycles), out / "uncontrolled_year.png", "li2022, 2020, no control")
    ref = rows[-1][2]
    lines = [
        "# li2022: one uncontrolled year (2020-01-01 12:00 UTC + 365.25 d)",
        "",
        "Force model of Li 2022 eq. (3): J2, Sun, Moon (Meeus), SRP with conical shadow.",
        "Changes are between one-cycle means (eq. (9)) 365.25 days apart; the last row is the reference.",
        "",
        "| dynamics | step (s) | |Δi| (deg) | Δi direction (deg) | max |e − e0| | Δλ (deg) | |Δi| − ref (deg) | Δλ − ref (deg) | wall (s) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for dynamics, step, s, wall in rows:
        lines.append(
            f"| {dynamics} | {step:.1f} | {s.di_deg:.6f} | {s.di_direction_deg:.4f} | {s.de_max:.5e} | {s.dlon_deg:+.5f} "
            f"| {s.di_deg - ref.di_deg:+.1e} | {s.dlon_deg - ref.dlon_deg:+.1e} | {wall:.1f} |"
        )
    out.mkdir(parents=True, exist_ok=True)
    (out / "uncontrolled_year.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'uncontrolled_year.md'}")


if __name__ == "__main__":
    main()
