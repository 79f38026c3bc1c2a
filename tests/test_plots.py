"""Figures: the ground-track reconstruction against Kepler's equation; files are written."""

import jax.numpy as jnp
import numpy as np

from geojax.physics import constants as c
from geojax import plots
from geojax.control.effects import R_SYNC_M
from geojax.physics.elements import kepler_to_cartesian, kepler_to_mee
from geojax.plots.parts import plot_consistency, plot_navigation_error, plot_wheels


def test_libration_matches_keplers_equation_to_second_order():
    # Independent: a Keplerian orbit sampled in mean anomaly (Kepler's equation by Newton), its
    # right ascension minus mean longitude and its latitude, against the first-order MEE formula.
    e, i, raan, argp = 2e-4, np.radians(0.05), 1.1, 2.3
    mean_anomaly = np.linspace(0, 2 * np.pi, 97)
    ecc_anomaly = mean_anomaly.copy()
    for _ in range(20):
        ecc_anomaly -= (ecc_anomaly - e * np.sin(ecc_anomaly) - mean_anomaly) / (1 - e * np.cos(ecc_anomaly))
    nu = 2 * np.arctan2(np.sqrt(1 + e) * np.sin(ecc_anomaly / 2), np.sqrt(1 - e) * np.cos(ecc_anomaly / 2))
    r, _ = kepler_to_cartesian(R_SYNC_M, e, i, raan, argp, jnp.asarray(nu), c.MU_EARTH_M3_S2)
    r = np.asarray(r)
    ra = np.arctan2(r[..., 1], r[..., 0])
    lat = np.arcsin(r[..., 2] / np.linalg.norm(r, axis=-1))
    d_lon = np.angle(np.exp(1j * (ra - (raan + argp + mean_anomaly))))
    mee = np.asarray(kepler_to_mee(R_SYNC_M, e, i, raan, argp, 0.0))
    model_lon, model_lat = plots.libration_rad(raan + argp + nu, *mee[1:5])
    # Residuals are O(e^2, i^2) ~ 1e-7 rad against amplitudes 2e = i = 4e-4 and 8.7e-4 rad.
    assert np.max(np.abs(d_lon - model_lon)) < 3e-7
    assert np.max(np.abs(lat - model_lat)) < 3e-7
    assert np.max(np.abs(model_lat)) > 8e-4


# ---------------------------------------------------------------- every figure kind, from synthetic results
# Magnitudes as in a real run: longitude near 96 deg E varying by 1e-3 deg, e and i components 1e-5 to 1e-4,
# thrust about 1e-6 m/s^2.  Each figure is written as PDF and PNG; its figures are kept (``plt.close`` patched)
# and drawn, to read back what a reader sees: no offset text on any axes, a label on both axes of every panel.

import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

DAY = 86164.0905


def _cycles(n=40, controlled=True):
    t = np.arange(n) * DAY
    phase = 2 * np.pi * np.arange(n) / 365.25
    wobble = 1e-3 * np.sin(np.arange(n) / 3.0)
    scale = 1e-6 if controlled else 1e-4
    table = {"t_s": t, "lon_deg": 96.0 + wobble, "drift_deg_per_day": 1e-4 * np.cos(np.arange(n) / 3.0),
             "ex": scale * np.cos(phase), "ey": 1e-4 + scale * np.sin(phase), "ix": 3e-6 + 2e-6 * np.sin(phase),
             "iy": 3e-5 + 1e-6 * np.cos(phase), "a_m": 42164.17e3 + 50.0 * np.sin(np.arange(n) / 5.0)}
    table.update(dv_ns_mps=0.05 + 0.01 * np.sin(phase), v1_mps=0.04 + 0 * t, v2_mps=0.03 + 0 * t)
    return table


def _reference(n=41):
    phase = 2 * np.pi * np.arange(n) / 365.25
    return {"t_s": np.arange(n) * DAY, "lon_deg": 96.0 + 0.02 * np.arange(n) ** 2 / n,
            "ex": 1e-4 * np.sin(3 * phase), "ey": 1e-4 * np.cos(3 * phase), "ix": 2e-4 * np.arange(n) / n,
            "iy": 3e-5 + 1e-4 * np.arange(n) / n}


