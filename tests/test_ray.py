"""Sweeps on a Ray cluster (geojax.sweep.cluster): bit for bit a local run, through a worker killed mid-sweep and
a driver killed and resumed; bad addresses and a missing Ray in one line.

The cluster is two Ray nodes on this machine (a head and one more worker node, one CPU each), so the
sweep really runs in two worker processes on two nodes.  A worker is killed with SIGKILL by its process
title (``ray::ChunkWorker``), the driver (a ``geojax sweep --ray`` process) with SIGKILL after its first
chunk is saved.
"""

from __future__ import annotations

import collections
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

# Every process here on the loopback address: the test cluster's nodes bind to 127.0.0.1 (``two_nodes``), and
# Ray, which on Linux turns a loopback address given to ``ray.init`` into the machine's own IP, keeps it when told
# that this is one host (read when ``ray`` is imported; the commands a test starts inherit it).
os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"

from ray.cluster_utils import Cluster  # noqa: E402  (the README's test command installs geojax[ray])

from geojax import cli, store, sweep
from geojax.sweep import cluster

SPEC = """
name = "ray"
scenario = "li2022-qffc"
controllers = ["qffc"]
repetitions = 3
seed = 5
[set]
"duration.days" = 3.0
"errors.h_rv" = 3.0
[grid]
"thrusters.beta_max_deg" = [60.0, 90.0]
"""
CHUNK = 1  # six chunks, so that there is work left when something is killed


def data(path):
    with h5py.File(path) as f:
        return {f"{g}/{k}": f[g][k][()] for g in ("metrics", "status", "grid") for k in f[g]}


def assert_same(path, expected, what):
    got = data(path)
    assert got.keys() == expected.keys()
    for name in expected:
        np.testing.assert_array_equal(got[name], expected[name], err_msg=f"{what}: {name}")


@pytest.fixture(scope="module")
def two_nodes():
    # Both nodes on the loopback address, as ``--ray``'s own local start does.
    nodes = Cluster(initialize_head=True, head_node_args={"num_cpus": 1, "node_ip_address": "127.0.0.1"})
    nodes.add_node(num_cpus=1, node_ip_address="127.0.0.1")
    nodes.wait_for_nodes()
    yield nodes.address
    nodes.shutdown()


