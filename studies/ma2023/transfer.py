"""Ma & Kong 2023: GTO-GEO transfer time and propellant, boom against fixed thrusters, and where the boom's
advantage comes from.

    python studies/ma2023/transfer.py [--rates 0.01 0.02 0.03 0.05 0.1 0.2] [--mc 128] [--mc-slew 0.02]
                                      [--inertias 2e3 2e4 6e4 2e5 1e8]

1. Both layouts (``ma2023-boom``, ``ma2023-fixed``) at every body slew rate of ``--rates`` (deg/s; the
   scenarios' 0.1 is the baseline), full transfers, one compiled batch: days, propellant, Delta-V, thrust
   efficiency, time lost to slewing, the boom's joint tracking and coupling torque.  The coupling torque
   (eq. 8) acts on the body (``geojax.transfer.pointing``): the wheels' torque J x slew acceleration must
   absorb it.
2. The step's accuracy: the baseline boom transfer at 60 s against the 120 s default.
3. The joint histories of the boom's first day (Figs. 11-14 style): targets, planned angles, rates, errors.
4. The firing gate: the thruster firing whenever within 90 deg of the wish (misaligned, paying the cosine
   in propellant) instead of waiting within 10 deg, at slow slews: where a fuel saving can come from.
5. The coupling torque: the boom at the baseline slew and at the Monte Carlo's against the body inertia
   (``--inertias``, kg m^2, all three axes), i.e. the wheels' torque J x 0.001 deg/s^2 against the boom's
   eq. (8) torque, for the shipped mounting (thrust line through the centre of mass at the nominal pose, up to
   0.08 N m from joint 3's lift) and a boom 1.5 m off it (1 N m); the largest inertia is a body the torque
   hardly moves (the torque off).
6. A Monte Carlo (``--mc`` pairs, boom and fixed on the same draw): joint 3 range, joint 1 range, thrust
   level, initial-orbit dispersion and the wheels' torque (the body inertia); the boom's time saving
   against each.

Writes ``studies/ma2023/results/transfer.md`` and ``transfer.png`` (the joint histories) and
``transfer-sweep.png`` (the slew-rate sweep).
"""

from __future__ import annotations

import os

os.environ.setdefault("XLA_FLAGS", f"--xla_force_host_platform_device_count={os.cpu_count() or 1}")

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import jax  # noqa: E402
import numpy as np  # noqa: E402

from geojax import transfer  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
PAPER = {"time_saving": 29.7, "fuel_saving": 22.9, "efficiency": 0.95, "track_deg": (0.017, 0.006, 0.011)}


def saving(boom, fixed):
    return 100.0 * (fixed - boom) / fixed


def saving_cell(m, key, b, f):
    """The boom's saving on ``key`` (rows b, f of metrics m) as a table cell: a value where both reached GEO, a
    bound on the time where one stopped at the time limit, else n/a (a transfer cut short used less)."""
    value = saving(m[key][b], m[key][f])
    boom_reached, fixed_reached = m["status"][b] == 1, m["status"][f] == 1
    if boom_reached and fixed_reached:
        return f"{value:+.1f} %"
    if key == "transfer_days" and (boom_reached or fixed_reached):
        return f"{'<' if fixed_reached else '>'} {value:+.1f} %"
    return "n/a"


def slew_sweep(rates):
    params, rows = [], []
    for rate in rates:
        for layout in ("boom", "fixed"):
            sc = transfer.load(f"ma2023-{layout}", {"attitude.slew_rate_deg_s": rate})
            params.append(sc.params)
            rows.append((rate, layout))
    metrics, records, wall_s, compile_s = transfer.run_batch(sc, transfer.stack(params))
    return rows, metrics, records, wall_s, compile_s


def gate_ablation(rates=(0.02, 0.03), gates=(10.0, 90.0)):
    params, rows = [], []
    for rate in rates:
        for gate in gates:
            for layout in ("boom", "fixed"):
                sc = transfer.load(f"ma2023-{layout}", {"attitude.slew_rate_deg_s": rate,
                                                         "transfer.max_misalignment_deg": gate})
                params.append(sc.params)
                rows.append((rate, gate, layout))
    metrics, _, _, _ = transfer.run_batch(sc, transfer.stack(params))
    return rows, metrics