TARGET = {"lon_deg": 96.0, "ex": 0.0, "ey": 1e-4, "ix": 0.0, "iy": 3e-5}


def _steps(days=3.0, step_s=900.0):
    t = np.arange(int(days * 86400 / step_s)) * step_s
    turn = 2 * np.pi * t / DAY
    return {"t_s": t, "dlon_deg": 0.03 * np.sin(turn / 5) + 0.005 * np.sin(turn), "lat_deg": 0.02 * np.sin(turn),
            # u_x at rounding level, as a real run's x axis can be: it must not bring a 1e-16 scale along.
            "ux_mps2": 1e-22 * np.sin(7 * turn), "uy_mps2": 2e-6 * np.cos(turn),
            "uz_mps2": 1e-6 * (np.sin(3 * turn) > 0)}


def _sweep():
    grid = {"controller": np.array([b"qffc", b"fompc"]), "controller__di_max": np.array([2e-5, 4e-5, 8e-5, 1.6e-4])}
    rng = np.random.default_rng(0)
    dv = 50.0 + rng.normal(0.0, 0.5, (2, 4, 3))
    status = np.zeros((2, 4, 3), int)
    status[1, 0, 0] = 2
    return {"grid": grid, "metrics": {"dv_per_year_mps": dv}, "status": {"code": status}}


def _tuning(iterations=8, starts=4):
    it = np.arange(iterations)[:, None]
    dv = 30.0 + 10.0 * np.exp(-it / 3.0) + np.arange(starts)
    dv[2, 1] = np.inf
    shape = (iterations, starts)
    constraint = np.stack([np.broadcast_to(0.2 * np.exp(-it / 2.0) - 0.05, shape), np.full(shape, -0.5)], -1)
    best = np.minimum.accumulate(np.where(np.max(constraint, -1) <= 0, dv, np.inf).min(axis=1))
    active = np.ones((iterations, starts), np.int8)
    active[5:, 3] = 0
    return {"iterations": {"dv_per_year_mps": dv, "constraint": constraint, "loss": dv,
                           "step_norm": np.broadcast_to(0.5 ** it, shape),
                           "theta": np.zeros((iterations, starts, 2)), "temperature": np.ones(iterations),
                           "active": active, "trust_radius": np.ones((iterations, starts)),
                           "best_dv_per_year_mps": best, "wall_s": np.arange(iterations, dtype=float)},
            "best": {"k_h": 1.0, "theta": np.zeros(2)},
            "metrics": {"dv_per_year_mps": best[-1], "constraint_lon": -0.01, "constraint_lat": -0.5}}


def _part_cycles(n=12):
    """Per-cycle records of the wheels and the filter, magnitudes as in li2022-momentum and li2022-qffc-ranging."""
    rng = np.random.default_rng(1)
    table = {"t_s": (np.arange(n) + 0.5) * DAY, "nees": rng.chisquare(6, n), "measurements": np.full(n, 32.0),
             "nis_per_dof": rng.chisquare(32, n) / 32}
    for axis in "xyz":
        table[f"wheel_{axis}_nms"] = rng.normal(0.0, 10.0, n)
        table[f"wheel_max_abs_{axis}_nms"] = np.abs(table[f"wheel_{axis}_nms"]) + 5.0
    for axis in ("radial", "along", "cross"):
        for unit, sigma in (("m", 100.0), ("mps", 0.01)):
            table[f"nav_sigma_{axis}_{unit}"] = np.full(n, sigma)
            table[f"nav_error_{axis}_{unit}"] = rng.normal(0.0, sigma, n)
    return table


FIGURES = {
    "cycles": lambda path, dpi: [plots.plot_cycles(_cycles(), path, title="cycles", dpi=dpi)],
    "station_keeping": lambda path, dpi: [plots.plot_station_keeping(_cycles(), _reference(), TARGET, path, "sk",
                                                                      box_half_width_deg=0.05, dpi=dpi)],
    "sweep": lambda path, dpi: [plots.plot_sweep(_sweep(), ["controller", "controller.di_max"], path, dpi=dpi)],
    "feedback": lambda path, dpi: plots.plot_feedback(_steps(), 0.05, path.with_suffix(""), "katz", dpi=dpi,
                                                      fmt=path.suffix[1:]),
    "tuning": lambda path, dpi: [plots.plot_tuning(_tuning(), path, title="tune", dpi=dpi)],
    "wheels": lambda path, dpi: [plot_wheels(_part_cycles(), 50.0, path, title="wheels", dpi=dpi)],
    "navigation_error": lambda path, dpi: [plot_navigation_error(_part_cycles(), path, dpi=dpi)],
    "consistency": lambda path, dpi: [plot_consistency(_part_cycles(), path, dpi=dpi)],
}
MAGIC = {"pdf": b"%PDF", "png": b"\x89PNG"}