@pytest.fixture(scope="module")
def local(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ray")
    (tmp / "s.toml").write_text(SPEC)
    return tmp / "s.toml", data(sweep.run_sweep(sweep.load(tmp / "s.toml"), tmp / "local.h5", chunk=CHUNK,
                                                progress=False))


@pytest.fixture
def chunk_writes(monkeypatch):
    """How many times each chunk file was written."""
    counts, real = collections.Counter(), store.atomic_write

    def counting(path, payload):
        if Path(path).suffix == ".npz":
            counts[Path(path).name] += 1
        real(path, payload)

    monkeypatch.setattr(store, "atomic_write", counting)
    return counts


def worker_processes() -> list[int]:
    """The Ray worker processes of sweep chunks, those running one first."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            title = (proc / "cmdline").read_bytes() if proc.name.isdigit() else b""
        except OSError:
            continue
        if title.startswith(b"ray::ChunkWorker"):
            found.append((not title.startswith(b"ray::ChunkWorker.run"), int(proc.name)))
    return [pid for _, pid in sorted(found)]


def when_first_chunk_saved(parts: Path, action, timeout_s: float = 300.0) -> threading.Thread:
    def watch():
        stop = time.monotonic() + timeout_s
        while time.monotonic() < stop and not (parts.exists() and any(parts.glob("*.npz"))):
            time.sleep(0.02)
        action()

    thread = threading.Thread(target=watch, daemon=True)
    thread.start()
    return thread


def test_worker_placement_shares_each_nodes_cores():
    nodes = [{"NodeID": "b", "Alive": True, "Resources": {"CPU": 2.0}},
             {"NodeID": "a", "Alive": True, "Resources": {"CPU": 8.0, "GPU": 2.0}},
             {"NodeID": "c", "Alive": False, "Resources": {"CPU": 64.0}}]
    assert cluster.placements(nodes, None) == [("a", 4, 1.0), ("a", 4, 1.0), ("b", 2, 0.0)]  # one per GPU, or node
    assert cluster.placements(nodes, 3) == [("a", 4, 1.0), ("b", 2, 0.0), ("a", 4, 1.0)]  # two on a: halves
    assert cluster.placements(nodes, 5)[0] == ("a", 2, pytest.approx(2 / 3))  # three on a: GPUs shared
    with pytest.raises(ValueError, match="no alive node"):
        cluster.placements(nodes[2:], None)
    # Chunks on a GPU cluster: an even share per GPU, at most one GPU batch; a CPU cluster keeps the driver's.
    assert cluster.default_chunk(1000, nodes) == 500 and cluster.default_chunk(10**6, nodes) == 65536
    assert cluster.default_chunk(1000, nodes[::2]) is None


@pytest.mark.slow
def test_a_sweep_on_two_nodes_is_bit_for_bit_the_local_run(two_nodes, local, tmp_path, chunk_writes):
    spec, expected = local
    out = sweep.run_sweep(sweep.load(spec), tmp_path / "ray.h5", chunk=CHUNK, progress=False, ray=two_nodes)
    assert_same(out, expected, "two Ray nodes")
    assert sorted(chunk_writes.values()) == [1] * 6  # every chunk written once
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ray.h5"]


@pytest.mark.slow
def test_a_worker_killed_mid_sweep_leaves_the_results_unchanged(two_nodes, local, tmp_path, chunk_writes):
    """SIGKILL to one worker process once the first chunk is in: Ray restarts it and retries its chunks."""
    spec, expected = local
    killed = []

    def kill_one():
        pids = worker_processes()
        if pids:
            os.kill(pids[0], signal.SIGKILL)
            killed.append(pids[0])

    watcher = when_first_chunk_saved(tmp_path / "ray.h5.parts", kill_one)
    out = sweep.run_sweep(sweep.load(spec), tmp_path / "ray.h5", chunk=CHUNK, progress=False, ray=two_nodes)
    watcher.join()
    assert killed, "no worker process was found to kill"
    assert_same(out, expected, "a worker killed")
    assert sorted(chunk_writes.values()) == [1] * 6


@pytest.mark.slow
def test_a_killed_driver_resumes_on_the_cluster(two_nodes, local, tmp_path):
    spec, expected = local
    out = tmp_path / "ray.h5"
    args = [sys.executable, "-m", "geojax", "sweep", str(spec), "--out", str(out), "--chunk", str(CHUNK), "--quiet",
            "--ray", two_nodes]
    driver = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    when_first_chunk_saved(out.with_name("ray.h5.parts"), lambda: driver.send_signal(signal.SIGKILL)).join()
    assert driver.wait(timeout=60) == -signal.SIGKILL
    saved = sorted((tmp_path / "ray.h5.parts").glob("*.npz"))
    assert 1 <= len(saved) < 6, "the driver was not killed mid-sweep"
    resumed = subprocess.run([*args, "--resume"], capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    assert_same(out, expected, "driver killed, resumed")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ray.h5"]


@pytest.mark.slow
@pytest.mark.parametrize("address", ["127.0.0.1:1", "ray://127.0.0.1:1", "no-port", "host:99999"])
def test_an_unreachable_address_is_one_line_exit_2_nothing_written(local, tmp_path, capsys, address):
    spec, _ = local
    start = time.perf_counter()
    code = cli.main(["sweep", str(spec), "--out", str(tmp_path / "x.h5"), "--ray", address])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and f"--ray {address}" in err, err
    assert list(tmp_path.iterdir()) == []
    assert time.perf_counter() - start < 30


@pytest.mark.slow
def test_ray_missing_is_one_line_exit_2_nothing_written(local, tmp_path, capsys, monkeypatch):
    spec, _ = local
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` raises ImportError
    code = cli.main(["sweep", str(spec), "--out", str(tmp_path / "x.h5"), "--ray"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and 'pip install "geojax[ray]"' in err, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_workers_without_ray_is_refused(local, tmp_path, capsys):
    spec, _ = local
    assert cli.main(["sweep", str(spec), "--out", str(tmp_path / "x.h5"), "--workers", "2"]) == 2
    assert "--workers: only with --ray" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_a_local_start_finishes_beside_a_killed_cluster(tmp_path):
    """After a Ray head was killed (SIGKILL, its GCS server and raylet too), ``--ray`` hung
    ten minutes on "Failed to connect to GCS": ``ray.init()`` joined the dead cluster Ray had recorded.  Now
    ``--ray`` starts an instance of its own and the sweep finishes.  Ray's temporary folder is this test's
    own (``RAY_TMPDIR``, short: Ray's socket paths must fit 107 characters), so no other Ray run on the
    machine sees the dead cluster."""
    import shutil
    import socket
    import tempfile

    root = Path(sweep.__file__).parents[2]
    ray_tmp = Path(tempfile.mkdtemp(prefix="gjray", dir="/tmp"))
    env = {**os.environ, "RAY_TMPDIR": str(ray_tmp),
           "PYTHONPATH": os.pathsep.join([str(root), str(root / "tests")])}
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]

    def ours() -> list[int]:
        """The processes of the Ray instances started with this test's temporary folder."""
        found = []
        for proc in Path("/proc").iterdir():
            try:
                if proc.name.isdigit() and str(ray_tmp).encode() in (proc / "cmdline").read_bytes():
                    found.append(int(proc.name))
            except OSError:
                continue
        return found

    def kill_ours():
        for pid in ours():
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

    (tmp_path / "s.toml").write_text('scenario = "li2022"\ncontrollers = ["own_laws:DAMPER"]\nrepetitions = 1\n'
                                     '[set]\n"duration.days" = 2.0\n[grid]\n"controller.k_inc_per_s" = [1e-5, 1e-4]\n')
    try:
        subprocess.run([str(Path(sys.executable).with_name("ray")), "start", "--head", f"--port={port}",
                        "--node-ip-address=127.0.0.1", "--num-cpus=1", "--include-dashboard=false"],
                       env=env, check=True, capture_output=True, timeout=180)
        assert ours(), "the Ray head did not start"
        # Killed until nothing of it is left and its port refuses (on a loaded machine a process of the head may
        # still be starting when the first kill comes)
        deadline = time.monotonic() + 60
        while True:
            kill_ours()
            time.sleep(1.0)
            with socket.socket() as probe:
                answers = probe.connect_ex(("127.0.0.1", port)) == 0
            if not ours() and not answers or time.monotonic() > deadline:
                break
        assert (ray_tmp / "ray" / "ray_current_cluster").read_text().strip().endswith(f":{port}")  # recorded

        geojax_command = [str(Path(sys.executable).with_name("geojax")), "sweep", "s.toml"]
        # (``--ray auto`` against the dead recorded cluster is meant to fail in one line: on a fresh clone here it
        # connected and then reported its workers lost, exit 1; not checked until that is understood.)
        run = subprocess.run([*geojax_command, "--out", "s.h5", "--ray", "-q"], cwd=tmp_path, env=env,
                             capture_output=True, text=True, timeout=540)
        assert run.returncode == 0, run.stderr
        assert "Failed to connect" not in run.stderr
        with h5py.File(tmp_path / "s.h5") as f:
            assert f["metrics/dv_per_year_mps"].shape == (1, 2, 1)
    finally:
        kill_ours()
        shutil.rmtree(ray_tmp, ignore_errors=True)