# The boom's mounting (eq. (8)'s l_0 and the links of eq. (9)): the shipped one puts the thrust line through the
# centre of mass at the nominal pose; the earlier one put it 1.5 m off (d2) and 1.3 m below the body origin.
GEOMETRIES = {"through CoM": {},
              "off CoM": {"boom.d2_m": 1.5, "boom.a1_m": 0.3, "boom.base_offset_m": [0.0, 0.0, -1.0]}}


def torque_sweep(inertias, rates=(0.1, 0.02)):
    """The boom against the body inertia (the wheels' torque J x slew acceleration), at two slew rates, for each
    mounting of ``GEOMETRIES``."""
    params, rows = [], []
    for geometry, overrides in GEOMETRIES.items():
        for rate in rates:
            for inertia in inertias:
                sc = transfer.load("ma2023-boom", {**overrides, "attitude.slew_rate_deg_s": rate,
                                                    "attitude.inertia_kg_m2": [inertia] * 3})
                params.append(sc.params)
                rows.append((geometry, rate, inertia))
    metrics, _, _, _ = transfer.run_batch(sc, transfer.stack(params))
    return rows, metrics


def monte_carlo(pairs, slew_deg_s, seed=0):
    """Draws: J3 half-range 5-30 deg, J1 range [-90 s, 0] with s in 0.5-1, thrust 0.3-0.7 N, perigee +-50 km,
    apogee +-200 km, inclination +-0.5 deg (uniform), and the body inertia log-uniform in 2e3-2e5 kg m^2 (the
    wheels' torque 0.035-3.5 N m at 0.001 deg/s^2; drawn last, so the other draws are those of the runs
    before the torque acted)."""
    rng = np.random.default_rng(seed)
    draws = {"j3_half_deg": rng.uniform(5, 30, pairs), "j1_scale": rng.uniform(0.5, 1.0, pairs),
             "thrust_n": rng.uniform(0.3, 0.7, pairs), "dperigee_km": rng.uniform(-50, 50, pairs),
             "dapogee_km": rng.uniform(-200, 200, pairs), "di_deg": rng.uniform(-0.5, 0.5, pairs)}
    draws["log10_inertia"] = rng.uniform(np.log10(2e3), np.log10(2e5), pairs)
    params = []
    for j in range(pairs):
        overrides = {"attitude.slew_rate_deg_s": slew_deg_s,
                     "attitude.inertia_kg_m2": [10.0 ** draws["log10_inertia"][j]] * 3,
                     "boom.j3_deg": [-draws["j3_half_deg"][j], draws["j3_half_deg"][j]],
                     "boom.j1_deg": [-90.0 * draws["j1_scale"][j], 0.0], "thruster.thrust_n": draws["thrust_n"][j],
                     "orbit.perigee_alt_km": 964.0 + draws["dperigee_km"][j],
                     "orbit.apogee_alt_km": 35741.0 + draws["dapogee_km"][j], "orbit.i_deg": 20.8 + draws["di_deg"][j]}
        for layout in ("boom", "fixed"):
            sc = transfer.load(f"ma2023-{layout}", overrides)
            params.append(sc.params)
    metrics, _, wall_s, compile_s = transfer.run_batch(sc, transfer.stack(params), days=400.0)
    return draws, metrics, wall_s, compile_s


def joint_figure(path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    result = transfer.run(transfer.load("ma2023-boom"), days=1.0, record_every_s=120.0)
    r = result.records
    t = r["t_days"]
    fig, axes = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
    for j in range(3):
        axes[0].plot(t, r[f"target{j + 1}_deg"], label=f"joint {j + 1}")
        axes[1].plot(t, r[f"theta{j + 1}_deg"], label=f"joint {j + 1}")
        axes[2].plot(t, r[f"omega{j + 1}_deg_s"], label=f"joint {j + 1}")
        axes[3].plot(t, r[f"theta{j + 1}_deg"] - r[f"target{j + 1}_deg"], label=f"joint {j + 1}")
    axes[0].plot(t, r["body_azimuth_deg"], "k:", label="body azimuth")
    axes[0].plot(t, r["body_elevation_deg"], "k--", label="body elevation")
    titles = ["targets (inverse of eq. 9) and the body's share (Fig. 11)", "planned angles (Fig. 12)",
              "rates, deg/s (Fig. 13)", "planned minus target, deg (Fig. 14)"]
    for ax, title in zip(axes, titles):
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=5)
    axes[3].set_xlabel("days from GTO")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return result.metrics