@pytest.fixture
def closed_figures(monkeypatch):
    """The figures ``plots`` closes, kept open so the test can draw and read them."""
    kept, close = [], plt.close
    monkeypatch.setattr(plots.plt, "close", kept.append)
    yield kept
    for fig in kept:
        close(fig)


@pytest.mark.parametrize("kind", sorted(FIGURES))
@pytest.mark.parametrize("fmt", sorted(MAGIC))
def test_every_figure_is_written_in_the_format_of_its_suffix(kind, fmt, tmp_path):
    written = FIGURES[kind](tmp_path / f"{kind}.{fmt}", 72)
    assert written and all(p.suffix == f".{fmt}" for p in written)
    for path in written:
        assert path.read_bytes()[:4] == MAGIC[fmt], path


@pytest.mark.parametrize("kind", sorted(FIGURES))
def test_no_offset_text_and_every_panel_labelled(kind, tmp_path, closed_figures):
    FIGURES[kind](tmp_path / f"{kind}.png", 50)
    assert closed_figures
    for fig in closed_figures:
        fig.canvas.draw()
        for ax in fig.axes:
            assert ax.get_xlabel() and ax.get_ylabel(), (kind, ax.get_xlabel(), ax.get_ylabel())
            for a in (ax, *ax.child_axes):
                for axis in (a.xaxis, a.yaxis):
                    assert axis.get_offset_text().get_text() == "", (kind, ax.get_xlabel(), ax.get_ylabel())


def test_station_keeping_draws_the_box_a_zoomed_inset_and_states_the_run(tmp_path, closed_figures):
    plots.plot_station_keeping(_cycles(), _reference(), TARGET, tmp_path / "sk.png", box_half_width_deg=0.05)
    (fig,) = closed_figures
    fig.canvas.draw()
    e_plane, i_plane, track = fig.axes[1:4]
    # The controlled e path spans 2e-6 against the reference's 2e-4: zoomed; in i, 3e-5 against 2e-4: zoomed.
    assert len(e_plane.child_axes) == 1 and len(i_plane.child_axes) == 1
    legend = [t.get_text() for t in track.get_legend().get_texts()]
    # 41 reference boundaries one sidereal day apart: 39.9 days drawn in full, the first 30 in the ground track.
    assert legend == ["uncontrolled, first 30 days", "controlled, 40 days", "box ±0.05°"]
    e_legend = [t.get_text() for t in e_plane.get_legend().get_texts()]
    assert e_legend == ["uncontrolled, 40 days", "controlled, 40 days", "target"]
    (x0, x1), (y0, y1) = track.get_xlim(), track.get_ylim()
    assert x0 < -0.05 and x1 > 0.05 and y0 < -0.05 and y1 > 0.05
    assert e_plane.get_xlabel() == "δe_x (10⁻⁴)"


def test_thrust_is_in_micrometres_per_second_squared(tmp_path, closed_figures):
    plots.plot_feedback(_steps(), 0.05, tmp_path / "katz", fmt="svg")
    assert (tmp_path / "katz-ground-track.svg").read_text().lstrip().startswith("<?xml")
    history = closed_figures[1]
    assert history.axes[1].get_ylabel() == "u_y (µm/s²)"
    # u_y = 2e-6 cos: 2 µm/s² at its peak.
    assert np.max(history.axes[1].get_lines()[0].get_ydata()) == pytest.approx(2.0)


def test_an_unknown_suffix_is_refused(tmp_path, closed_figures):
    with pytest.raises(ValueError, match="suffix"):
        plots.plot_cycles(_cycles(), tmp_path / "cycles.jpg")
    assert closed_figures and not (tmp_path / "cycles.jpg").exists()


