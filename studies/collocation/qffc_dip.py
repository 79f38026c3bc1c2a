"""Why the QFFC's year of ``collocation-4`` comes closest near the June solstice (``cluster_year_qffc.md``: 5.59
km on days 175.6-176.6, pairs A_B and C_D, in 25 of 64 clusters, against 8.3 km at the median): the pairs'
relative e and i vectors and longitude offset per cycle around those days, with and without Li's errors.

    python studies/collocation/qffc_dip.py [--days 182] [--seeds 3] [--out studies/collocation/results]

``collocation-4`` under the QFFC for ``--days`` (the dip lies before day 182), once without errors and for
``--seeds`` seeds with Li's nominal errors (H_rv = H_att = 1).  Per pair and cycle: the least true separation,
the relative mean e vector's and i vector's magnitudes (a·|δe|, 2a·|δi|, km: the radial and cross-track
amplitudes of the linearised relative motion), the angle between them (0 or 180 deg: parallel, the safe
geometry whose least distance is a·|δe|) and the mean longitude offset (a·δλ, km).  Writes ``qffc_dip.md`` and
``.json`` into ``--out``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import geojax
from geojax import scenario
from geojax.collocation import run
from geojax.control.effects import R_SYNC_M
from geojax.loop.cluster import pairs

HERE = Path(__file__).resolve().parent


def pair_table(r) -> dict:
    """Per pair (by name) and cycle: separation, a|de|, 2a|di|, the angle between de and di, a dlon (km, deg)."""
    means = r.satellites.records.cycles.means
    e = np.stack([np.asarray(means.ex), np.asarray(means.ey)], -1)  # [satellite, cycle, 2]
    i = np.stack([np.asarray(means.ix), np.asarray(means.iy)], -1)
    lon = np.asarray(means.lon_rad)
    out = {}
    for k, (name, (a, b)) in enumerate(zip(r.pair_names, pairs(len(r.names)))):
        de, di = e[a] - e[b], i[a] - i[b]
        cross = de[:, 0] * di[:, 1] - de[:, 1] * di[:, 0]
        angle = np.degrees(np.arctan2(cross, np.sum(de * di, -1)))
        out[name] = {"separation_km": r.separation.min_m[:, k] / 1e3,
                     "a_de_km": R_SYNC_M * np.linalg.norm(de, axis=-1) / 1e3,
                     "two_a_di_km": 2 * R_SYNC_M * np.linalg.norm(di, axis=-1) / 1e3,
                     "angle_deg": angle, "a_dlon_km": R_SYNC_M * np.angle(np.exp(1j * (lon[a] - lon[b]))) / 1e3}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=182.0)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--out", type=Path, default=HERE / "results")
    args = parser.parse_args()
    runs, start = {}, time.perf_counter()
    for errors in (0.0, 1.0):
        sc = scenario.load("collocation-4", {"duration.days": args.days, "errors.h_rv": errors,
                                             "errors.h_att": errors})
        for seed in range(1 if errors == 0 else args.seeds):
            r = run.simulate_cluster(sc, seed=seed)
            m = r.metric_table()
            label = "no errors" if errors == 0 else f"Li's errors, seed {seed}"
            runs[label] = {"min_separation_km": m["min_separation_km"], "day": m["min_separation_day"],
                           "pair": r.pair_names[int(m["min_separation_pair"])], "pairs": pair_table(r)}
    wall_s = time.perf_counter() - start
    command = f"python studies/collocation/qffc_dip.py --days {args.days:g} --seeds {args.seeds}"
    worst = min(runs, key=lambda k: runs[k]["min_separation_km"])
    day = int(runs[worst]["day"])
    cycles = range(max(day - 4, 0), min(day + 4, int(args.days)))
    lines = ["# collocation-4 under the QFFC: the separation near the June solstice", "",
             f"`{command}` ({wall_s / 60:.0f} min, geojax {geojax.__version__}).", "",
             "| run | least separation (km) | day | pair |", "|---|---:|---:|---|"]
    lines += [f"| {k} | {v['min_separation_km']:.3f} | {v['day']:.2f} | {v['pair']} |" for k, v in runs.items()]
    for label in dict.fromkeys(["no errors", worst]):
        for pair in ("A_B", "C_D", "A_D"):
            t = runs[label]["pairs"][pair]
            lines += ["", f"{label}, pair {pair}, per cycle (day = cycle start):", "",
                      "| day | least separation (km) | a·‖δe‖ (km) | 2a·‖δi‖ (km) | angle δe to δi (deg) | "
                      "a·δλ (km) |",
                      "|---:|---:|---:|---:|---:|---:|"]
            lines += [f"| {c} | {t['separation_km'][c]:.3f} | {t['a_de_km'][c]:.3f} | {t['two_a_di_km'][c]:.3f} | "
                      f"{t['angle_deg'][c]:.1f} | {t['a_dlon_km'][c]:.3f} |" for c in cycles]
    data = {"command": command, "wall_s": wall_s, "runs": {
        k: {**{key: v[key] for key in ("min_separation_km", "day", "pair")},
            "pairs": {p: {q: np.asarray(x).tolist() for q, x in t.items()} for p, t in v["pairs"].items()}}
        for k, v in runs.items()}}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "qffc_dip.json").write_text(json.dumps(data))
    (args.out / "qffc_dip.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
