"""Why do our QFFC and FOMPC leave the box under Li 2022's attitude errors (Fig. 15)?

    python studies/ablation/li_attitude_error.py [--reps 6] [--days 180] [--levels 0 300 500]

Li 2022 eq. (47) draws the yaw alpha and the pitch beta of each burn from N(true, sigma^2), eq. (48) puts
3 sigma at 0.05 deg, and Fig. 15 magnifies it by H_att: "almost no effect" on either controller.  Ours
(``fig15_h_att.md``, one year, 20 repetitions): at H_att = 300 (3 sigma = 15 deg) the QFFC costs +28 % and
half the runs leave the +-0.05 deg box; from 500 every run fails.  Each variant switches one reading of how
the error enters (``errors.att_*``, ``geojax/control/burns.py``) or one candidate cause, at every level of
``--levels``, for both controllers, ``--reps`` error draws each, all in one compiled batch per controller:

* flown: eq. (47) on the direction flown, one draw per burn, the magnitudes as planned (our reading);
* yaw-only, pitch-only: the error in one angle;
* shared: one draw for both burns of a cycle (a pointing bias per cycle instead of per burn);
* plan-known: the plan knows the error: the two magnitudes are re-fitted so that the burns along the
  perturbed directions best reproduce the planned effect (eq. (29));
* weak-limits: Table 1's weak arm limits (beta_max 90, alpha 90 / 90) instead of the normal ones;
* determination: the nominal orbit-determination errors (H_rv = 1) on top, so the predictor starts from a
  noisy estimate too;
* vdt-estimate: the QFFC's V_DT from the predictor's drift estimate (eqs. (37)-(39)).

Besides ΔV and the status, the table gives the in-plane ΔV planned per year and the error's own ΔV per year:
the sum over burns of |V u' - v|, the velocity increment the error put where the plan did not want it (what
the next cycles must undo, at least in part).  Writes ``studies/ablation/results/li_attitude_error.md`` and
``.json``.
"""

from __future__ import annotations

import os

os.environ.setdefault("XLA_FLAGS", f"--xla_force_host_platform_device_count={os.cpu_count() or 1}")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import geojax  # noqa: E402
from geojax.loop.metrics import STATUS_MEANINGS  # noqa: E402

HERE = Path(__file__).resolve().parent
NORMAL = {"thrusters.beta_max_deg": 70.0, "thrusters.beta_min_deg": 0.0, "thrusters.alpha_max_deg": 60.0,
          "thrusters.alpha_min_deg": 30.0}  # Li Table 1, normal (Fig. 15's setting, as fig15_h_att.toml)
WEAK = {"thrusters.beta_max_deg": 90.0, "thrusters.beta_min_deg": 0.0, "thrusters.alpha_max_deg": 90.0,
        "thrusters.alpha_min_deg": 90.0}
VARIANTS = {
    "flown": ({}, "eq. (47) on the direction flown, one draw per burn, magnitudes as planned (ours)"),
    "yaw-only": ({"errors.att_axes": "yaw"}, "the error in the yaw alpha only"),
    "pitch-only": ({"errors.att_axes": "pitch"}, "the error in the pitch beta only"),
    "shared": ({"errors.att_shared": True}, "one draw for both burns of a cycle"),
    "plan-known": ({"errors.att_known": True}, "magnitudes re-fitted to the directions flown"),
    "weak-limits": (WEAK, "Table 1 weak arm limits"),
    "determination": ({"errors.h_rv": 1.0}, "nominal orbit-determination errors too (H_rv = 1)"),
    "vdt-estimate": ({"controller.vdt_estimate": True}, "V_DT from the drift estimate, eqs. (37)-(39)"),
}
YEAR_DAYS = 365.25


def cases(levels, reps):
    """(variant, level) rows, each ``reps`` samples; the error-free level only for the variants that change
    something without errors."""
    rows = []
    for name, (overrides, _) in VARIANTS.items():
        for level in levels:
            if level == 0 and not any(k.startswith(("thrusters.", "controller.")) or k == "errors.h_rv"
                                      for k in overrides) and name != "flown":
                continue
            rows.append((name, level))
    return rows


def run(controller: str, rows, reps: int, days: float, seed: int = 34) -> dict:
    scenarios = []
    for name, level in rows:
        overrides = {**NORMAL, "duration.days": days, "errors.h_att": level, **VARIANTS[name][0]}
        scenarios += [geojax.load_scenario(f"li2022-{controller}", overrides)] * reps
    start = time.perf_counter()
    result = geojax.simulate_batch(scenarios, seeds=[seed + j for j in range(len(scenarios))])
    wall_s = time.perf_counter() - start
    rec = result.records.cycles.controller
    planned = np.asarray(rec["burns"].dv_rsw_mps)  # [B, C, 2, 3]
    # the magnitude flown, F t / m at the start mass (the mass falls by < 0.5 % over a year: 50 m/s at 1500 s)
    sc = scenarios[0]
    flown_mps = np.asarray(rec["fired_s"]) * sc.config["thrusters"]["thrust_n"] / sc.mass_kg  # [B, C, 2]
    # an unsolved cycle's plan is not flown (its planned numbers are not meaningful): count fired burns only
    error = np.where(flown_mps[..., None] > 0, flown_mps[..., None] * np.asarray(rec["directions_rsw"]) - planned, 0.0)
    years = days / YEAR_DAYS
    out = {"wall_s": wall_s, "rows": {}}
    for r, (name, level) in enumerate(rows):
        s = slice(r * reps, (r + 1) * reps)
        status = np.asarray(result.status[s])
        dv = np.asarray(result.metrics["dv_per_year_mps"][s])
        ok = status == 0
        out["rows"][f"{name}@{level:g}"] = {
            "variant": name, "level": level, "status": [int(x) for x in status],
            "dv": [float(x) for x in dv], "dv_ok_mean": float(dv[ok].mean()) if ok.any() else None,
            "in_plane_per_year": float(np.where(flown_mps[s] > 0, np.hypot(planned[s, ..., 0], planned[s, ..., 1]),
                                                0.0).sum((1, 2)).mean() / years),
            "error_dv_per_year": float(np.linalg.norm(error[s], axis=-1).sum((1, 2)).mean() / years),
            "unsolved_cycles": float(np.mean(np.sum(~np.asarray(rec["solved"][s]), axis=1))),
        }
    return out


