"""The missed-burn probability each controller holds its box at: a Monte Carlo per probability and controller.

    python studies/contingencies/missed_burns.py [--samples 100] [--days 365.25]
        [--probabilities 0,0.05,0.1,0.15,0.2,0.25,0.3] [--katz-probabilities P,...]
        [--controllers qffc,fompc,mpc,katz] [--out studies/contingencies/results]
    python studies/contingencies/missed_burns.py --merge A/missed_burns.json B/missed_burns.json [--note TEXT]

Each controller's shipped scenario (``li2022-qffc``, ``li2022-fompc``, ``li2022-mpc``: Li's arms, no errors;
``katz2025-discrete``: Katz's discrete law, whose "burn" is a cycle of firing) flown ``--days`` with every planned
burn lost with probability p (``faults.missed_burn_probability``, the faults part's own stream, seeds 0 .. samples
- 1; a lost burn is not known ahead, the next cycle's plan sees the orbit it left).  For each p: the fraction of
samples that keep the box at every step, the fraction of burns lost (``burns_missed`` / ``burns_planned``, against
p), and the mean Delta-V.  The threshold is the smallest p of the grid at which fewer than 99 % of the samples keep
the box (at 100 samples: two or more lost); with fewer than 100 samples that is the first p that loses any sample,
so the grid brackets it from below.  The results are written after every point (a long run stopped early keeps what
it measured), and ``--merge`` joins runs of parts of the grid (one controller, a finer grid) into one file.
Writes ``missed_burns.json`` and ``missed_burns.md`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.runner.rollout import simulate_batch

HERE = Path(__file__).resolve().parent
SCENARIOS = {"qffc": "li2022-qffc", "fompc": "li2022-fompc", "mpc": "li2022-mpc", "katz": "katz2025-discrete"}


def run_point(name: str, p: float, days: float, samples: int) -> dict:
    # enabled at every p (p = 0 too): the same compiled loop for the whole grid
    sc = scenario.load(SCENARIOS[name], {"duration.days": days, "faults.enabled": True,
                                         "faults.missed_burn_probability": p})
    begun = time.perf_counter()
    result = simulate_batch([sc] * samples, seeds=np.arange(samples))
    wall_s = time.perf_counter() - begun
    m = {k: np.asarray(v, float) for k, v in result.metrics.items()}
    status = np.asarray(result.status)
    return {"p": p, "kept": float(np.mean(status == 0)), "statuses": [int(s) for s in status],
            "lost_fraction": float(m["burns_missed"].sum() / max(m["burns_planned"].sum(), 1.0)),
            "burns_planned": float(m["burns_planned"].sum()),
            "dv_per_year_mps_mean": float(m["dv_per_year_mps"].mean()),
            "days_out_of_box_mean": float(m["days_out_of_box"].mean()), "wall_s": wall_s}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--probabilities", default="0,0.05,0.1,0.15,0.2,0.25,0.3")
    parser.add_argument("--katz-probabilities", default="",
                        help="Katz's law's own grid (default: --probabilities); it leaves the box without faults")
    parser.add_argument("--controllers", default="qffc,fompc,mpc,katz")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    parser.add_argument("--merge", type=Path, nargs="+", default=None,
                        help="no run: join these results files (same samples and days; rows per controller by p) "
                             "into --out")
    parser.add_argument("--note", default="", help="a sentence the table carries (why a grid is partial)")
    args = parser.parse_args()
    if args.merge:
        write(merged([json.loads(path.read_text()) for path in args.merge], args.note), args.out)
        return
    grid = [float(x) for x in args.probabilities.split(",")]
    args.out.mkdir(parents=True, exist_ok=True)
    command = (f"python studies/contingencies/missed_burns.py --samples {args.samples} --days {args.days:g} "
               f"--probabilities {args.probabilities} --controllers {args.controllers}"
               + (f" --katz-probabilities {args.katz_probabilities}" if args.katz_probabilities else ""))
    payload = {"samples": args.samples, "days": args.days, "geojax": geojax.__version__, "controllers": {},
               "command": command}
    rows = payload["controllers"]
    for name in args.controllers.split(","):
        grid_of = [float(x) for x in args.katz_probabilities.split(",")] if name == "katz" and \
            args.katz_probabilities else grid
        rows[name] = []
        for p in grid_of:
            r = run_point(name, p, args.days, args.samples)
            rows[name].append(r)
            print(name, r["p"], f"kept {r['kept']:.3f}", f"lost {r['lost_fraction']:.3f}", f"{r['wall_s']:.0f} s",
                  flush=True)
            # written after every point: a long run stopped early keeps what it measured
            (args.out / "missed_burns.json").write_text(json.dumps(payload, indent=1))
    write(payload, args.out)


def write(payload: dict, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / "missed_burns.json").write_text(json.dumps(payload, indent=1))
    (out / "missed_burns.md").write_text(table(payload))
    print(table(payload))


def merged(payloads: list[dict], note: str = "") -> dict:
    """One results payload of several runs of the same samples and days: each controller's points of every run,
    by p (a later run's point replaces an earlier one's), the runs' commands joined."""
    first = payloads[0]
    if any((p["samples"], p["days"]) != (first["samples"], first["days"]) for p in payloads):
        raise SystemExit("--merge: the results files differ in samples or days")
    rows: dict = {}
    for payload in payloads:
        for name, points in payload["controllers"].items():
            rows.setdefault(name, {}).update({r["p"]: r for r in points})
    return {**first, "controllers": {name: [at[p] for p in sorted(at)] for name, at in rows.items()},
            "command": "; ".join(p["command"] for p in payloads), "note": note}


