"""What a tracking set-up costs in Delta-V and box margin, and the Gaussian fix that costs the same (Li 2022's
Fig. 16 in physical terms).

    python studies/navigation/tracking_cost.py [--controller qffc] [--samples 16] [--days 365.25]
                                               [--out studies/navigation/results]

Li 2022 (Fig. 16) sweeps its determination error as a multiple H_rv of a nominal Gaussian fix.  Here the estimate
comes from the extended Kalman filter on a tracking set-up (``li2022-qffc-ranging``: two stations' 5 m ranging, a
2 h pass twice a day, burns flown with 2 % and 0.1 deg errors), varied one property at a time: the ranging noise
(1-50 m), the passes a day (1, 2, 4, each 2 h), the burns' magnitude error (0-5 %, pointing 0.1 deg; 0 % also
without pointing error) and one station instead of two; QFFC, ``--samples`` draws each, the same seeds for every
set-up.  Beside them, li2022-qffc with Li's Gaussian fix at H_rv from 0 to 800 and the same execution errors as
Li draws them (3-sigma 6 % and 0.3 deg: 1 sigma 2 % and 0.1 deg), and, for each set-up with those execution
errors, the H_rv whose mean Delta-V equals the set-up's (linear interpolation in the H_rv grid; none where the
set-up spends less than H_rv = 0, or where the grid's Delta-V does not rise by more than three standard errors up
to H_rv = 400).  Writes ``tracking_cost.md`` and ``.json`` into ``--out`` (the FOMPC's and the
MPC's: ``tracking_cost_fompc``, ``tracking_cost_mpc``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.loop.metrics import STATUS_MEANINGS
from geojax.runner.rollout import simulate_batch

HERE = Path(__file__).resolve().parent
BOTH = ("navigation.stations[0].", "navigation.stations[1].")
XICHANG = {"lat_deg": 28.25, "lon_deg": 102.03, "alt_m": 1800.0, "cadence_s": 43200.0, "pass_s": 7200.0,
           "measurements": ["range"], "range_sigma_m": 5.0}


def both(key: str, value) -> dict:
    return {prefix + key: value for prefix in BOTH}


# (label, overrides of li2022-qffc-ranging, whether its execution errors are Li's nominal ones)
SETUPS = [
    ("two stations, 5 m, 2 passes/day, 2 % (the scenario)", {}, True),
    ("σ_range 1 m", both("range_sigma_m", 1.0), True),
    ("σ_range 20 m", both("range_sigma_m", 20.0), True),
    ("σ_range 50 m", both("range_sigma_m", 50.0), True),
    ("1 pass/day", both("cadence_s", 86400.0), True),
    ("4 passes/day", both("cadence_s", 21600.0), True),
    ("no execution errors", {"errors.sigma3_dv_pct": 0.0, "errors.sigma3_att_deg": 0.0},
     False),
    ("magnitude error 5 %", {"errors.sigma3_dv_pct": 15.0}, False),
]
ONE_STATION = ("one station (Xichang), 5 m, 2 passes/day, 2 %", {"navigation.stations": [XICHANG]}, True)
H_RV = [0.0, 10.0, 20.0, 50.0, 100.0, 200.0, 400.0, 800.0]
LI_EXECUTION = {"errors.sigma3_dv_pct": 6.0, "errors.sigma3_att_deg": 0.3}


def summary(result, rows: slice, samples: int) -> dict:
    m = {k: np.asarray(v, float)[rows] for k, v in result.metrics.items()}
    status = [STATUS_MEANINGS[int(s)] for s in np.asarray(result.status)[rows]]
    out = {"dv_per_year_mps_mean": float(m["dv_per_year_mps"].mean()),
           "dv_per_year_mps_std": float(m["dv_per_year_mps"].std()),
           "max_abs_dlon_deg": float(m["max_abs_dlon_deg"].max()),
           "max_abs_dlat_deg": float(m["max_abs_dlat_deg"].max()),
           "ok": sum(s == "ok" for s in status), "samples": samples}
    if "nav_position_rms_m" in m:
        out["nav_position_rms_m"] = float(np.sqrt(np.mean(m["nav_position_rms_m"] ** 2)))
        out["nav_along_rms_m"] = float(np.sqrt(np.mean(m["nav_along_rms_m"] ** 2)))
    return out


def batch(scenarios: list, samples: int) -> list[dict]:
    """One compiled batch of every scenario x ``samples`` seeds; a summary per scenario."""
    result = simulate_batch([sc for sc in scenarios for _ in range(samples)],
                            seeds=np.tile(np.arange(samples), len(scenarios)))
    return [summary(result, slice(i * samples, (i + 1) * samples), samples) for i in range(len(scenarios))]


def equivalent_h_rv(dv: float, grid: list[float], dv_grid: list[float]) -> float | None:
    """The H_rv of the Gaussian fix with the same mean Delta-V (the grid's Delta-V increasing); None below it."""
    if dv < dv_grid[0]:
        return None
    return float(np.interp(dv, dv_grid, grid))


def navigation_overrides() -> dict:
    """The ``[navigation]`` table of li2022-qffc-ranging and its burns' execution errors (``[errors]``) as overrides
    (for another controller's scenario); the filter's priors left to follow the errors, as there."""
    config = scenario.load("li2022-qffc-ranging").config
    table = {key: value for key, value in config["navigation"].items()
             if value is not None and not key.startswith("assumed_")}
    return {**{f"navigation.{key}": value for key, value in table.items()},
            **{f"errors.{key}": config["errors"][key] for key in ("sigma3_dv_pct", "sigma3_att_deg")}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--controller", choices=("qffc", "fompc", "mpc"), default="qffc")
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    days = {"duration.days": args.days}
    base, ranging = f"li2022-{args.controller}", {}
    if args.controller != "qffc":
        ranging = navigation_overrides()
    name = "li2022-qffc-ranging" if args.controller == "qffc" else base
    filtered = batch([scenario.load(name, {**days, **ranging, **o}) for _, o, _ in SETUPS], args.samples)
    filtered += batch([scenario.load(name, {**days, **ranging, **ONE_STATION[1]})], args.samples)
    fixes = batch([scenario.load(base, {**days, **LI_EXECUTION, "errors.h_rv": h}) for h in H_RV], args.samples)
    dv_grid = [f["dv_per_year_mps_mean"] for f in fixes]
    # an equivalent H_rv only where the grid's Delta-V rises, step by step, and over the grid by more than three
    # standard errors of its draws (the MPC's does not move with H_rv up to 400: no equivalent to read)
    spread = 3 * max(f["dv_per_year_mps_std"] for f in fixes[:-1]) / np.sqrt(args.samples)
    monotone = bool(np.all(np.diff(dv_grid) > 0) and dv_grid[-2] - dv_grid[0] > spread)
    rows = []
    for (label, overrides, nominal), row in zip([*SETUPS, ONE_STATION], filtered):
        row = {"label": label, "overrides": {k: v for k, v in overrides.items() if k != "navigation.stations"},
               **row}
        row["h_rv_equivalent"] = equivalent_h_rv(row["dv_per_year_mps_mean"], H_RV, dv_grid) if nominal and \
            monotone else None
        rows.append(row)
        print(row, flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    stem = "tracking_cost" if args.controller == "qffc" else f"tracking_cost_{args.controller}"
    payload = {"controller": args.controller, "samples": args.samples, "days": args.days, "geojax": geojax.__version__, "setups": rows,
               "gaussian_fix": [{"h_rv": h, **f} for h, f in zip(H_RV, fixes)], "dv_grid_increasing": monotone}
    (args.out / f"{stem}.json").write_text(json.dumps(payload, indent=1))
    lines = [f"# What a tracking set-up costs: {args.controller.upper()}, {args.samples} draws, {args.days:g} days",
             "", f"`python studies/navigation/tracking_cost.py --controller {args.controller} --samples "
             f"{args.samples} --days {args.days:g}`; geojax {geojax.__version__}. The extended Kalman filter on "
             f"{name} (li2022-qffc-ranging's tracking), one property varied at a time; beside it Li's Gaussian fix "
             f"({base}, execution errors 3σ 6 % and 0.3°) at H_rv from 0 to "
             "800. ΔV: mean over the draws; |Δλ|, |Δφ|: the largest over the draws (box half-width 0.05°).", "",
             "| tracking set-up | ΔV (m/s/yr) | ± std | max abs Δλ (deg) | max abs Δφ (deg) | position RMS (m) | "
             "along-track RMS (m) | H_rv of the same ΔV | in the box |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        h = "—" if r["h_rv_equivalent"] is None else f"{r['h_rv_equivalent']:.0f}"
        lines.append(f"| {r['label']} | {r['dv_per_year_mps_mean']:.3f} | {r['dv_per_year_mps_std']:.3f} | "
                     f"{r['max_abs_dlon_deg']:.4f} | {r['max_abs_dlat_deg']:.4f} | "
                     f"{r['nav_position_rms_m']:.1f} | "
                     f"{r['nav_along_rms_m']:.1f} | {h} | {r['ok']}/{r['samples']} |")
    lines += ["", "| Gaussian fix H_rv | ΔV (m/s/yr) | ± std | max abs Δλ (deg) | max abs Δφ (deg) | in the box |",
              "|---:|---:|---:|---:|---:|---|"]
    for h, f in zip(H_RV, fixes):
        lines.append(f"| {h:g} | {f['dv_per_year_mps_mean']:.3f} | {f['dv_per_year_mps_std']:.3f} | "
                     f"{f['max_abs_dlon_deg']:.4f} | {f['max_abs_dlat_deg']:.4f} | {f['ok']}/{f['samples']} |")
    (args.out / f"{stem}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
