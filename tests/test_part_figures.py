"""The parts' figures and a sweep's spread, drawn from real short runs: what each figure plots is read back from
the matplotlib figure before it is closed and compared with the run's records, its metrics and χ² quantiles
computed here with SciPy; the sweep's percentile band against NumPy's percentiles of the file's held samples."""

import subprocess
import sys

import matplotlib.pyplot as plt
import numpy as np
import pytest
from scipy.stats import chi2

import geojax
from geojax import cli, plots, store

DAY_S = 86400.0


@pytest.fixture
def kept(monkeypatch):
    """The figures ``plots`` closes, kept open by their file's name, so the test can read what they plot."""
    figures, close = {}, plt.close

    def keep(fig):
        figures[len(figures)] = fig
    monkeypatch.setattr(plots.plt, "close", keep)
    yield figures
    for fig in figures.values():
        close(fig)


def _by_gid(ax, gid):
    (artist,) = [a for a in (*ax.lines, *ax.patches, *ax.collections) if a.get_gid() == gid]
    return artist


def _run(name):
    sc = geojax.load_scenario(name, {"duration.days": 3})
    return sc, geojax.simulate(sc, seed=1)


@pytest.fixture(scope="module")
def wheels_run():
    return _run("li2022-momentum")


@pytest.fixture(scope="module")
def navigation_run():
    return _run("li2022-qffc-ranging")


def test_the_wheels_figure_plots_each_wheels_records_against_the_capacity(wheels_run, tmp_path, kept):
    sc, result = wheels_run
    written = result.plot(tmp_path)
    assert [p.name for p in written] == ["li2022-momentum.png", "li2022-momentum-station-keeping.png",
                                         "li2022-momentum-wheels.png"]
    assert all(p.stat().st_size > 0 for p in written)
    cycles = result.cycles()
    fig = kept[len(kept) - 1]
    capacity = sc.config["attitude"]["wheel_capacity_nms"]  # the scenario's key, not the figure's source
    assert capacity == 50.0
    peaks = []
    for ax, axis in zip(fig.axes, "xyz"):
        assert np.array_equal(_by_gid(ax, "end").get_ydata(), cycles[f"wheel_{axis}_nms"])
        # the momentum at each cycle's end: the cycles' ends one sidereal day apart
        assert np.allclose(_by_gid(ax, "end").get_xdata(), np.arange(1, 4) * 86164.0905 / DAY_S)
        values, edges, _ = _by_gid(ax, "max_abs").get_data()
        assert np.array_equal(values, cycles[f"wheel_max_abs_{axis}_nms"])
        assert np.array_equal(_by_gid(ax, "-max_abs").get_data()[0], -values)
        assert np.allclose(edges, np.arange(4) * 86164.0905 / DAY_S)
        assert list(_by_gid(ax, "+capacity").get_ydata()) == [capacity] * 2
        assert list(_by_gid(ax, "-capacity").get_ydata()) == [-capacity] * 2
        peaks.append(values.max())
    # the figure's largest |h| is the run's metric (every step start and cycle end, any wheel)
    assert max(peaks) == pytest.approx(float(result.metrics["max_wheel_momentum_nms"]), rel=1e-12)
    assert 0 < max(peaks) < capacity


def test_geojax_plot_draws_the_parts_figures_of_a_simulate_file(wheels_run, tmp_path, kept, capsys):
    sc, result = wheels_run
    h5 = result.save(tmp_path / "run.h5")
    assert cli.main(["plot", str(h5), "--out", str(tmp_path / "figs"), "--format", "pdf"]) == 0
    assert "run-wheels.pdf" in capsys.readouterr().out
    assert (tmp_path / "figs" / "run-wheels.pdf").read_bytes()[:4] == b"%PDF"
    groups, _ = store.read_h5(h5)
    fig = kept[len(kept) - 1]
    for ax, axis in zip(fig.axes, "xyz"):
        assert np.array_equal(_by_gid(ax, "end").get_ydata(), groups["cycles"][f"wheel_{axis}_nms"])
        assert list(_by_gid(ax, "+capacity").get_ydata()) == [50.0, 50.0]


