"""How accurate is the FOMPC's state predictor over N cycles, against the true propagation?

    python studies/ablation/li_predictor_error.py [--days 365.25] [--horizon 10]

Li 2022 (Sec. 4.3) explains the optimum of the horizon N (Fig. 13: 3 / 6 / 7 under weak / normal /
strong limits) by the state predictor losing accuracy as N grows.  Our optimum does not move with the
limits, so this script measures our predictor's open-loop error.

For one year of ``li2022-qffc`` and ``li2022-fompc`` (normal limits, no determination or attitude errors,
so the estimate is the truth's mean elements), at every cycle k the predictor of eq. (25) is run N cycles
ahead from the true mean state x_k: the natural drift from the uncontrolled reference (eqs. (26)-(27),
``control.predictor.predict_next``) plus the linear effect of the burns actually delivered in cycles
k .. k+N-1 (eq. (23), ``control.qffc.effect``, each burn's delivered ΔV from the cycle's record), and
compared with the true mean state x_{k+N} (``predictor.estimate_mean`` of the true osculating state at
that boundary, the same definition the controller reads).  Nothing here feeds back: the error is the
model's alone (linear impulsive burns against finite burns with shadow interruptions; the reference's
drift against the controlled orbit's).

A second predictor is Li's as printed: eq. (22)'s longitude entry of a tangential burn, -3 c_i / V_s
(ours, from the dynamics, -6 pi c_i / V_s: ``control.effects``), and eq. (27)'s drift step
Δλ = λ̇_{k-1} T_s (ours adds half the cycle's change of drift).  If Li's simulations used the printed
model, this is the accuracy its state predictor had.

Writes ``results/li_predictor_error.md``, ``.json`` and ``.png``: per N, the RMS and the largest error
of longitude (deg), drift (deg/day), eccentricity vector and inclination vector (MEE (h, k), the units of
Δi_max = 8e-5), over every start k of the year.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import geojax
from geojax import plots
from geojax.control import qffc
from geojax.control.effects import V_SYNC_MPS, remaining_fraction
from geojax.control.predictor import estimate_mean, predict_next
from geojax.runner.setup import controller_of, prepare
from geojax.physics.elements import wrap_angle

HERE = Path(__file__).resolve().parent
DI_MAX = 8e-5  # li2022-fompc's Δi_max, MEE (h, k)


def true_l_start(boundary, earth_angle_rad):
    """True longitude L at each cycle start from (lon, a, f, g, h, k): lon + θ = L - 2 f sin L + 2 g cos L."""
    mean_lon = boundary[:, 0] + earth_angle_rad
    f, g = boundary[:, 2], boundary[:, 3]
    true_lon = mean_lon
    for _ in range(3):  # fixed point, e ~ 1e-4
        true_lon = mean_lon + 2 * f * np.sin(true_lon) - 2 * g * np.cos(true_lon)
    return true_lon


def delivered_burns(cycles):
    """Each cycle's BurnPair with the ΔV actually delivered (the cycle's ΔV shared by the burns' fired times)."""
    c = cycles.controller
    burns, fired_s = c["burns"], c["fired_s"]
    share = np.where(fired_s.sum(1, keepdims=True) > 0, fired_s / np.maximum(fired_s.sum(1, keepdims=True), 1e-30), 0.0)
    v = cycles.dv_mps[:, None] * share
    unit = burns.dv_rsw_mps / np.maximum(burns.v_mps, 1e-30)[..., None]
    return burns._replace(dv_rsw_mps=unit * v[..., None], v_mps=v, feasible=np.ones_like(burns.feasible))


def predictor_errors(controller: str, days: float, horizon: int) -> dict:
    sc = geojax.load_scenario(f"li2022-{controller}", {"duration.days": days, "errors.h_rv": 0.0, "errors.h_att": 0.0})
    result = geojax.simulate(sc)
    cycles = result.records.cycles
    # the reference as the controller reads it, each cycle's window widened to the horizon
    batch = prepare([sc], dataclasses.replace(controller_of([sc]), reference_cycles=horizon + 1))
    ref = batch.shared.reference
    mu = float(result.params.forces.mu_m3_s2)
    cycle_s = batch.step_s * batch.shared.env.earth_angle_rad.shape[1]
    n = cycles.boundary.shape[0]
    ref_osc, ref_window = np.asarray(ref.osc), jnp.asarray(ref.window)
    truth = np.asarray(jax.vmap(estimate_mean, (0, 0, 0, None))(cycles.boundary, ref_osc[:n], ref_window[:n, 0], mu))
    l_start = true_l_start(cycles.boundary, np.asarray(batch.shared.env.earth_angle_rad[:n, 0, 0]))
    burns = delivered_burns(cycles)
    kicks = jax.vmap(qffc.effect)(burns, l_start)  # [n, 6]
    # Li's printed eq. (22): the tangential burn's longitude entry -3 c_i / V_s instead of -6 pi c_i / V_s
    c_i = np.asarray(remaining_fraction(burns.l_rad, l_start[:, None]))
    printed_lon = np.sum(3 * c_i * burns.dv_rsw_mps[..., 1] * (2 * np.pi - 1) / V_SYNC_MPS, axis=1)
    kicks_printed = kicks.at[:, 0].add(printed_lon)

    def ahead(kicks, printed):
        @jax.jit
        def predict(x, k0):
            """x_{k0+N} predicted from x = x_{k0}, N = 1 .. horizon."""
            def one(x, j):
                k = k0 + j
                x_next = predict_next(x, ref_window[k0, j], ref_window[k0, j + 1], cycle_s)
                if printed:  # eq. (27): the drift of the cycle before, no change over the cycle
                    x_next = x_next.at[0].set(x[0] + cycle_s * x[1])
                x = x_next + kicks[k]
                return x, x
            return jax.lax.scan(one, x, jnp.arange(horizon))[1]
        return jax.vmap(predict)

    starts = np.arange(n - horizon)
    actual = truth[starts[:, None] + np.arange(1, horizon + 1)[None, :]]
    out = {"controller": controller, "dv_per_year_mps": float(result.metrics["dv_per_year_mps"]), "starts": int(len(starts)),
           "mean_burn_di_mee": float(np.mean(np.hypot(kicks[:, 4], kicks[:, 5])))}
    for label, model in (("ours", ahead(kicks, False)), ("printed", ahead(kicks_printed, True))):
        out[label] = errors(np.asarray(model(truth[starts], starts)) - actual)
    return out


