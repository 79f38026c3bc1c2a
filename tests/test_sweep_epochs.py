"""The epoch as a sweep axis (``geojax.sweep.epochs``): each point is the slot flown from its date.

Checked against a second method: each sample of the sweep against its own ``simulate`` run of the
``scenario.started_at`` scenario with the sample's key (separate compilations, one sample each)."""

import h5py
import jax
import numpy as np
import pytest

import geojax
from geojax import cli, scenario, store, sweep
from geojax.runner.rollout import simulate
from geojax.physics.frames import earth_rotation_angle_rad

pytestmark = pytest.mark.slow  # sweeps over epochs, each a closed loop per start: the slow tier

DATES = ["2027-01-01T12:00:00", "2036-07-01T00:00:00"]
SPEC = f"""
name = "epochs"
scenario = "li2022-qffc"
controllers = ["qffc"]
repetitions = 2
seed = 3
[set]
"duration.days" = 2
"errors.h_rv" = 5.0
"errors.h_att" = 5.0
[grid]
"thrusters.beta_max_deg" = [60.0, 90.0]
"epoch.utc" = {DATES!r}
""".replace("'", '"')


@pytest.fixture(scope="module")
def straight(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("epochs")
    path = tmp / "epochs.toml"
    path.write_text(SPEC)
    spec = sweep.load(path)
    return spec, sweep.run_sweep(spec, tmp / "straight.h5", chunk=3, progress=False)


@pytest.mark.slow
def test_each_sample_is_a_simulate_run_of_the_scenario_started_that_day(straight):
    spec, out = straight
    ds = geojax.open_results(out)
    for b, beta in enumerate(spec.grid["thrusters.beta_max_deg"]):
        for e, utc in enumerate(DATES):
            moved = scenario.started_at("li2022-qffc", utc, {**spec.fixed, "thrusters.beta_max_deg": beta})
            for rep in range(spec.repetitions):
                j = (b * len(DATES) + e) * spec.repetitions + rep  # the sample's global index
                alone = simulate(moved, key=jax.random.fold_in(jax.random.key(spec.seed), j))
                for name in ("dv_per_year_mps", "max_abs_dlon_deg", "max_abs_di"):
                    np.testing.assert_allclose(ds[name].values[0, b, e, rep], alone.metrics[name], rtol=1e-9,
                                               atol=1e-12)
                assert ds.status.values[0, b, e, rep] == alone.status


def test_the_moved_scenario_keeps_the_geographic_longitude():
    # Invariant of started_at: true longitude minus Earth angle, the same at both epochs.
    base = scenario.load("li2022-qffc")
    moved = scenario.started_at("li2022-qffc", DATES[1])
    angle = lambda sc: float(earth_rotation_angle_rad(sc.epoch_tt_s, sc.epoch_tt_s, sc.tt_minus_ut1_s))  # noqa: E731
    geographic = lambda sc: np.remainder(sc.initial_mee[5] - angle(sc), 2 * np.pi)  # noqa: E731
    assert abs(geographic(moved) - geographic(base)) < 1e-12
    np.testing.assert_array_equal(moved.initial_mee[:5], base.initial_mee[:5])


def test_the_epoch_is_a_coordinate_of_the_results(straight):
    _, out = straight
    ds = geojax.open_results(out)
    assert ds.dv_per_year_mps.dims == ("controller", "thrusters.beta_max_deg", "epoch.utc", "repetition")
    np.testing.assert_array_equal(ds["epoch.utc"].values, np.array(DATES, dtype="datetime64[s]"))
    one_year = ds.dv_per_year_mps.sel({"epoch.utc": "2036"})  # partial-date selection of a datetime axis
    np.testing.assert_array_equal(one_year.values[:, :, 0], ds.dv_per_year_mps.values[:, :, 1])
    with h5py.File(out) as f:
        assert [v.decode() for v in f["grid/epoch__utc"][()]] == DATES


@pytest.mark.slow
def test_a_killed_epoch_sweep_resumes_to_the_same_data(straight, tmp_path, monkeypatch):
    spec, out = straight
    resumed = tmp_path / "resumed.h5"
    real_write = store.atomic_write
    calls = []

    def dies_after_first_chunk(path, payload):
        calls.append(path)
        if len(calls) == 4:  # chunk, sweep.sha256, the first chunk, then killed while writing the second
            raise KeyboardInterrupt
        real_write(path, payload)

    monkeypatch.setattr(store, "atomic_write", dies_after_first_chunk)
    with pytest.raises(KeyboardInterrupt):
        sweep.run_sweep(spec, resumed, chunk=3, progress=False)
    monkeypatch.setattr(store, "atomic_write", real_write)
    sweep.run_sweep(spec, resumed, resume=True, progress=False)
    with h5py.File(out) as a, h5py.File(resumed) as b:
        for group in ("metrics", "status", "grid"):
            for name in a[group]:
                np.testing.assert_array_equal(a[group][name][()], b[group][name][()])


@pytest.mark.parametrize("values, message", [
    ('["2027-13-01"]', "grid.epoch.utc: '2027-13-01' is not an ISO 8601 date-time"),
    ('[2027]', "grid.epoch.utc: must be a list of ISO 8601 UTC dates"),
    ('["2027-01-01", "2027-01-01T00:00:00Z"]', "grid.epoch.utc: the dates must be distinct"),
    ('["2027-01-01", "2060-01-01"]', "epoch.utc: a run of 2 days from 2060-01-01 leaves the dates of the meeus "
                                     "ephemeris, 1999-01-01 to 2051-01-01"),
    ('["1995-01-01"]', "epoch.utc: dates before 1999-01-01 are not supported"),
])
def test_bad_epochs_exit_2_in_one_line_and_write_nothing(tmp_path, capsys, values, message):
    path = tmp_path / "bad.toml"
    path.write_text(SPEC.split("[grid]")[0] + f'[grid]\n"epoch.utc" = {values}\n')
    out = tmp_path / "never.h5"
    assert cli.main(["sweep", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not out.exists() and not out.with_name(out.name + ".parts").exists()


def test_an_epoch_axis_of_a_keplerian_scenario_is_refused(tmp_path, capsys):
    path = tmp_path / "kepler.toml"
    path.write_text(SPEC.replace('"li2022-qffc"', '"ye2022-ex1"').replace('["qffc"]', '["zone_nssk"]').split("[grid]")[0]
                    + '[grid]\n"epoch.utc" = ["2027-01-01T00:00:00"]\n')
    assert scenario.load("ye2022-ex1").config["orbit"]["elements"] == "kepler"
    assert cli.main(["sweep", str(path), "--out", str(tmp_path / "never.h5")]) == 2
    assert "orbit.elements: moving a scenario to another epoch needs" in capsys.readouterr().err


def test_the_sweep_figure_draws_the_epoch_axis_in_years(straight, tmp_path):
    _, out = straight
    assert cli.main(["plot", str(out), "--out", str(tmp_path)]) == 0
    assert list(tmp_path.glob("*.png"))