def table(results: dict, controllers, levels, reps: int, days: float) -> list[str]:
    lines = [f"# Li 2022 Fig. 15: how the attitude error enters, and why ours fail ({days:g} days, {reps} draws)", "",
             f"`python studies/ablation/li_attitude_error.py --reps {reps} --days {days:g} --levels "
             f"{' '.join(f'{x:g}' for x in levels)}`; li2022, normal limits (Table 1) unless the variant says, "
             "eq. (48)'s 3 sigma = 0.05 deg x H_att. ΔV: mean over the draws that kept the box at every step "
             "(its change against the same variant without errors, else against flown at 0) "
             "(all draws in brackets); out: draws that left the box or ran dry; unsolved: mean cycles without a "
             "solution per draw. In-plane: the planned in-plane ΔV of the fired burns per year; error ΔV: the sum "
             "over fired burns of |V u' - v| per year, what the error put where the plan did not want it (for "
             "plan-known it includes the re-fitted magnitudes' change).", "",
             f"Status codes: {', '.join(f'{k} {v}' for k, v in enumerate(STATUS_MEANINGS))}.", ""]
    for controller in controllers:
        res = results[controller]
        base = res["rows"]["flown@0"]["dv_ok_mean"]
        lines += [f"## {controller.upper()} ({res['wall_s']:.0f} s)", "",
                  "| variant | what it changes | H_att | ΔV m/s/yr | vs H_att = 0 | out / draws | unsolved | "
                  "in-plane m/s/yr | error ΔV m/s/yr |", "|---|---|---:|---|---:|---:|---:|---:|---:|"]
        for key, row in res["rows"].items():
            dv = np.array(row["dv"])
            out = sum(s not in (0, 1) for s in row["status"])
            ok_mean = row["dv_ok_mean"]
            own = res["rows"].get(f"{row['variant']}@0", {}).get("dv_ok_mean") or base  # the variant's own H_att = 0
            change = f"{100 * (ok_mean / own - 1):+.1f} %" if ok_mean is not None else "–"
            lines.append(f"| {row['variant']} | {VARIANTS[row['variant']][1]} | {row['level']:g} | "
                         f"{'–' if ok_mean is None else f'{ok_mean:.2f}'} ({dv.mean():.2f}) | {change} | "
                         f"{out} / {len(dv)} | {row['unsolved_cycles']:.1f} | {row['in_plane_per_year']:.2f} | "
                         f"{row['error_dv_per_year']:.2f} |")
        lines.append("")
    lines += ["## What the rows say", ""] + findings(results, controllers, levels)
    return lines


def findings(results: dict, controllers, levels) -> list[str]:
    """One line per controller and level: which readings keep every draw in the box, from the rows."""
    out = []
    for controller in controllers:
        rows = results[controller]["rows"]
        for level in [x for x in levels if x > 0]:
            kept = [v for v in VARIANTS if f"{v}@{level:g}" in rows
                    and all(s in (0,) for s in rows[f"{v}@{level:g}"]["status"])]
            lost = {v: sum(s != 0 for s in rows[f"{v}@{level:g}"]["status"]) for v in VARIANTS
                    if f"{v}@{level:g}" in rows and v not in kept}
            out.append(f"- {controller.upper()}, H_att = {level:g} (3 sigma = {0.05 * level:g} deg): every draw kept the "
                       f"box with no unsolved cycle under {', '.join(kept) or 'no variant'}; draws lost under "
                       f"{', '.join(f'{v} {n}' for v, n in lost.items()) or 'none'}.")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reps", type=int, default=6)
    parser.add_argument("--days", type=float, default=180.0)
    parser.add_argument("--levels", type=float, nargs="+", default=[0.0, 300.0, 500.0])
    parser.add_argument("--controllers", nargs="+", default=["qffc", "fompc"], choices=["qffc", "fompc"])
    parser.add_argument("--out", default=str(HERE / "results"))
    parser.add_argument("--table-only", action="store_true", help="rewrite the table from the saved .json")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.table_only:
        saved = json.loads((out / "li_attitude_error.json").read_text())
        args.days, args.reps, args.levels, results = saved["days"], saved["reps"], saved["levels"], saved["results"]
        args.controllers = list(results)
    else:
        rows = cases(args.levels, args.reps)
        results = {}
        for controller in args.controllers:
            results[controller] = run(controller, rows, args.reps, args.days)
            print(f"{controller}: {len(rows) * args.reps} samples in {results[controller]['wall_s']:.0f} s", flush=True)
        (out / "li_attitude_error.json").write_text(json.dumps({"days": args.days, "reps": args.reps,
                                                                 "levels": args.levels, "results": results}, indent=1))
    lines = table(results, args.controllers, args.levels, args.reps, args.days)
    (out / "li_attitude_error.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
