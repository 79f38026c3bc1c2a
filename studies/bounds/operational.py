"""Gazzino 2016's operational thruster constraints: the bound's relaxed plan made flyable by
the paper's two equivalence schemes (``geojax.bound.operational``), each flown in the nonlinear closed loop.

    python studies/bounds/operational.py [--days 28] [--margin 0.2] [--out studies/bounds/results]
    python studies/bounds/operational.py --terminal --days 7 14 28 [--margin 0.2]


1. The relaxed optimum: ``bound`` of gazzino2016 over the full box (the reference for "% above").
2. The relaxed plan to start from: ``bound`` in the box shrunk by ``--margin`` (the room the pulses need).
3. Fuel-based (Problem 6) and effect-based (Problem 7) pulses under (i)-(iv), flown by ``bound.replay``.
Writes ``operational.md`` (the table) and ``operational.png`` (longitude, latitude and the pulses).

``--terminal``: the relaxed plans with Gazzino's terminal condition x(T) = x(0) (``bound``'s default),
at each of ``--days``; the schemes as above plus Problem 7 as the paper writes it (``operational.effect_matched``:
the durations match the relaxed plan's effect on the end state, no box), with both tie-breaks.  Writes
``operational-terminal.md`` and ``operational-terminal.png`` (the longest horizon).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import geojax  # noqa: E402
from geojax.bound import bound, replay  # noqa: E402
from geojax.bound import operational as op  # noqa: E402
from geojax.bound.directions import geometry_of  # noqa: E402
from geojax.bound.run import BOX_MARGIN, _uncontrolled  # noqa: E402
from geojax.runner.rollout import simulate  # noqa: E402
from geojax.papers import GAZZINO2016  # noqa: E402

HERE = Path(__file__).resolve().parent
SCENARIO = "gazzino2016"
OUTER = 0.8  # "near the edge": beyond this fraction of the box half-width
ROUNDS = 3  # effect-based: re-linearisations about its own flight at most


def fly(sc, u_rsw_mps, fuel_mps, step_s, concurrent=1):
    """The per-step plan in the closed loop: metrics, status, (lon - station, lat) at every step start (deg)."""
    result = simulate(_uncontrolled(sc), 0, controller=replay(u_rsw_mps, fuel_mps, 1, step_s, concurrent),
                      keep_steps=True)
    steps = result.records.steps
    lon = np.degrees(np.angle(np.exp(1j * (np.asarray(steps.lon_rad).ravel() - np.radians(sc.config["station"]["lon_deg"])))))
    return {k: float(v) for k, v in result.metrics.items()}, int(result.status), lon, np.degrees(np.asarray(steps.lat_rad).ravel())


def centre_measures(lon_deg, lat_deg, box_deg) -> dict:
    """How far from the box centre a history lives: RMS of |dlon| / box and |lat| / box, and the fraction of
    step starts with max(|dlon|, |lat|) beyond ``OUTER`` of the box."""
    edge = np.maximum(np.abs(lon_deg), np.abs(lat_deg)) / box_deg
    return {"rms_lon_box": float(np.sqrt(np.mean((lon_deg / box_deg) ** 2))),
            "rms_lat_box": float(np.sqrt(np.mean((lat_deg / box_deg) ** 2))),
            "outer_fraction": float(np.mean(edge > OUTER))}


def run(days: float, margin: float, constraints=op.Constraints(), say=print) -> dict:
    sc = geojax.load_scenario(SCENARIO, {"duration.days": days})
    box_deg = float(sc.config["station"]["box_half_width_deg"])
    shrunk = geojax.load_scenario(SCENARIO, {"duration.days": days, "station.box_half_width_deg": box_deg * (1 - margin)})
    geometry = geometry_of(sc.config)
    directions = np.concatenate(geometry.generators)
    accel_mps2 = float(sc.config["thrusters"]["thrust_n"]) / float(sc.config["spacecraft"]["mass_kg"])
    optimum = bound(sc, slot_steps=1, free_end=True)
    relaxed = bound(shrunk, slot_steps=1, free_end=True)
    step_s = relaxed.slot_s
    n_steps = len(relaxed.u_rsw_mps)
    horizon_s = n_steps * step_s
    say(f"relaxed optimum {optimum.fuel_mps:.4f} m/s; in the box less {margin:.0%}: {relaxed.fuel_mps:.4f} m/s")

    start = time.perf_counter()
    fuel_pulses = op.fuel_based(relaxed.thruster_mps / accel_mps2, step_s, horizon_s, constraints)
    say(f"fuel-based: {len(fuel_pulses.centre_s)} pulses ({time.perf_counter() - start:.2f} s)")
    box_rad = np.radians(box_deg) * (1 - BOX_MARGIN)
    effect_pulses = op.effect_based(sc, relaxed.u_rsw_mps, fuel_pulses, directions, accel_mps2, box_rad, constraints, say=say)

    rows = {}
    cases = {"relaxed optimum": (optimum.u_rsw_mps, optimum.thruster_mps.sum(axis=1), len(directions), None),
             f"relaxed, box less {margin:.0%}": (relaxed.u_rsw_mps, relaxed.thruster_mps.sum(axis=1), len(directions), None),
             "fuel-based": (*op.step_plan(fuel_pulses, directions, accel_mps2, step_s, n_steps), 1, fuel_pulses),
             "effect-based": (*op.step_plan(effect_pulses, directions, accel_mps2, step_s, n_steps), 1, effect_pulses)}
    for name, (u, fuel, concurrent, pulses) in cases.items():
        metrics, status, lon, lat = fly(sc, u, fuel, step_s, concurrent)
        rows[name] = {"plan_mps": float(np.sum(fuel)), "dv_per_year_mps": metrics["dv_per_year_mps"], "status": status,
                      "max_abs_dlon_deg": float(np.max(np.abs(lon))), "max_abs_dlat_deg": float(np.max(np.abs(lat))),
                      **centre_measures(lon, lat, box_deg), "lon_deg": lon, "lat_deg": lat, "pulses": pulses,
                      "violations": None if pulses is None else op.violations(pulses, horizon_s, constraints)}
        say(f"{name}: {rows[name]['dv_per_year_mps']:.3f} m/s/yr, status {status}")
    return {"days": days, "margin": margin, "box_deg": box_deg, "step_s": step_s, "constraints": constraints,
            "rows": rows, "directions": directions}


def flown_row(sc, u, fuel, step_s, concurrent, pulses, horizon_s, box_deg, constraints, **extra) -> dict:
    metrics, status, lon, lat = fly(sc, u, fuel, step_s, concurrent)
    return {"plan_mps": float(np.sum(fuel)), "dv_per_year_mps": metrics["dv_per_year_mps"], "status": status,
            "max_abs_dlon_deg": float(np.max(np.abs(lon))), "max_abs_dlat_deg": float(np.max(np.abs(lat))),
            **centre_measures(lon, lat, box_deg), "end_box": float(max(abs(lon[-1]), abs(lat[-1])) / box_deg),
            "lon_deg": lon, "lat_deg": lat, "pulses": pulses,
            "violations": None if pulses is None else op.violations(pulses, horizon_s, constraints), **extra}


def run_terminal(days: float, margin: float, constraints=op.Constraints(), say=print) -> dict:
    """The relaxed plans with x(T) = x(0), and the fuel-based, Problem 7 (as written) and box-holding
    effect-based pulses from the one in the box less ``margin``, each flown in the closed loop."""
    sc = geojax.load_scenario(SCENARIO, {"duration.days": days})
    box_deg = float(sc.config["station"]["box_half_width_deg"])
    shrunk = geojax.load_scenario(SCENARIO, {"duration.days": days, "station.box_half_width_deg": box_deg * (1 - margin)})
    directions = np.concatenate(geometry_of(sc.config).generators)
    accel_mps2 = float(sc.config["thrusters"]["thrust_n"]) / float(sc.config["spacecraft"]["mass_kg"])
    free = bound(sc, slot_steps=1, free_end=True)
    optimum = bound(sc, slot_steps=1)
    relaxed = bound(shrunk, slot_steps=1)
    step_s, n_steps = relaxed.slot_s, len(relaxed.u_rsw_mps)
    horizon_s = n_steps * step_s
    miss = {name: r.rounds[-1]["terminal_miss"] for name, r in (("optimum", optimum), ("relaxed", relaxed))}
    say(f"{days:g} days: relaxed optimum {free.fuel_mps:.4f} m/s, with x(T) = x(0) {optimum.fuel_mps:.4f}, in the box "
        f"less {margin:.0%} {relaxed.fuel_mps:.4f}; flown end state less x(0): {miss}")
    fuel_pulses = op.fuel_based(relaxed.thruster_mps / accel_mps2, step_s, horizon_s, constraints)
    matched = {tie: op.effect_matched(sc, relaxed.u_rsw_mps, fuel_pulses, directions, accel_mps2, constraints, tie)
               for tie in ("fuel", "near")}
    box_rad = np.radians(box_deg) * (1 - BOX_MARGIN)
    try:
        effect_pulses = op.effect_based(sc, relaxed.u_rsw_mps, fuel_pulses, directions, accel_mps2, box_rad,
                                        constraints, say=say)
    except ValueError as error:  # the scheduled pulses cannot hold the box
        say(f"effect-based: {error}")
        effect_pulses = None
    rest = (horizon_s, box_deg, constraints)
    rows = {"relaxed optimum, free end": flown_row(sc, free.u_rsw_mps, free.thruster_mps.sum(axis=1), step_s,
                                                   len(directions), None, horizon_s, box_deg, constraints),
            "relaxed optimum, x(T) = x(0)": flown_row(sc, optimum.u_rsw_mps, optimum.thruster_mps.sum(axis=1), step_s,
                                                      len(directions), None, horizon_s, box_deg, constraints),
            f"relaxed x(T) = x(0), box less {margin:.0%}": flown_row(
                sc, relaxed.u_rsw_mps, relaxed.thruster_mps.sum(axis=1), step_s, len(directions), None, *rest)}
    rows["fuel-based (Problem 6)"] = flown_row(sc, *op.step_plan(fuel_pulses, directions, accel_mps2, step_s, n_steps),
                                               step_s, 1, fuel_pulses, *rest)
    for tie, (pulses, report) in matched.items():
        rows[f"Problem 7 as written, tie: {tie}"] = flown_row(
            sc, *op.step_plan(pulses, directions, accel_mps2, step_s, n_steps), step_s, 1, pulses, *rest,
            mismatch=float(np.sum(np.abs(report["mismatch"]))), effect=float(np.sum(np.abs(report["relaxed"]))),
            mismatch_vector=report["mismatch"], effect_vector=report["relaxed"])
    if effect_pulses is not None:
        rows["effect-based, box held (ours)"] = flown_row(
            sc, *op.step_plan(effect_pulses, directions, accel_mps2, step_s, n_steps), step_s, 1, effect_pulses,
            *rest)
    for name, r in rows.items():
        say(f"  {name}: {r['dv_per_year_mps']:.3f} m/s/yr, status {r['status']}, outer {r['outer_fraction']:.3f}")
    return {"days": days, "margin": margin, "box_deg": box_deg, "step_s": step_s, "constraints": constraints,
            "rows": rows, "miss": miss}


def write_terminal(outs: list, wall_s: float, folder: Path) -> None:
    """``operational-terminal.md`` (one table over the horizons) and ``operational-terminal.png`` (the last)."""
    folder.mkdir(parents=True, exist_ok=True)
    c, margin = outs[0]["constraints"], outs[0]["margin"]
    days = " ".join(f"{o['days']:g}" for o in outs)
    lines = [f"# Gazzino 2016's operational constraints with the terminal condition x(T) = x(0), {SCENARIO}", "",
             f"`python studies/bounds/operational.py --terminal --days {days} --margin {margin:g}` ({wall_s:.0f} s on 2 CPU "
             f"cores). T_l = {c.t_min_firing_s:g} s, T_s = {c.t_same_gap_s:g} s, T_d = {c.t_other_gap_s:g} s (choices). "
             f"The pulses come from the relaxed x(T) = x(0) plan in the box less {margin:.0%}. Every plan flown in the "
             f"nonlinear closed loop; status 0: the +-{outs[0]['box_deg']:g} deg box held at every step start. "
             f"% above: over the relaxed optimum with x(T) = x(0) (full box). Outer 20 %: the fraction of step starts "
             f"with max(|dlon|, |lat|) beyond {OUTER:.0%} of the box; end/box: max(|dlon|, |lat|) at the last step start "
             f"over the box. Problem 7 mismatch: sum over the six MEE of |effect of the pulses - effect of the relaxed "
             f"plan| on the end state, over sum |effect of the relaxed plan| (linear model, units of 1e-4).", "",
             "| days | plan | pulses | violations | ΔV (m/s/yr) | above | status | max abs dλ (°) | max abs φ (°) "
             "| RMS dλ/box | RMS φ/box | outer 20 % | end/box | P7 mismatch |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for o in outs:
        rows = o["rows"]
        reference = rows["relaxed optimum, x(T) = x(0)"]["dv_per_year_mps"]
        for name, r in rows.items():
            pulses = "" if r["pulses"] is None else str(len(r["pulses"].centre_s))
            broken = "" if r["violations"] is None else str(sum(r["violations"].values()))
            mismatch = f"{r['mismatch']:.3g} / {r['effect']:.3g}" if "mismatch" in r else ""
            lines.append(f"| {o['days']:g} | {name} | {pulses} | {broken} | {r['dv_per_year_mps']:.2f} "
                         f"| {100 * (r['dv_per_year_mps'] / reference - 1):+.1f} % | {r['status']} | {r['max_abs_dlon_deg']:.4f} "
                         f"| {r['max_abs_dlat_deg']:.4f} | {r['rms_lon_box']:.2f} | {r['rms_lat_box']:.2f} "
                         f"| {100 * r['outer_fraction']:.1f} % | {r['end_box']:.2f} | {mismatch} |")
    lines += ["", "Fuel-based over each (ΔV per year):", ""]
    for o in outs:
        rows = o["rows"]
        fuel = rows["fuel-based (Problem 6)"]["dv_per_year_mps"]
        ratios = ", ".join(f"{name} {100 * (fuel / r['dv_per_year_mps'] - 1):+.1f} %" for name, r in rows.items()
                           if name.startswith(("Problem 7", "effect-based")))
        lines.append(f"- {o['days']:g} days: {ratios} (Gazzino: {GAZZINO2016['fuel_over_effect_percent']} %)")
    lines += ["", "Problem 7: the relaxed plan's effect on the end state and the pulses' mismatch (MEE p, f, g, h, k, L in "
              "units of 1e-4 of p, of 1, of rad; linear model):", ""]
    for o in outs:
        for name, r in o["rows"].items():
            if "mismatch_vector" in r:
                lines.append(f"- {o['days']:g} days, {name}: effect " + ", ".join(f"{v:.3g}" for v in r["effect_vector"])
                             + "; mismatch " + ", ".join(f"{v:.3g}" for v in r["mismatch_vector"]))
    lines += ["", "The relaxed plans' flown end state less x(0) (MEE p m, f, g, h, k, L rad; the last linearisation):", ""]
    for o in outs:
        for name, miss in o["miss"].items():
            lines.append(f"- {o['days']:g} days, {name}: " + ", ".join(f"{v:.2e}" for v in miss))
    (folder / "operational-terminal.md").write_text("\n".join(lines) + "\n")
    out = outs[-1]
    styles = {"relaxed optimum, x(T) = x(0)": ("0.6", "-"), "fuel-based (Problem 6)": ("C0", "-"),
              "Problem 7 as written, tie: fuel": ("C2", "-"), "effect-based, box held (ours)": ("C3", "--")}
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    for name, (color, line) in styles.items():
        if name not in out["rows"]:
            continue
        r = out["rows"][name]
        t = np.arange(len(r["lon_deg"])) * out["step_s"] / 86400.0
        axes[0].plot(t, r["lon_deg"], color=color, ls=line, lw=0.9, label=name)
        axes[1].plot(t, r["lat_deg"], color=color, ls=line, lw=0.9, label=name)
    for ax, label in zip(axes, ("λ - station (°)", "φ (°)")):
        for edge in (-out["box_deg"], out["box_deg"]):
            ax.axhline(edge, color="k", lw=0.8)
        ax.set_ylabel(label)
    axes[0].legend(loc="lower left", fontsize=8)
    axes[0].set_title(f"x(T) = x(0), {out['days']:g} days")
    axes[1].set_xlabel("days")
    fig.tight_layout()
    fig.savefig(folder / "operational-terminal.png", dpi=120)
    plt.close(fig)


def write(out: dict, wall_s: float, folder: Path) -> None:
    """``operational.md`` (the table and its reading) and ``operational.png``."""
    folder.mkdir(parents=True, exist_ok=True)
    rows, box = out["rows"], out["box_deg"]
    optimum = rows["relaxed optimum"]["dv_per_year_mps"]
    c = out["constraints"]
    lines = [f"# Gazzino 2016's operational constraints, {SCENARIO}, {out['days']:g} days", "",
             f"`python studies/bounds/operational.py --days {out['days']:g} --margin {out['margin']:g}` ({wall_s:.0f} s on 2 CPU cores). "
             f"Constraints (choices, the paper gives no values): T_l = {c.t_min_firing_s:g} s, T_s = {c.t_same_gap_s:g} s, "
             f"T_d = {c.t_other_gap_s:g} s. Every plan flown in the nonlinear closed loop (`bound.replay`, one step per slot); "
             f"status 0: the +-{box:g} deg box held at every step start. Centre vs edge: RMS of |dlon|/box and |lat|/box, and "
             f"the fraction of step starts with max(|dlon|, |lat|) beyond {OUTER:.0%} of the box.", "",
             "| plan | pulses | constraint violations | ΔV (m/s/yr) | above the relaxed optimum | status | max abs dλ (°) | max abs φ (°) "
             "| RMS dλ/box | RMS φ/box | outer 20 % |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, r in rows.items():
        pulses = "" if r["pulses"] is None else str(len(r["pulses"].centre_s))
        broken = "" if r["violations"] is None else str(sum(r["violations"].values()))
        lines.append(f"| {name} | {pulses} | {broken} | {r['dv_per_year_mps']:.2f} | {100 * (r['dv_per_year_mps'] / optimum - 1):+.1f} % "
                     f"| {r['status']} | {r['max_abs_dlon_deg']:.4f} | {r['max_abs_dlat_deg']:.4f} | {r['rms_lon_box']:.2f} "
                     f"| {r['rms_lat_box']:.2f} | {100 * r['outer_fraction']:.1f} % |")
    fuel, effect = rows["fuel-based"]["dv_per_year_mps"], rows["effect-based"]["dv_per_year_mps"]
    lines += ["", f"Fuel-based over effect-based: {100 * (fuel / effect - 1):+.1f} % (Gazzino: {GAZZINO2016['fuel_over_effect_percent']} %).", "",
              "The same with a smaller margin: `--margin 0.05 --out studies/bounds/results/operational-margin0.05`; "
              "with Gazzino's terminal condition x(T) = x(0) and Problem 7 as printed: `--terminal --days 7 14 28` "
              "(`operational-terminal.md`). What the three say about Gazzino's findings (the fuel factor, Fig. 6's "
              "centre and edge): `studies/README.md`, Gazzino 2016.", ""]
    (folder / "operational.md").write_text("\n".join(lines))
    _figure(out, folder / "operational.png")


def _figure(out: dict, path: Path) -> None:
    rows, box, step_s = out["rows"], out["box_deg"], out["step_s"]
    fig, axes = plt.subplots(3, 1, figsize=(10, 9), sharex=True)
    styles = {"relaxed optimum": ("0.6", "-"), "fuel-based": ("C0", "-"), "effect-based": ("C3", "--")}
    for name, (color, line) in styles.items():
        r = rows[name]
        days = np.arange(len(r["lon_deg"])) * step_s / 86400.0
        axes[0].plot(days, r["lon_deg"], color=color, ls=line, lw=0.9, label=name)
        axes[1].plot(days, r["lat_deg"], color=color, ls=line, lw=0.9, label=name)
    for ax, label in zip(axes[:2], ("λ - station (°)", "φ (°)")):
        for edge in (-box, box):
            ax.axhline(edge, color="k", lw=0.8)
        ax.set_ylabel(label)
    axes[0].legend(loc="lower left", fontsize=8)
    names = ("NE", "NW", "SE", "SW")
    for offset, (name, color) in ((0.2, ("fuel-based", "C0")), (-0.2, ("effect-based", "C3"))):
        p = rows[name]["pulses"]
        axes[2].barh(p.thruster + offset, p.duration_s / 86400.0, left=(p.centre_s - p.duration_s / 2) / 86400.0,
                     height=0.35, color=color, label=name)
    axes[2].set_yticks(range(4), names)
    axes[2].set_ylabel("thruster")
    axes[2].set_xlabel("days")
    axes[2].legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--days", type=float, nargs="+", default=[28.0], help="horizon(s); several with --terminal")
    parser.add_argument("--margin", type=float, default=0.2, help="the relaxed plan's box shrunk by this fraction")
    parser.add_argument("--terminal", action="store_true", help="relaxed plans with x(T) = x(0), Problem 7 as written")
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    if args.terminal:
        outs = [run_terminal(days, args.margin) for days in args.days]
        write_terminal(outs, time.perf_counter() - start, args.out)
        print((args.out / "operational-terminal.md").read_text())
        return 0
    if len(args.days) != 1:
        parser.error("--days: one horizon without --terminal")
    args.days = args.days[0]
    out = run(args.days, args.margin)
    write(out, time.perf_counter() - start, args.out)
    print((args.out / "operational.md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