def test_rcparams_are_left_as_they_were(tmp_path):
    before = dict(plt.rcParams)
    plots.plot_sweep(_sweep(), ["controller", "controller.di_max"], tmp_path / "sweep.png")
    assert dict(plt.rcParams) == before
    assert plt.rcParams["axes.formatter.useoffset"] == before["axes.formatter.useoffset"]


def test_label_for_names_the_quantity_and_its_unit():
    assert plots.label_for("thrusters.beta_max_deg") == "β_max (deg)"
    assert plots.label_for("controller.horizon") == "horizon N (cycles)"
    assert plots.label_for("controller.di_max") == "Δi_max"
    assert plots.label_for("errors.h_rv") == "H_rv"
    assert plots.label_for("dv_per_year_mps") == "ΔV per year (m/s/yr)"
    assert plots.label_for("max_abs_dlon_deg") == "max |δλ| (deg)"
    # The fallback: the section dropped, the unit suffix read (the longer suffix first: _mps2 before _mps, _s).
    assert plots.label_for("spacecraft.mass_kg") == "mass (kg)"
    assert plots.label_for("spacecraft.srp_area_m2") == "srp_area (m²)"
    assert plots.label_for("noise_mps2") == "noise (m/s²)"
    assert plots.label_for("thrusters.min_burn_s") == "min_burn (s)"
    assert plots.label_for("thrusters.count") == "count"


def test_decade_brings_small_values_near_one_and_leaves_ordinary_ones():
    assert plots.decade(np.array([1.2e-4, -3e-5])) == -4
    assert plots.decade(np.array([96.0, 95.9])) == 0
    assert plots.decade(np.array([0.05]), np.array([np.inf, np.nan])) == 0
    assert plots.decade(np.array([2e-6])) == -6
    assert plots.decade(np.zeros(3)) == 0
    assert plots.decade(np.array([1000.0, 222.0])) == 0 and plots.decade(np.array([3e5])) == 5  # ΔV, H_rv as they are


def test_a_sweep_figure_marks_the_grid_and_draws_only_what_its_legend_names(tmp_path, monkeypatch):
    """Ticks at the grid's values (they fell between them), controllers as written, the 5-95 % band in the
    legend with its repetitions and the min-max one, the failed point too; the title as the command line writes
    it."""
    from geojax import cli

    kept = []
    monkeypatch.setattr(plt, "close", kept.append)
    groups = _sweep()
    groups["grid"]["controller__di_max"] = np.array([60.0, 70.0, 80.0, 90.0])
    plots.plot_sweep(groups, ["controller", "controller.di_max"], tmp_path / "sweep.png")
    ax = kept[-1].axes[0]
    assert list(ax.get_xticks()) == [60.0, 70.0, 80.0, 90.0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        "qffc: mean (held)", "fompc: mean (held)", "fompc: failed (status not 0): mean, count",
        "qffc: 5–95 % (held, 3 repetitions)", "qffc: min–max (held)", "fompc: 5–95 % (held, 3 repetitions)",
        "fompc: min–max (held)"]
    attrs = {"name": "fig09", "base_scenario_toml": '[duration]\ndays = 365.25\n'}
    assert cli.sweep_title(attrs, ["controller", "thrusters.beta_max_deg"]) == "thrusters.beta_max_deg: fig09, 365.25 days"