def errors(err) -> dict:
    """RMS and largest error per N of longitude, drift, e and i from state errors [k, N, 6]."""
    err[..., 0] = np.asarray(wrap_angle(err[..., 0]))
    quantities = {
        "lon_deg": np.degrees(np.abs(err[..., 0])),
        "drift_deg_per_day": np.degrees(np.abs(err[..., 1])) * 86400.0,
        "e": np.hypot(err[..., 2], err[..., 3]),
        "i_mee": np.hypot(err[..., 4], err[..., 5]),
    }
    return {name: {"rms": np.sqrt(np.mean(values**2, axis=0)).tolist(), "max": values.max(axis=0).tolist()}
            for name, values in quantities.items()}


def markdown(rows, args) -> str:
    lines = ["# The FOMPC's state predictor over N cycles against the true propagation (issue 20)", "",
             f"`python studies/ablation/li_predictor_error.py --days {args.days:g} --horizon {args.horizon}`: "
             "li2022, normal limits, no determination or attitude errors; at every cycle k the predictor "
             "(reference drift + linear effect of the burns actually delivered) N cycles ahead from the true mean "
             "state, against the true mean state N cycles later.  RMS (largest) over the year's starts.", ""]
    for row in rows:
        lines += [f"## {row['controller'].upper()} ({row['dv_per_year_mps']:.2f} m/s/yr, {row['starts']} starts; "
                  f"mean per-cycle inclination change by the burns {row['mean_burn_di_mee']:.2e})", "",
                  "| N | longitude deg | drift deg/day | e | i (MEE h, k) | i error / Δi_max | longitude deg, Li's printed model |",
                  "|---:|---:|---:|---:|---:|---:|---:|"]
        ours, printed = row["ours"], row["printed"]
        for k in range(args.horizon):
            cell = lambda e, q: f"{e[q]['rms'][k]:.2e} ({e[q]['max'][k]:.2e})"  # noqa: E731
            lines.append(f"| {k + 1} | {cell(ours, 'lon_deg')} | {cell(ours, 'drift_deg_per_day')} | {cell(ours, 'e')} | "
                         f"{cell(ours, 'i_mee')} | {ours['i_mee']['rms'][k] / DI_MAX:.3f} | {cell(printed, 'lon_deg')} |")
        lines.append("")
    return "\n".join(lines)


@plots.styled
def figure(rows, path):
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(7.0, 3.0))
    for row in rows:
        n = np.arange(1, len(row["ours"]["lon_deg"]["rms"]) + 1)
        name = row["controller"].upper()
        axes[0].semilogy(n, row["ours"]["lon_deg"]["rms"], marker="o", label=name)
        axes[0].semilogy(n, row["printed"]["lon_deg"]["rms"], marker="x", linestyle=":", label=f"{name}, Li's printed model")
        axes[1].semilogy(n, row["ours"]["i_mee"]["rms"], marker="o", label=name)
    axes[1].axhline(DI_MAX, color="0.5", linestyle="--", label="Δi_max")
    axes[0].set(xlabel="cycles ahead N", ylabel="RMS longitude error (deg)")
    axes[1].set(xlabel="cycles ahead N", ylabel="RMS inclination error (MEE)")
    axes[0].legend()
    axes[1].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=365.25)
    parser.add_argument("--horizon", type=int, default=10)
    args = parser.parse_args()
    rows = [predictor_errors(c, args.days, args.horizon) for c in ("qffc", "fompc")]
    out = HERE / "results"
    out.mkdir(exist_ok=True)
    (out / "li_predictor_error.json").write_text(json.dumps(rows, indent=1))
    (out / "li_predictor_error.md").write_text(markdown(rows, args))
    figure(rows, out / "li_predictor_error.png")
    print((out / "li_predictor_error.md").read_text())


if __name__ == "__main__":
    main()