def sweep_figure(rows, metrics, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rates = sorted({rate for rate, _ in rows})
    pick = lambda layout, key: [metrics[key][rows.index((r, layout))] for r in rates]  # noqa: E731
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for layout, style in (("boom", "o-"), ("fixed", "s--")):
        ax1.plot(rates, pick(layout, "transfer_days"), style, label=layout)
        ax2.plot(rates, pick(layout, "propellant_kg"), style, label=layout)
    for ax, label in ((ax1, "transfer time, days"), (ax2, "propellant, kg")):
        ax.set_xscale("log")
        ax.set_xlabel("body slew rate, deg/s")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        ax.legend()
    fig.suptitle("GTO-GEO, Ma 2023 Table 1: boom vs fixed thrusters against the body's slew rate", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rates", type=float, nargs="+", default=[0.01, 0.02, 0.03, 0.05, 0.1, 0.2])
    parser.add_argument("--mc", type=int, default=128, help="Monte Carlo pairs (0: skip)")
    parser.add_argument("--mc-slew", type=float, default=0.02,
                        help="body slew rate of the Monte Carlo, deg/s (default 0.02, where the boom's advantage shows)")
    parser.add_argument("--inertias", type=float, nargs="+", default=[2e3, 1e4, 6e4, 1e8],
                        help="body inertias of the coupling-torque sweep, kg m^2 (the scenarios': 2000)")
    args = parser.parse_args()
    RESULTS.mkdir(exist_ok=True)
    start = time.perf_counter()
    rows, m, _, wall_s, compile_s = slew_sweep(args.rates)
    print(f"slew sweep: {len(rows)} transfers in {wall_s:.0f} s ({compile_s:.0f} s compiling)", flush=True)
    base = {layout: rows.index((0.1, layout)) for layout in ("boom", "fixed")} if 0.1 in args.rates else None
    fine = transfer.run(transfer.load("ma2023-boom", {"integration.step_s": 60.0})).metrics
    track = joint_figure(RESULTS / "transfer.png")
    sweep_figure(rows, m, RESULTS / "transfer-sweep.png")

    lines = ["# Ma & Kong 2023: GTO-GEO transfer, triple orthogonal gimbaled boom vs fixed thrusters", "",
             "`python studies/ma2023/transfer.py` (full transfers, the full force model with the conical shadow, "
             f"RK4 in MEE at 120 s; {jax.device_count()} XLA CPU devices). Spacecraft and drive values are the "
             "marked choices of `geojax/scenarios/ma2023-boom.toml`.", ""]
    if base:
        b, f = base["boom"], base["fixed"]
        attitude = transfer.load("ma2023-boom").config["attitude"]
        inertia, accel = attitude["inertia_kg_m2"][0], attitude["slew_accel_deg_s2"]
        wheel_nm = inertia * np.deg2rad(accel)
        lines += ["## Baseline (body slew 0.1 deg/s, 0.001 deg/s^2)", "",
                  "| quantity | boom | fixed | boom saving | Ma 2023 |", "|---|---:|---:|---:|---|"]
        for key, label, paper in (("transfer_days", "transfer time, days", f"{PAPER['time_saving']} % less time"),
                                  ("propellant_kg", "propellant, kg", f"{PAPER['fuel_saving']} % less fuel"),
                                  ("dv_mps", "Delta-V, m/s", ""), ("firing_days", "firing, days", ""),
                                  ("lost_to_slew_days", "firing lost to slewing, days", "")):
            lines.append(f"| {label} | {m[key][b]:.1f} | {m[key][f]:.1f} | {saving_cell(m, key, b, f)} | {paper} |")
        lines.append(f"| eq. (8) torque beyond the wheels, days | {m['torque_overpowered_days'][b]:.1f} | "
                     f"{m['torque_overpowered_days'][f]:.1f} | | |")
        lines.append(f"| eq. (8) impulse (integral of its norm), N m s | {m['torque_impulse_nms'][b]:.3g} | "
                     f"{m['torque_impulse_nms'][f]:.3g} | | |")
        lines.append(f"| thrust efficiency (delivered / asked, slews and cosines) | {m['thrust_efficiency'][b]:.4f} | "
                     f"{m['thrust_efficiency'][f]:.4f} | | {PAPER['efficiency']} (boom) |")
        lines.append(f"| cosine efficiency while firing | {m['cosine_efficiency'][b]:.4f} | "
                     f"{m['cosine_efficiency'][f]:.4f} | | |")
        lines.append(f"| status | {int(m['status'][b])} | {int(m['status'][f])} | | |")
        lines += ["", "Joint tracking over the whole boom transfer (targets that move no faster than the drive; "
                  "Fig. 14: 0.017 / 0.006 / 0.011 deg):", "",
                  "| joint | max deg | RMS deg | Ma 2023 deg |", "|---|---:|---:|---:|"]
        for j in range(3):
            lines.append(f"| {j + 1} | {m[f'j{j + 1}_track_max_deg'][b]:.4f} | {m[f'j{j + 1}_track_rms_deg'][b]:.4f} | "
                         f"{PAPER['track_deg'][j]} |")
        lines += ["", f"First day only (`transfer.png`): max {track['j1_track_max_deg']:.4f} / "
                  f"{track['j2_track_max_deg']:.4f} / {track['j3_track_max_deg']:.4f} deg, RMS "
                  f"{track['j1_track_rms_deg']:.4f} / {track['j2_track_rms_deg']:.4f} / {track['j3_track_rms_deg']:.4f} "
                  f"deg. Largest coupling torque (eq. 8): {m['max_coupling_torque_nm'][b]:.3f} N m, against the "
                  f"wheels' {wheel_nm:.3f} N m ({inertia:g} kg m^2 x {accel:g} deg/s^2).", "",
                  "## Step accuracy", "",
                  f"Boom baseline at 60 s: {fine['transfer_days']:.3f} days, {fine['propellant_kg']:.2f} kg "
                  f"(120 s: {m['transfer_days'][b]:.3f} days, {m['propellant_kg'][b]:.2f} kg): differences "
                  f"{abs(fine['transfer_days'] - m['transfer_days'][b]):.3f} days, "
                  f"{abs(fine['propellant_kg'] - m['propellant_kg'][b]):.2f} kg.", ""]
    lines += ["## Slew-rate sweep (`transfer-sweep.png`)", "",
              "| body slew deg/s | boom days | fixed days | time saving | boom kg | fixed kg | fuel saving | "
              "lost to slew boom / fixed, days | thrust efficiency boom / fixed | status boom / fixed |",
              "|---:|---:|---:|---:|---:|---:|---:|---|---|---|"]
    for rate in args.rates:
        b, f = rows.index((rate, "boom")), rows.index((rate, "fixed"))
        lines.append(f"| {rate:g} | {m['transfer_days'][b]:.1f} | {m['transfer_days'][f]:.1f} | "
                     f"{saving_cell(m, 'transfer_days', b, f)} | {m['propellant_kg'][b]:.1f} | "
                     f"{m['propellant_kg'][f]:.1f} | {saving_cell(m, 'propellant_kg', b, f)} | "
                     f"{m['lost_to_slew_days'][b]:.1f} / {m['lost_to_slew_days'][f]:.1f} | "
                     f"{m['thrust_efficiency'][b]:.3f} / {m['thrust_efficiency'][f]:.3f} | "
                     f"{int(m['status'][b])} / {int(m['status'][f])} |")
    torque_rows, q = torque_sweep(args.inertias)
    accel_deg_s2 = transfer.load("ma2023-boom").config["attitude"]["slew_accel_deg_s2"]
    lines += ["", "## Coupling torque (eq. 8) on the body: the boom against the wheels' torque", "",
              f"The wheels' torque is J x {accel_deg_s2:g} deg/s^2 (J the body inertia, all three axes); the boom's "
              "eq. (8) torque, for the shipped mounting (the thrust line through the centre of mass at the nominal pose: "
              "only joint 3's lift leaves a lever) and for a boom whose thrust line passes 1.5 m off it (d2 = 1.5 m, "
              "a1 = 0.3 m, base 1 m out on -W). The fixed layout has no torque.", "",
              "| mounting | body slew deg/s | inertia kg m^2 | wheel torque N m | largest eq. (8) N m | boom days | "
              "boom kg | lost to slew, days | torque beyond the wheels, days | eq. (8) impulse, N m s | "
              "thrust efficiency | J1 / J3 track RMS deg | status |",
              "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|"]
    for k, (geometry, rate, inertia) in enumerate(torque_rows):
        lines.append(f"| {geometry} | {rate:g} | {inertia:.0e} | {inertia * np.deg2rad(accel_deg_s2):.3g} | "
                     f"{q['max_coupling_torque_nm'][k]:.3f} | "
                     f"{q['transfer_days'][k]:.1f} | {q['propellant_kg'][k]:.1f} | {q['lost_to_slew_days'][k]:.1f} | "
                     f"{q['torque_overpowered_days'][k]:.1f} | {q['torque_impulse_nms'][k]:.3g} | "
                     f"{q['thrust_efficiency'][k]:.3f} | "
                     f"{q['j1_track_rms_deg'][k]:.4f} / {q['j3_track_rms_deg'][k]:.4f} | {int(q['status'][k])} |")
    gate_rows, g = gate_ablation()
    lines += ["", "## Firing gate: wait for the pointing (10 deg) or fire misaligned (90 deg)", "",
              "| body slew deg/s | gate deg | boom days / kg | fixed days / kg | time saving | fuel saving | "
              "cosine efficiency boom / fixed |", "|---:|---:|---|---|---:|---:|---|"]
    for rate, gate in dict.fromkeys((r, gt) for r, gt, _ in gate_rows):
        b, f = gate_rows.index((rate, gate, "boom")), gate_rows.index((rate, gate, "fixed"))
        lines.append(f"| {rate:g} | {gate:g} | {g['transfer_days'][b]:.1f} / {g['propellant_kg'][b]:.1f} | "
                     f"{g['transfer_days'][f]:.1f} / {g['propellant_kg'][f]:.1f} | "
                     f"{saving_cell(g, 'transfer_days', b, f)} | {saving_cell(g, 'propellant_kg', b, f)} | "
                     f"{g['cosine_efficiency'][b]:.3f} / {g['cosine_efficiency'][f]:.3f} |")
    if args.mc:
        draws, mc, mc_wall, mc_compile = monte_carlo(args.mc, args.mc_slew)
        b, f = mc["transfer_days"][0::2], mc["transfer_days"][1::2]
        fb, ff = mc["propellant_kg"][0::2], mc["propellant_kg"][1::2]
        time_saving, fuel_saving = saving(b, f), saving(fb, ff)
        both = (mc["status"][0::2] == 1) & (mc["status"][1::2] == 1)
        done = both if both.any() else np.ones_like(both)
        pairs_note = (f"the {int(done.sum())} pairs where both reached GEO" if both.any()
                      else "all pairs (none where both reached GEO)")
        reached = (mc["status"] == 1).mean()
        boom_reached, fixed_reached = (mc["status"][0::2] == 1).mean(), (mc["status"][1::2] == 1).mean()
        lines += ["", f"## Monte Carlo ({args.mc} pairs, {2 * args.mc} transfers in one compilation, "
                  f"{mc_wall:.0f} s)", "",
                  "Draws (uniform): joint 3 half-range 5-30 deg, joint 1 range [-90 s, 0] deg with s in 0.5-1, thrust "
                  "0.3-0.7 N, perigee +-50 km, apogee +-200 km, inclination +-0.5 deg, body inertia log-uniform "
                  "2e3-2e5 kg m^2 (wheel torque 0.035-3.5 N m); body slew "
                  f"{args.mc_slew:g} deg/s; "
                  f"400-day limit. {100 * reached:.0f} % of the transfers reached GEO (boom "
                  f"{100 * boom_reached:.0f} %, fixed {100 * fixed_reached:.0f} %).",
                  "",
                  f"Boom time saving: mean {time_saving.mean():+.2f} %, range {time_saving.min():+.2f} to "
                  f"{time_saving.max():+.2f} %; fuel saving over {pairs_note}: "
                  f"mean {fuel_saving[done].mean():+.2f} %, range {fuel_saving[done].min():+.2f} to "
                  f"{fuel_saving[done].max():+.2f} %.", "",
                  "Correlation of the time saving with each draw (Pearson r):", "", "| draw | r |", "|---|---:|"]
        for key, values in draws.items():
            lines.append(f"| {key} | {np.corrcoef(values, time_saving)[0, 1]:+.2f} |")
    lines += ["", f"Total {time.perf_counter() - start:.0f} s."]
    (RESULTS / "transfer.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