def test_axis_labels_come_from_the_fields(tmp_path, monkeypatch):
    """A swept key is labelled by its ``Field``'s symbol and unit (declared once, with the key), a user's
    controller key by its own ``Field`` (found through the import path the file names), not guessed from the
    key's spelling; an undeclared unit is read from the key's suffix."""
    from geojax.plots import label_for

    (tmp_path / "laws_with_units.py").write_text(
        "import geojax\n"
        "from geojax.control.base import no_plan, stateless_init, coast\n"
        "LAW = geojax.Controller(stateless_init, no_plan, coast, geojax.Spec(fields={\n"
        "    'thrust_frac_n': geojax.Field(float, 0.5, lower=0.0, si='frac', unit=''),\n"
        "    'gain_x': geojax.Field(float, 1.0, si='gain', symbol='g', unit='1/s')}))\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert label_for("thrusters.beta_max_deg") == "β_max (deg)"
    assert label_for("controller.horizon", ["fompc"]) == "horizon N (cycles)"
    assert label_for("controller.k_h_per_km2_s", ["lyapunov"]) == "k_h (1/(km² s))"
    assert label_for("spacecraft.mass_kg") == "mass (kg)"  # no symbol declared: the key's own stem and suffix
    assert label_for("controller.thrust_frac_n", ["laws_with_units:LAW"]) == "thrust_frac_n"  # declared unitless
    assert label_for("controller.gain_x", ["laws_with_units:LAW"]) == "g (1/s)"
    assert label_for("controller.thrust_frac_n") == "thrust_frac (N)"  # no controller named: the suffix's unit


def _sweep_two_keys():
    groups = _sweep()
    groups["grid"]["errors__h_rv"] = np.array([1.0, 2.0])
    groups["metrics"]["dv_per_year_mps"] = np.repeat(groups["metrics"]["dv_per_year_mps"][:, :, None], 2, 2)
    groups["metrics"]["dv_per_year_mps"][:, :, 1] += 5.0
    groups["status"]["code"] = np.repeat(groups["status"]["code"][:, :, None], 2, 2)
    return groups


def test_a_sweep_over_two_keys_names_the_second_by_its_values_and_keeps_the_legend_off_the_bands(
        tmp_path, closed_figures):
    """Each line of a two-key sweep is named by the second key's symbol and value (not a running number), the
    legend sits beside the axes (its box clear of the axes' box), and the title names both keys."""
    from geojax import cli

    keys = ["controller", "controller.di_max", "errors.h_rv"]
    plots.plot_sweep(_sweep_two_keys(), keys, tmp_path / "sweep.png")
    (fig,) = closed_figures
    fig.canvas.draw()
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert texts[:2] == ["qffc, H_rv = 1: mean (held)", "qffc, H_rv = 2: mean (held)"]
    assert "fompc, H_rv = 1: failed (status not 0): mean, count" in texts and not any("#" in t for t in texts)
    legend, frame = ax.get_legend().get_window_extent(), ax.get_window_extent()
    assert legend.x0 >= frame.x1 and legend.x1 <= fig.bbox.x1 + 1  # beside the axes, inside the figure
    attrs = {"name": "grid2", "base_scenario_toml": '[duration]\ndays = 30\n'}
    assert cli.sweep_title(attrs, keys) == "controller.di_max × errors.h_rv: grid2, 30 days"


def test_demo_labels_say_each_unit_once_insets_have_tick_values_and_thrust_names_its_frame(tmp_path,
                                                                                          closed_figures):
    plots.plot_cycles(_cycles(), tmp_path / "c.png")
    plots.plot_station_keeping(_cycles(), _reference(), TARGET, tmp_path / "sk.png", box_half_width_deg=0.05)
    plots.plot_feedback(_steps(), 0.05, tmp_path / "katz")
    cycles, station_keeping, _, thrust = closed_figures
    for fig in closed_figures:
        fig.canvas.draw()
        for ax in fig.axes:
            for label in (ax.get_xlabel(), ax.get_ylabel()):
                assert all(label.count(unit) <= 1 for unit in ("km", "deg", "m/s")), label
    assert cycles.axes[2].get_ylabel() == "mean a − 42164.17 (km)"
    insets = [inset for ax in station_keeping.axes for inset in ax.child_axes]
    assert len(insets) == 2
    for inset in insets:  # values on both axes, besides the magnification
        for axis in (inset.xaxis, inset.yaxis):
            shown = [t.get_text() for t in axis.get_ticklabels() if t.get_visible() and t.get_text()]
            shown += [t.label2.get_text() for t in axis.get_major_ticks() if t.label2.get_visible()]
            assert len([t for t in shown if t]) >= 2
    assert "ECEF" in thrust.axes[0].get_title(loc="left")


def test_run_titles_name_the_controller_once():
    from geojax import scenario
    from geojax.runner.report import run_title

    assert run_title(scenario.load("li2022-qffc")) == "li2022-qffc"
    assert run_title(scenario.load("katz2025-constant")) == "katz2025-constant"
    assert run_title(scenario.load("li2022", {"controller.kind": "fompc"})) == "li2022, fompc"
