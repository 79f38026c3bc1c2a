"""A cluster's figures: every satellite's e and i vectors (cycle means) against its target, and the least
separation of every pair per cycle with the alert distance."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from geojax.plots import plt
from geojax.plots.style import _save, styled

DAY_S = 86400.0


@styled
def plot_vectors(names, cycles: list[dict], targets: list[dict], path: str | Path, title: str = "",
                 dpi: int = 150) -> Path:
    """The e-vector plane (MEE f, g) and the i-vector plane (MEE h, k) of every satellite: its cycle means as a
    line and its target as a cross (``cycles``: each satellite's ``/cycles``; ``targets``: its ``station``)."""
    fig, axes = plt.subplots(1, 2, figsize=(7.2, 3.6), constrained_layout=True)
    for k, (name, cyc, target) in enumerate(zip(names, cycles, targets)):
        for ax, (x, y) in zip(axes, (("ex", "ey"), ("ix", "iy"))):
            ax.plot(np.asarray(cyc[x]) * 1e4, np.asarray(cyc[y]) * 1e4, "-", lw=0.8, color=f"C{k}", label=name,
                    gid=f"{name}_{x}")
            ax.plot(target[x] * 1e4, target[y] * 1e4, "x", ms=8, color=f"C{k}", gid=f"{name}_{x}_target")
    for ax, (x, y), keys in zip(axes, (("e_x", "e_y"), ("i_x (h)", "i_y (k)")), (("ex", "ey"), ("ix", "iy"))):
        values = [np.abs(np.asarray(c[key])) for c in cycles for key in keys]
        values += [abs(t[key]) for t in targets for key in keys]
        reach = 1.15e4 * max(float(np.max(v)) for v in values) or 1.0  # a square around every vector
        ax.set(xlabel=f"{x} (10⁻⁴)", ylabel=f"{y} (10⁻⁴)", xlim=(-reach, reach), ylim=(-reach, reach),
               aspect="equal")
    axes[0].set_title("eccentricity vectors (x: targets)", loc="left")
    axes[1].set_title("inclination vectors", loc="left")
    axes[1].legend(loc="best", frameon=False)
    return _save(fig, list(axes), title, path, dpi)


@styled
def plot_separation(pair_names, min_km: np.ndarray, cycle_s: float, alert_km: float, path: str | Path,
                    title: str = "", dpi: int = 150) -> Path:
    """Every pair's least true distance per cycle (``min_km`` [cycle, pair]) and the alert distance."""
    fig, ax = plt.subplots(figsize=(7.2, 3.2), constrained_layout=True)
    days = (np.arange(min_km.shape[0]) + 0.5) * cycle_s / DAY_S
    for k, pair in enumerate(pair_names):
        ax.plot(days, min_km[:, k], "o-", ms=2, lw=0.8, label=pair.replace("_", "–"), gid=pair)
    ax.axhline(alert_km, color="C3", ls="--", lw=0.9, label=f"alert {alert_km:g} km", gid="alert")
    ax.set(xlabel="days", ylabel="least separation in the cycle (km)", ylim=(0, None))
    ax.legend(loc="best", frameon=False, ncol=3)
    return _save(fig, [ax], title, path, dpi)