def threshold(points: list[dict]) -> str:
    """The smallest p of the grid at which fewer than 99 % of the samples keep the box ("> the grid" if none)."""
    below = [r["p"] for r in points if r["kept"] < 0.99]
    return f"{min(below):g}" if below else f"> {max(r['p'] for r in points):g}"


def held_to(points: list[dict]) -> str:
    """The largest p of the grid below the threshold at which at least 99 % keep the box ("–" if none)."""
    below = [r["p"] for r in points if r["kept"] < 0.99]
    held = [r["p"] for r in points if r["kept"] >= 0.99 and (not below or r["p"] < min(below))]
    return f"{max(held):g}" if held else "–"


def table(payload: dict) -> str:
    """The study's table from its results (``missed_burns.json``)."""
    lines = [f"Burns lost with probability p: {payload['samples']} samples per point, {payload['days']:g} days "
             f"(`{payload['command']}`; geojax {payload['geojax']}). Each cell: the fraction of samples that keep "
             "the box / the fraction of planned burns lost / the mean ΔV (m/s/yr) / the mean days out of the box "
             "(a sample out of it at some step start of a cycle counts the cycle). Katz's discrete law leaves the "
             "±0.05° box in its first five days without any fault (0.058° at seed 0, 3 days out), so for it the "
             "days out of the box are the measure."
             + (f" Shorter than the year asked ({payload['days']:g} days, for the time the run had); the full "
                f"run: `python studies/contingencies/missed_burns.py --samples {payload['samples']} --days 365.25`."
                if payload["days"] < 365.25 else "")
             + (f" {payload['note']}" if payload.get("note") else ""), ""]
    grid = sorted({r["p"] for points in payload["controllers"].values() for r in points})
    lines += ["| controller | " + " | ".join(f"p = {p:g}" for p in grid) + " | ≥ 99 % kept to | fewer than 99 % kept from "
              "| wall (s) |", "|---|" + "---:|" * len(grid) + "---:|---:|---:|"]
    for name, points in payload["controllers"].items():
        at = {r["p"]: r for r in points}
        cells = [f"{at[p]['kept']:.2f} / {at[p]['lost_fraction']:.3f} / {at[p]['dv_per_year_mps_mean']:.1f} / "
                 f"{at[p]['days_out_of_box_mean']:.1f}" if p in at else "–" for p in grid]
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {held_to(points)} | {threshold(points)} | "
                     f"{sum(r['wall_s'] for r in points):.0f} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
