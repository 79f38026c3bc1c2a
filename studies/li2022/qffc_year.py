"""One year of QFFC station keeping on li2022 (normal limits), beside Li 2022 Table 2.

    python studies/li2022/qffc_year.py [--limits normal|weak|strong] [--out studies/li2022/results]

Burns are not yet suspended in Earth shadow and there are no orbit or
attitude errors (see geojax/simulate.py); the table says so.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from geojax import constants as c
from geojax import run, scenario
from geojax.control.predictor import reference
from geojax.propagate import environment_grid, steps_per_cycle
from geojax.propulsion import PRESETS_DEG, arm_limits_deg
from geojax.simulate import LoopParams, rollout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limits", choices=sorted(PRESETS_DEG), default="normal")
    parser.add_argument("--days", type=int, default=365)
    parser.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = parser.parse_args()
    start = time.perf_counter()
    sc = scenario.load("li2022")
    n = steps_per_cycle(sc.step_s)
    h = c.SIDEREAL_DAY_S / n
    env = environment_grid(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s, h, args.days + 1, n)
    state = run.initial_state(sc)
    ref = jax.jit(lambda s, e: reference(s, e, sc.force_model, h))(state, env)
    cfg = sc.config
    params = LoopParams(
        arm_limits_deg(*PRESETS_DEG[args.limits]), jnp.asarray(cfg["thrusters"]["thrust_n"]),
        jnp.asarray(cfg["thrusters"]["isp_s"]), jnp.asarray(30.0),
        jnp.array([np.radians(cfg["station"]["lon_deg"]), 0.0, cfg["station"]["ex"], cfg["station"]["ey"],
                   cfg["station"]["ix"], cfg["station"]["iy"]]),
    )
    cycles = jax.tree_util.tree_map(lambda x: x[: args.days], env)
    final, rec = jax.jit(lambda s, e, p: rollout(s, e, sc.force_model, h, ref, p))(state, cycles, params)
    wall = time.perf_counter() - start
    m = rec.means
    dv_year = float(final.dv_mps) * 365.25 * 86400 / (args.days * c.SIDEREAL_DAY_S)
    burns = np.asarray(rec.burn_s) > 0
    after = slice(3, None)  # after acquisition
    rows = [
        ("ΔV per year (m/s/yr)", f"{dv_year:.1f}", "60.2"),
        ("burns per thruster per orbit", f"{burns.mean():.3f}", "0.997"),
        ("burns in total", f"{int(burns.sum())}", "728"),
        ("max abs(mean λ − 96°) after 3 cycles (°)", f"{np.max(np.abs(np.degrees(m.lon_rad[after]) - 96)):.4f}", "≈ 0.013"),
        ("max norm(mean e − e_T)", f"{np.max(np.hypot(m.ex - cfg['station']['ex'], m.ey - cfg['station']['ey'])):.2e}", "≈ 1.1e-4"),
        ("max norm(mean i − i_T), (h, k), after 3 cycles", f"{np.max(np.hypot(m.ix[after] - cfg['station']['ix'], m.iy[after] - cfg['station']['iy'])):.2e}", "–"),
        ("cycles with no QFFC solution", f"{int((~np.asarray(rec.burns.feasible)).sum())}", "–"),
        ("wall time, 1 CPU sample (s)", f"{wall:.1f}", "0.09 s per orbit (Fortran)"),
    ]
    lines = [f"# li2022, QFFC, {args.limits} limits, {args.days} cycles", "",
             "No shadow suspension of burns, no orbit or attitude errors yet.", "",
             "| quantity | geojax | Li 2022 (Table 2, Sec. 5.1) |", "|---|---|---|"]
    lines += [f"| {a} | {b} | {p} |" for a, b, p in rows]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"qffc_year_{args.limits}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
