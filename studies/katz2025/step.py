"""Step size of the Katz 2025 feedback loop: one year per thrust mode at 450, 900, 1800 and 3600 s.

    python studies/katz2025/step.py [--out studies/katz2025/results]

The law is sampled at each step and held over it (``geojax.feedback``), so the
step sets both the integration error and the control sampling.  Writes
``step.md`` and ``step.json``: Delta-V per year and the largest excursions at
each step, with the differences from the finest step.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from geojax import scenario
from table import simulate_feedback  # this folder: one run with its per-step records

STEPS_S = (450.0, 900.0, 1800.0, 3600.0)
MODES = ("continuous", "discrete", "constant")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(Path(__file__).resolve().parent / "results"))
    out = Path(parser.parse_args().out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for mode in MODES:
        for step in STEPS_S:
            result = simulate_feedback(scenario.load(f"katz2025-{mode}", {"integration.step_s": step}))
            rows.append({"mode": mode, "step_s": step, **result.metrics, "wall_s": result.wall_s})
            print(rows[-1], flush=True)
    (out / "step.json").write_text(json.dumps(rows, indent=1))
    lines = ["# Step size of the feedback loop (one year, Katz's gains)", "",
             "`python studies/katz2025/step.py`; differences from the 450 s run in brackets.", "",
             "| mode | step s | ΔV m/s/yr | max abs Δλ deg | max abs δ deg | duty z |", "|---|---:|---:|---:|---:|---:|"]
    for r in rows:
        ref = next(x for x in rows if x["mode"] == r["mode"] and x["step_s"] == STEPS_S[0])
        d = lambda k: r[k] - ref[k]  # noqa: E731
        lines.append(f"| {r['mode']} | {r['step_s']:.0f} | {r['dv_per_year_mps']:.3f} ({d('dv_per_year_mps'):+.3f}) | "
                     f"{r['max_abs_dlon_deg']:.4f} ({d('max_abs_dlon_deg'):+.4f}) | "
                     f"{r['max_abs_dlat_deg']:.4f} ({d('max_abs_dlat_deg'):+.4f}) | {r['duty_z']:.3f} |")
    (out / "step.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
