"""Kill -9 at chosen and at random moments of a real ``geojax sweep`` process, then ``--resume``: bit for bit the
straight run, for both controllers, on one and two devices (the kill and the resume need not agree on the
device count), and nothing left behind but the results file.

The chosen moments are the three writes a sweep makes: a chunk (killed between its temporary file and the
rename), the final HDF5 file (killed with half of it written), and the removal of the parts folder (killed
after one file of it is gone).  A process kills itself there with ``SIGKILL`` (no clean-up handler runs),
through a wrapper of the ``geojax.store`` function that does that write.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from geojax import sweep

SPEC = """
name = "kill"
scenario = "li2022-qffc"
controllers = ["qffc", "fompc"]
repetitions = 2
seed = 11
[set]
"duration.days" = 2.0
"errors.h_rv" = 3.0
"errors.h_att" = 3.0
[grid]
"thrusters.beta_max_deg" = [60.0, 90.0]
"""
CHUNK = "2"  # 2 chunks per controller
# One lane per device, every run: a chunk of 2 then runs on both devices where there are 2 (a chunk that fits one
# device's lanes runs on one, ``sweep.batch.devices_for``); a batch of one lane is its own program (XLA drops the
# batch axis of size 1), so the straight run uses the same width
LANES = 1

# Runs `geojax sweep` in this process, killing it with SIGKILL at the moment named by argv[1].
DYING = r"""
import os, pathlib, signal, sys
from geojax import cli, store
moment, args = sys.argv[1], sys.argv[2:]
die = lambda: os.kill(os.getpid(), signal.SIGKILL)
if moment == "chunk":  # the third chunk (the FOMPC's first): its temporary file written, not renamed
    real, calls = store.atomic_write, []
    def atomic_write(path, data):
        calls.append(path)
        if path.suffix == ".npz" and sum(p.suffix == ".npz" for p in calls) == 3:
            store.temporary(path).write_bytes(data)
            die()
        real(path, data)
    store.atomic_write = atomic_write
elif moment == "final-write":  # half of the results file written under its temporary name
    def write_h5(path, *a, **k):
        store.temporary(pathlib.Path(path)).write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 1000)
        die()
    store.write_h5 = write_h5
elif moment == "clean-up":  # the parts folder renamed and one chunk of it deleted
    real_rmtree = store.shutil.rmtree
    def rmtree(path, *a, **k):
        next(pathlib.Path(path).glob("*.npz")).unlink()
        die()
    store.shutil.rmtree = rmtree
sys.exit(cli.main(["sweep", *args]))
"""


def data(path):
    with h5py.File(path) as f:
        return {f"{g}/{k}": f[g][k][()] for g in ("metrics", "status", "grid") for k in f[g]}


def env_with(devices: int) -> dict:
    return {**os.environ, "XLA_FLAGS": f"--xla_force_host_platform_device_count={devices}"}


@pytest.fixture(scope="module")
def straight(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("kill")
    spec = tmp / "kill.toml"
    spec.write_text(SPEC)
    start = time.perf_counter()
    out = sweep.run_sweep(sweep.load(spec), tmp / "straight.h5", chunk=int(CHUNK), progress=False, lanes=LANES)
    return data(out), time.perf_counter() - start


def run(tmp_path, moment: str, devices: int, resume: bool, kill_after_s: float | None = None) -> int:
    """``geojax sweep`` in a subprocess on ``devices`` devices, killed at ``moment`` ("none": not at all,
    "random": after ``kill_after_s``); its return code."""
    spec, out = tmp_path / "kill.toml", tmp_path / "out.h5"
    if not spec.exists():
        spec.write_text(SPEC)
    args = [str(spec), "--out", str(out), "--chunk", CHUNK, "--lanes", str(LANES), "--quiet",
            *(["--resume"] if resume else [])]
    proc = subprocess.Popen([sys.executable, "-c", DYING, moment, *args], env=env_with(devices))
    try:
        proc.wait(timeout=kill_after_s)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGKILL)
    return proc.wait()


def check(tmp_path, expected, what: str) -> None:
    resumed = data(tmp_path / "out.h5")
    assert resumed.keys() == expected.keys()
    for name in expected:
        np.testing.assert_array_equal(resumed[name], expected[name], err_msg=f"{what}: {name}")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kill.toml", "out.h5"], what


@pytest.mark.slow
def test_killed_at_every_write_and_resumed_on_either_device_count(straight, tmp_path):
    """One sweep killed three times, each resume on another device count: while a chunk is written (1
    device), while the results file is written (2 devices), while the parts are removed (1 device); the
    last resume (2 devices) finds the finished file, removes what the kills left, and it is the straight run."""
    expected, _ = straight
    for moment, devices in (("chunk", 1), ("final-write", 2), ("clean-up", 1)):
        assert run(tmp_path, moment, devices, resume=moment != "chunk") == -signal.SIGKILL, moment
    assert run(tmp_path, "none", 2, resume=True) == 0
    check(tmp_path, expected, "three kills")


@pytest.mark.slow
def test_killed_at_a_random_moment_and_resumed(straight, tmp_path):
    expected, straight_s = straight
    kill_after_s = random.Random("kill-random").uniform(3.0, 3.0 + 2 * straight_s)  # seeded: the same each run
    code = run(tmp_path, "none", 2, resume=False, kill_after_s=kill_after_s)
    assert code in (0, -signal.SIGKILL)
    assert run(tmp_path, "none", 1, resume=True) == 0
    check(tmp_path, expected, f"killed after {kill_after_s:.1f} s")
