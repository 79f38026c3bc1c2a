"""Sweeps: chunk-size and device-count invariance, resume after a kill, the HDF5 schema, bad input."""

import os
import subprocess
import sys

import h5py
import jax
import numpy as np
import pytest

from geojax import cli, store, sweep
from geojax.physics.constants import SIDEREAL_DAY_S
from geojax.loop.metrics import CYCLE_NAMES

SPEC = """
name = "test"
scenario = "li2022-qffc"
controllers = ["qffc"]
repetitions = 5
seed = 4
[set]
"duration.days" = 3
"errors.h_rv" = 5.0
"errors.h_att" = 5.0
[grid]
"thrusters.beta_max_deg" = [60.0, 90.0]
"""


def write_spec(tmp_path, text=SPEC, name="s.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def data(path):
    with h5py.File(path) as f:
        return {name: f[name][()] for group in ("metrics", "status", "grid") for name in
                [f"{group}/{k}" for k in f[group]]}


@pytest.fixture(scope="module")
def straight(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("sweep")
    spec = sweep.load(write_spec(tmp))
    return spec, data(sweep.run_sweep(spec, tmp / "straight.h5", chunk=64, progress=False))


def test_schema_and_physics(straight):
    _, d = straight
    assert d["metrics/dv_per_year_mps"].shape == (1, 2, 5)
    assert d["status/code"].shape == (1, 2, 5)
    np.testing.assert_array_equal(d["grid/thrusters__beta_max_deg"], [60.0, 90.0])
    assert list(d["grid/controller"]) == [b"qffc"]
    # A wider pitch range needs less Delta-V for the same job (Li 2022 Fig. 9); errors spread the reps.
    dv = d["metrics/dv_per_year_mps"][0]
    assert np.mean(dv[1]) < np.mean(dv[0]) and np.std(dv[0]) > 0


def test_chunk_size_does_not_change_results(straight, tmp_path):
    spec, d = straight
    other = data(sweep.run_sweep(spec, tmp_path / "chunked.h5", chunk=7, progress=False))
    for name in d:
        np.testing.assert_array_equal(other[name], d[name])


@pytest.mark.slow
def test_killed_sweep_resumes_to_the_same_data(straight, tmp_path, monkeypatch):
    spec, d = straight
    out = tmp_path / "resumed.h5"
    real_write = store.atomic_write
    calls = []

    def dies_after_first_chunk(path, payload):
        calls.append(path)
        if len(calls) == 4:  # chunk, sweep.sha256, chunk 0, then "killed" while writing chunk 1
            path.with_name(f".{path.name}.tmp-999").write_bytes(payload[:10])  # a torn temporary file
            raise KeyboardInterrupt
        real_write(path, payload)

    monkeypatch.setattr(store, "atomic_write", dies_after_first_chunk)
    with pytest.raises(KeyboardInterrupt):
        sweep.run_sweep(spec, out, chunk=3, progress=False)
    monkeypatch.setattr(store, "atomic_write", real_write)
    assert not out.exists()
    with pytest.raises(ValueError, match="pass resume=True"):
        sweep.run_sweep(spec, out, chunk=3, progress=False)
    with pytest.raises(ValueError, match="cut into chunks of 3"):  # the cut on disk is kept
        sweep.run_sweep(spec, out, resume=True, chunk=2, progress=False)
    resumed = data(sweep.run_sweep(spec, out, resume=True, chunk=3, progress=False))
    for name in d:
        np.testing.assert_array_equal(resumed[name], d[name])
    assert not out.with_name(out.name + ".parts").exists()


ON_CPU = jax.default_backend() == "cpu"
HOST_DEVICES = pytest.mark.skipif(not ON_CPU, reason="XLA host devices: the CPU's device-count invariance")


@pytest.mark.slow
@HOST_DEVICES
def test_two_host_devices_give_the_same_results(straight, tmp_path):
    _, d = straight
    spec_path = write_spec(tmp_path)
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
    out = tmp_path / "two.h5"
    # 4 lanes per device: the 10 samples fill both devices (a sweep that fits one device's lanes runs on one)
    code = ("import jax, sys; from geojax import sweep; assert jax.device_count() == 2; "
            "from geojax.sweep.batch import devices_for; assert len(devices_for(10, 4)) == 2; "
            f"sweep.run_sweep(sweep.load({str(spec_path)!r}), {str(out)!r}, chunk=64, progress=False, lanes=4)")
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
    two = data(out)
    for name in d:
        np.testing.assert_array_equal(two[name], d[name])


@pytest.mark.parametrize("grid, message", [
    ('"thrusters.beta_maxx_deg" = [60.0]', "thrusters.beta_maxx_deg: unknown key; allowed: count, thrust_n"),
    ('"thrusters.beta_max_deg" = []', "grid.thrusters.beta_max_deg: must be a non-empty list of values"),
    ('"thrusters.beta_max_deg" = ["high"]', "grid.thrusters.beta_max_deg: must be a list of numbers"),
    ('"thrusters.beta_max_deg" = [60.0, 120.0]', "thrusters.beta_max_deg: must be >= 0 and <= 90, got 120.0"),
    ('"errors.h_rv" = [-1.0]', "errors.h_rv: must be >= 0"),
])
def test_bad_sweep_files_exit_2_and_write_nothing(tmp_path, capsys, grid, message):
    spec = write_spec(tmp_path, SPEC.split("[grid]")[0] + "[grid]\n" + grid + "\n")
    out = tmp_path / "never.h5"
    assert cli.main(["sweep", str(spec), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not out.exists() and not out.with_name(out.name + ".parts").exists()


def test_resume_into_the_results_of_another_sweep_is_refused(straight, tmp_path, capsys):
    spec, _ = straight
    out = tmp_path / "done.h5"
    sweep.run_sweep(spec, out, chunk=64, progress=False)
    other = write_spec(tmp_path, SPEC.replace("repetitions = 5", "repetitions = 4"), "other.toml")
    assert cli.main(["sweep", str(other), "--out", str(out), "--resume"]) == 2
    assert "holds the results of a different sweep file" in capsys.readouterr().err


def test_existing_output_without_resume_is_refused(tmp_path, capsys):
    out = tmp_path / "there.h5"
    out.write_bytes(b"not ours")
    assert cli.main(["sweep", str(write_spec(tmp_path)), "--out", str(out)]) == 2
    assert "exists; pass --resume" in capsys.readouterr().err
    assert out.read_bytes() == b"not ours"


@pytest.mark.slow
def test_per_cycle_records_agree_with_the_metrics(tmp_path):
    """``cycles = true`` keeps /cycles/<name> [controller, grid, reps, cycle]; recomputed from them, the longitude
    excursion equals the metric and the ΔV delivered per cycle adds up to the run's ΔV."""
    spec = sweep.load(write_spec(tmp_path, SPEC.replace("repetitions = 5", "repetitions = 2\ncycles = true")))
    groups, _ = store.read_h5(sweep.run_sweep(spec, tmp_path / "cycles.h5", progress=False))
    cycles, metrics = groups["cycles"], groups["metrics"]
    assert set(cycles) == set(CYCLE_NAMES) and cycles["lon_deg"].shape == (1, 2, 2, 3)
    np.testing.assert_allclose(np.max(np.abs(cycles["lon_deg"][..., 1:] - 96.0), axis=-1), metrics["max_abs_mean_dlon_deg"],
                               rtol=1e-9)
    per_year = 365.25 * 86400.0 / (3 * SIDEREAL_DAY_S)
    np.testing.assert_allclose(np.sum(cycles["dv_mps"], axis=-1) * per_year, metrics["dv_per_year_mps"], rtol=1e-9)


FOMPC_SPEC = """
name = "fompc-devices"
scenario = "li2022-qffc"
controllers = ["fompc"]
repetitions = 2
seed = 3
[set]
"duration.days" = 20.0
[grid]
"controller.di_max" = [8e-5, 2e-3]
"""


@pytest.mark.slow
def test_fompc_results_do_not_depend_on_the_device_count_or_the_width(tmp_path):
    """With the batch sharded by a plain ``jit``, XLA's SPMD pipeline fused the FOMPC's
    annealing differently on two devices and sample (0, 1) moved by 1.4e-14 m/s/yr from cycle 17 on.  Each
    device now runs the one-device program on its share (``parallel.per_device``): bit for bit.  And 128
    lanes instead of the FOMPC's 32: a step compiled for the batch's width moved the cycle means'
    e_x by 8e-15; it is compiled for the controller's CPU width whatever the batch."""
    spec_path = write_spec(tmp_path, FOMPC_SPEC.replace('seed = 3', 'seed = 3\ncycles = true'), "fompc.toml")
    one = sweep.run_sweep(sweep.load(spec_path), tmp_path / "one.h5", progress=False)
    others = [sweep.run_sweep(sweep.load(spec_path), tmp_path / "wide.h5", progress=False, lanes=128)]
    if ON_CPU:  # two XLA host devices
        env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
        others.append(tmp_path / "two.h5")
        code = ("import jax; from geojax import sweep; assert jax.device_count() == 2; "  # 2 lanes each: both used
                f"sweep.run_sweep(sweep.load({str(spec_path)!r}), {str(others[-1])!r}, progress=False, lanes=2)")
        subprocess.run([sys.executable, "-c", code], check=True, env=env)
    a = store.read_h5(one)[0]
    assert a["status"]["code"][0, 1].tolist() == [3, 3]  # the wide Delta-i limit leaves the latitude box
    for other in others:
        b = store.read_h5(other)[0]
        for group in ("metrics", "status"):
            for name in a[group]:
                np.testing.assert_array_equal(b[group][name], a[group][name], err_msg=f"{other.name}: {group}/{name}")
        # The per-cycle series to the last bit but one: on an AMD EPYC without AVX-512 (jaxlib 0.10.2) one cycle
        # mean of 80, lon_deg[0, 1, 0, 15], moved by one unit in the last place (4.4e-16) at 128 lanes, at main
        # 66ca5fa as well; every metric and status stays bit for bit.
        for name in a["cycles"]:
            np.testing.assert_allclose(b["cycles"][name], a["cycles"][name], rtol=1e-15, atol=0,
                                       err_msg=f"{other.name}: cycles/{name}")


def test_a_stray_parts_folder_is_refused_in_one_line(tmp_path, capsys):
    """A parts folder that is not a geojax sweep's (no sweep.sha256) does not crash ``--resume``: it is left
    alone and named."""
    out = tmp_path / "x.h5"
    parts = out.with_name(out.name + ".parts")
    parts.mkdir()
    (parts / "chunk").write_text("1")
    assert cli.main(["sweep", str(write_spec(tmp_path)), "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert "is not the parts folder of a geojax sweep" in err and err.count("\n") == 1
    assert sorted(p.name for p in parts.iterdir()) == ["chunk"]


@pytest.mark.parametrize("content", [b"not hdf5 at all", None])
def test_resume_onto_a_file_that_is_not_ours_is_refused_in_one_line(tmp_path, capsys, content):
    out = tmp_path / "y.h5"
    if content is None:
        store.write_h5(out, {"g": {"x": np.zeros(2)}}, "", 0.0)
        with h5py.File(out, "a") as f:
            del f.attrs["config_toml"]
        expected = "is not a geojax results file"
    else:
        out.write_bytes(content)
        expected = "is not an HDF5 file"
    assert cli.main(["sweep", str(write_spec(tmp_path)), "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert expected in err and err.count("\n") == 1


def test_a_kill_after_the_final_write_or_during_clean_up_resumes_to_the_finished_file(straight, tmp_path):
    """The parts folder is renamed before it is deleted, so a kill during the
    clean-up leaves it whole (or a hidden ``.trash-PID`` folder), never a folder without ``sweep.sha256``;
    ``--resume`` then returns the finished file and removes what the killed run left, its half-written
    ``.NAME.tmp-PID`` included."""
    spec, d = straight
    out = sweep.run_sweep(spec, tmp_path / "done.h5", chunk=64, progress=False)
    before = out.read_bytes()
    parts = out.with_name(out.name + ".parts")  # as if killed between the final write and the clean-up
    parts.mkdir()
    (parts / "sweep.sha256").write_text("whatever")
    (parts / "chunk").write_text("64")
    dead = 2 ** 22 + 12345  # above the default pid_max of 4194304: no process has it
    trash = tmp_path / f".done.h5.parts.trash-{dead}"  # as if killed while deleting
    trash.mkdir()
    (trash / "qffc_000000000.npz").write_bytes(b"x")
    torn = tmp_path / f".done.h5.tmp-{dead}"  # as if killed during the final write
    torn.write_bytes(b"half")
    assert sweep.run_sweep(spec, out, resume=True, progress=False) == out
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["done.h5"]


def test_stale_temporaries_are_removed_by_the_next_write_beside_them(tmp_path):
    dead = 2 ** 22 + 12345
    path = tmp_path / "r.h5"
    (tmp_path / f".r.h5.tmp-{dead}").write_bytes(b"torn")
    (tmp_path / f".r.h5.tmp-{os.getppid()}").write_bytes(b"a live process's")  # not ours to remove
    store.write_h5(path, {"g": {"x": np.arange(3.0)}}, "x = 1", 0.0)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f".r.h5.tmp-{os.getppid()}", "r.h5"]


def test_a_sweep_of_repetitions_alone_is_the_first_grid_point_of_a_grid(straight, tmp_path, capsys):
    """No [grid]: a Monte Carlo over the seeds alone, metrics and status [controller, repetition] and /grid holding
    the controllers only.  Second method: its samples are those of the first point of the gridded sweep with
    the same seed (sample j's key is fold_in(seed, j) and the first point's samples are j = 0 .. reps - 1)."""
    import geojax

    _, d = straight
    text = SPEC.replace('[grid]\n"thrusters.beta_max_deg" = [60.0, 90.0]', '"thrusters.beta_max_deg" = 60.0')
    assert "[grid]" not in text
    out = tmp_path / "mc.h5"
    assert cli.main(["sweep", str(write_spec(tmp_path, text)), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "1 grid point(s) x 5 repetition(s) = 5 samples" in printed and "    5 repetitions: ΔV" in printed
    mc = data(out)
    assert mc["metrics/dv_per_year_mps"].shape == mc["status/code"].shape == (1, 5)
    assert set(k for k in mc if k.startswith("grid/")) == {"grid/controller"}
    for name in (k for k in mc if k.startswith(("metrics/", "status/"))):
        np.testing.assert_array_equal(mc[name], d[name][:, 0])
    ds = geojax.open_results(out)
    assert ds.dv_per_year_mps.dims == ("controller", "repetition")
    assert float(geojax.results.summary_table(ds).held_mean.sel(controller="qffc")) == pytest.approx(
        np.mean(d["metrics/dv_per_year_mps"][0, 0]), rel=1e-12)
    assert cli.main(["plot", str(out), "--out", str(tmp_path)]) == 0
    assert (tmp_path / "mc.png").stat().st_size > 10_000
