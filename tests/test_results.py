"""Results as labelled arrays (geojax.results): a sweep, a simulation and a tuning opened with ``open_results``
(dimension names, coordinates, units), the same labels in the HDF5 file for other readers, the provenance,
and the tuned scenario a tuning writes, loaded back with its gains."""

import h5py
import numpy as np
import pytest

from geojax import cli, open_results, scenario, sweep, tune
from geojax.runner.setup import prepare, unstack

SWEEP = """
name = "labels"
scenario = "li2022-qffc"
controllers = ["qffc"]
repetitions = 2
seed = 3
cycles = true
[set]
"duration.days" = 3.0
"errors.h_rv" = 2.0
[grid]
"thrusters.beta_max_deg" = [60.0, 90.0]
"""


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("labels")
    (tmp / "s.toml").write_text(SWEEP)
    return sweep.run_sweep(sweep.load(tmp / "s.toml"), tmp / "s.h5", progress=False)


@pytest.mark.slow
def test_a_sweep_opens_with_named_dimensions_coordinates_and_units(sweep_file):
    ds = open_results(sweep_file)
    dv = ds.dv_per_year_mps
    assert dv.dims == ("controller", "thrusters.beta_max_deg", "repetition") and dv.shape == (1, 2, 2)
    assert list(ds.controller.values) == ["qffc"]
    np.testing.assert_array_equal(ds["thrusters.beta_max_deg"].values, [60.0, 90.0])
    assert dv.attrs["units"] == "m/s/yr" and "delta-V" in dv.attrs["description"]
    assert ds.max_abs_dlon_deg.attrs["units"] == "deg" and ds.status.dtype == np.int8
    assert ds.cycles__lon_deg.dims == ("controller", "thrusters.beta_max_deg", "repetition", "cycle")
    # Selecting by label gives the numbers of the raw file.
    with h5py.File(sweep_file) as f:
        raw = f["metrics/dv_per_year_mps"][()]
        np.testing.assert_array_equal(dv.sel(controller="qffc", **{"thrusters.beta_max_deg": 90.0}).values, raw[0, 1])
        # The same labels for any HDF5 reader: dimension labels, the grid attached as a dimension scale.
        ds_raw = f["metrics/dv_per_year_mps"]
        assert [d.label for d in ds_raw.dims] == ["controller", "thrusters.beta_max_deg", "repetition"]
        assert ds_raw.dims[1][0].name == "/grid/thrusters__beta_max_deg"
        assert ds_raw.attrs["units"] == "m/s/yr"


def test_provenance_and_the_resolved_base_scenario(sweep_file):
    import jax
    import jaxlib

    ds = open_results(sweep_file)
    assert ds.attrs["jax_version"] == jax.__version__ and ds.attrs["jaxlib_version"] == jaxlib.__version__
    assert ds.attrs["source_revision"]  # a commit (this is a checkout) or "unknown" (an installed wheel)
    base = scenario.from_dict(scenario.tomllib.loads(ds.attrs["base_scenario_toml"]))
    assert base.config["duration"]["days"] == 3.0 and base.config["errors"]["h_rv"] == 2.0  # [set] applied


def test_plot_a_sweep_as_svg_and_refuse_a_bad_dpi(sweep_file, tmp_path, capsys):
    assert cli.main(["plot", str(sweep_file), "--out", str(tmp_path), "--format", "svg", "--dpi", "300"]) == 0
    assert b"<svg" in (tmp_path / "s.svg").read_bytes()[:500]
    assert cli.main(["plot", str(sweep_file), "--dpi", "0"]) == 2
    assert "--dpi" in capsys.readouterr().err


def test_the_tuned_scenario_loads_back_with_the_tuned_gains(tmp_path):
    """Round trip: gains doubled in SI inside ``Params`` come back doubled in the scenario's own units."""
    spec_file = tmp_path / "t.toml"
    spec_file.write_text('scenario = "katz2025-discrete"\nparameters = ["k_h", "k_e", "sigma"]\ndays = 2.0\n')
    spec = tune.load(spec_file)
    params = unstack(prepare([spec.scenario]).params, 0)
    entries = tune.tuned(spec.scenario, None, spec.parameters)
    doubled = dict(params.controller)
    for entry in entries[:2]:  # sigma's norm is fixed by u0 (Katz eq. 6): kept
        doubled[entry.field.si] = params.controller[entry.field.si] * 2
    path = tune.tuned_scenario_path(tmp_path / "t.h5")
    path.write_text(tune.tuned_scenario_toml(spec, params._replace(controller=doubled)))
    assert path.name == "t-tuned.toml"
    tuned, original = scenario.load(path).config["controller"], spec.scenario.config["controller"]
    assert tuned["k_h_per_km2_s"] == pytest.approx(2 * original["k_h_per_km2_s"], rel=1e-12)
    assert tuned["k_e_km2_per_s3"] == pytest.approx(2 * original["k_e_km2_per_s3"], rel=1e-12)
    assert tuned["sigma_km_per_s2"] == pytest.approx(original["sigma_km_per_s2"], rel=1e-12)
    assert scenario.load(path).name == "katz2025-discrete-tuned"


@pytest.mark.parametrize("content, message", [(None, "no such file"), (b"not hdf5", "not an HDF5 file"),
                                              ("h5", "not a geojax results file")])