def test_the_navigation_figures_plot_the_error_against_3_sigma_and_nees_nis_against_chi2(navigation_run, tmp_path,
                                                                                        kept):
    sc, result = navigation_run
    written = result.plot(tmp_path)
    names = [p.name for p in written]
    assert names[2:] == ["li2022-qffc-ranging-navigation-error.png", "li2022-qffc-ranging-navigation-consistency.png"]
    assert "li2022-qffc-ranging-wheels.png" not in names  # a part not carried draws nothing
    assert all(p.stat().st_size > 0 for p in written)
    record = result.records.cycles.states["navigation"]  # the filter's own records: [cycles, 6] RSW, then NEES
    error, sigma = np.asarray(record.error_rsw), np.asarray(record.sigma_rsw)
    error_fig, consistency = kept[len(kept) - 2], kept[len(kept) - 1]
    for k, ax in enumerate(error_fig.axes):  # rows position (m), velocity (mm/s); columns R, S, W
        scale = 1.0 if k < 3 else 1e3
        column = (k % 3) + (0 if k < 3 else 3)
        assert np.allclose(_by_gid(ax, "error").get_ydata(), error[:, column] * scale, rtol=1e-12, atol=0)
        assert np.allclose(_by_gid(ax, "+3sigma").get_ydata(), 3 * sigma[:, column] * scale, rtol=1e-12, atol=0)
        assert np.allclose(_by_gid(ax, "-3sigma").get_ydata(), -3 * sigma[:, column] * scale, rtol=1e-12, atol=0)
        assert np.allclose(_by_gid(ax, "error").get_xdata(), np.arange(3) * 86164.0905 / DAY_S)  # cycle starts
    nees_ax, nis_ax = consistency.axes
    nees = np.asarray(record.nees)
    assert np.array_equal(_by_gid(nees_ax, "values").get_ydata(), nees)
    assert _by_gid(nees_ax, "low").get_ydata()[0] == pytest.approx(chi2.ppf(0.025, 6))
    assert _by_gid(nees_ax, "high").get_ydata()[0] == pytest.approx(chi2.ppf(0.975, 6))
    n = len(nees)
    assert _by_gid(nees_ax, "mean").get_ydata()[0] == pytest.approx(float(result.metrics["nees_mean"]), rel=1e-12)
    band = _by_gid(nees_ax, "mean_band")  # a Rectangle in data units along y
    assert (band.get_y(), band.get_y() + band.get_height()) == pytest.approx((chi2.ppf(0.025, 6 * n) / n, chi2.ppf(0.975, 6 * n) / n))
    dof = np.asarray(record.nis_dof)
    assert np.all(dof > 0)
    values, _, _ = _by_gid(nis_ax, "values").get_data()
    assert np.allclose(values, np.asarray(record.nis_sum) / dof, rtol=1e-12, atol=0)
    assert np.allclose(_by_gid(nis_ax, "low").get_data()[0], chi2.ppf(0.025, dof) / dof)
    assert np.allclose(_by_gid(nis_ax, "high").get_data()[0], chi2.ppf(0.975, dof) / dof)
    total = dof.sum()
    assert _by_gid(nis_ax, "mean").get_ydata()[0] == pytest.approx(float(result.metrics["nis_mean_per_dof"]),
                                                                  rel=1e-12)
    band = _by_gid(nis_ax, "mean_band")
    assert (band.get_y(), band.get_y() + band.get_height()) == pytest.approx((chi2.ppf(0.025, total) / total, chi2.ppf(0.975, total) / total))


SWEEP = """
name = "spread"
scenario = "li2022-qffc"
controllers = ["qffc"]
repetitions = 6
seed = 2
[set]
"duration.days" = 3
"errors.h_rv" = 5.0
"errors.h_att" = 5.0
[grid]
"thrusters.beta_max_deg" = [60.0, 90.0]
"""


def _band(ax, gid):
    """(x, lower, upper) of a ``fill_between`` band: its polygon's extremes at each x."""
    vertices = _by_gid(ax, gid).get_paths()[0].vertices
    x = np.unique(vertices[:, 0])
    return x, *np.array([[vertices[vertices[:, 0] == v, 1].min(), vertices[vertices[:, 0] == v, 1].max()]
                         for v in x]).T


def test_a_sweeps_figure_draws_the_held_samples_percentile_band_and_counts_the_failed_apart(tmp_path, kept):
    spec = tmp_path / "spread.toml"
    spec.write_text(SWEEP)
    h5 = geojax.run_sweep(geojax.load_sweep(spec), tmp_path / "spread.h5", progress=False)
    groups, attrs = store.read_h5(h5)
    dv = np.asarray(groups["metrics"]["dv_per_year_mps"])  # [controller, beta, repetition]
    assert dv.shape == (1, 2, 6) and np.all(np.asarray(groups["status"]["code"]) == 0)
    assert np.ptp(dv, axis=-1).min() > 0  # a spread to draw: the repetitions' errors differ
    # One sample at each grid point marked failed: left out of the band, counted apart.
    groups["status"]["code"] = np.asarray(groups["status"]["code"]).copy()
    groups["status"]["code"][0, :, 0] = 2
    plots.plot_sweep(groups, str(attrs["grid_axes"]).split(","), tmp_path / "spread.png")
    (ax,) = kept[len(kept) - 1].axes
    x, low, high = _band(ax, "qffc: 5–95 %")
    assert list(x) == [60.0, 90.0]
    held = dv[0, :, 1:]
    assert np.allclose(low, np.percentile(held, 5, axis=-1), rtol=1e-12, atol=0)
    assert np.allclose(high, np.percentile(held, 95, axis=-1), rtol=1e-12, atol=0)
    _, low, high = _band(ax, "qffc: min–max")
    assert np.allclose(low, held.min(-1), rtol=1e-12, atol=0) and np.allclose(high, held.max(-1), rtol=1e-12, atol=0)
    assert [t.get_text() for t in ax.texts] == ["1/6 failed", "1/6 failed"]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "qffc: 5–95 % (held, 6 repetitions)" in legend and "qffc: min–max (held)" in legend


def test_the_engine_draws_no_figure_the_parts_import_their_drawing_when_asked():
    """The parts declare their figures, yet importing them and the loop imports neither matplotlib nor the plots."""
    code = ("import sys, geojax.states, geojax.loop.simulate; "
            "print(any(m == 'matplotlib' or m.startswith('geojax.plots') for m in sys.modules)); "
            "print([p.figures is not None for p in geojax.states.REGISTRY if p.name in ('wheels', 'navigation')])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[:2] == ["False", "[True, True]"]