def test_open_results_refuses_what_is_not_a_results_file(tmp_path, content, message):
    path = tmp_path / "x.h5"
    if content == "h5":
        with h5py.File(path, "w") as f:
            f["a"] = 1
    elif content is not None:
        path.write_bytes(content)
    with pytest.raises(ValueError, match=message):
        open_results(path)


# A sweep file where samples failed, written by hand so every expected number is computed here, not by geojax:
# beta 60: one of four left the longitude box (its 900 m/s/yr must not reach the mean); beta 90: all held;
# beta 120: all four ran out of propellant.
FAILED_DV = np.array([[[50.0, 54.0, 900.0, 52.0], [60.0, 61.0, 62.0, 63.0], [70.0, 71.0, 72.0, 73.0]]])
FAILED_STATUS = np.array([[[0, 0, 2, 0], [0, 0, 0, 0], [5, 5, 5, 5]]], np.int8)
FAILED_DLON = np.array([[[0.01, 0.02, 27.0, 0.03], [0.04, 0.01, 0.01, 0.01], [0.5, 0.5, 0.5, 0.5]]])


@pytest.fixture
def failed_sweep_file(tmp_path):
    from geojax import store
    from geojax.results import dims_of_sweep

    grid = {"controller": np.array([b"qffc"]), "thrusters__beta_max_deg": np.array([60.0, 90.0, 120.0])}
    metrics = {"dv_per_year_mps": FAILED_DV, "max_abs_dlon_deg": FAILED_DLON, "max_abs_dlat_deg": FAILED_DLON / 10}
    return store.write_h5(tmp_path / "failed.h5", {"grid": grid, "metrics": metrics,
                                                   "status": {"code": FAILED_STATUS}}, 'scenario = "li2022-qffc"', 1.0,
                          attrs={"kind": "sweep", "name": "failed", "grid_axes": "controller,thrusters.beta_max_deg",
                                 "base_scenario_toml": "[duration]\ndays = 365.25\n"},
                          dims=dims_of_sweep(["thrusters.beta_max_deg"], cycles=False))


def test_failed_samples_are_counted_and_left_out_of_open_results_statistics(failed_sweep_file):
    """Independent check: the held samples' mean, spread and count worked out by hand from the arrays above."""
    from geojax.results import held, summary_table

    ds = open_results(failed_sweep_file)
    table = summary_table(ds)
    assert table.held_mean.dims == ("controller", "thrusters.beta_max_deg") and table.held_mean.attrs["units"] == "m/s/yr"
    np.testing.assert_array_equal(table.samples.values, [[4, 4, 4]])
    np.testing.assert_array_equal(table.failed.values, [[1, 0, 4]])
    np.testing.assert_allclose(table.held_mean.values[0, :2], [52.0, 61.5], rtol=1e-15)
    np.testing.assert_allclose(table.held_std.values[0, 0], np.sqrt(8.0 / 3.0), rtol=1e-15)
    assert table.held_max.values[0, 0] == 54.0 and np.isnan(table.held_mean.values[0, 2])  # none held at beta 120
    dlon = summary_table(ds, "max_abs_dlon_deg").held_max.sel(controller="qffc")
    assert dlon.sel({"thrusters.beta_max_deg": 60.0}).item() == 0.03  # not the failed sample's 27 deg
    # held(): the same, as a Dataset any xarray reduction reads.
    assert held(ds).dv_per_year_mps.mean("repetition").values[0, 0] == 52.0
    assert int((ds.status != 0).sum()) == 5


def test_the_sweep_summary_counts_failed_samples_and_averages_the_held(failed_sweep_file):
    from types import SimpleNamespace

    from geojax import store

    groups, _ = store.read_h5(failed_sweep_file)
    spec = SimpleNamespace(grid={"thrusters.beta_max_deg": [60.0, 90.0, 120.0]}, controllers=["qffc"], repetitions=4,
                           fixed={"duration.days": 365.25})
    lines = cli.sweep_summary(spec, groups)
    assert lines[1] == ("    beta_max_deg 60: ΔV 52.00 ± 1.63 m/s/yr, max |δλ| 0.0300°, max |δφ| 0.0030°; 3 held, "
                        "1 failed (1 left the longitude box)")
    assert lines[2].endswith("ΔV 61.50 ± 1.12 m/s/yr, max |δλ| 0.0400°, max |δφ| 0.0040°; all ok")
    assert lines[3] == "    beta_max_deg 120: all 4 failed (4 propellant exhausted): no statistics"
    assert "5 of 12 samples failed" in lines[4]


def test_the_sweep_figure_draws_the_held_mean_and_counts_the_failed(failed_sweep_file, tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    kept = []
    monkeypatch.setattr(plt, "close", kept.append)
    assert cli.main(["plot", str(failed_sweep_file), "--out", str(tmp_path)]) == 0
    ax = kept[-1].axes[0]
    mean_line = next(line for line in ax.get_lines() if line.get_label() == "qffc: mean (held)")
    np.testing.assert_allclose(mean_line.get_ydata(), [52.0, 61.5, np.nan], rtol=1e-15)
    assert sorted(t.get_text() for t in ax.texts) == ["1/4 failed", "4/4 failed"]
    crosses = next(line for line in ax.get_lines() if "failed" in line.get_label())
    np.testing.assert_allclose(crosses.get_ydata(), [900.0, 71.5])  # where they failed, at their own mean
