"""Ctrl-C in the middle of a real ``geojax sweep`` and ``geojax tune``: SIGINT sent to the
console script once its first piece of work is saved.  Both end with status 130 and no abort text, say what is
saved and how to go on (a sweep interrupted while it compiles too); the sweep's ``--resume`` finishes with the file an uninterrupted run writes.

The law is ``tests/own_laws.py``'s damper (a feedback law compiles in a fraction of the QFFC's time), run one lane
per device so that each chunk takes seconds and the signal lands between the first chunk and the last.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest
import numpy as np

import geojax
from geojax import scenario, sweep

ROOT = Path(geojax.__file__).parents[1]
GEOJAX = Path(sys.executable).with_name("geojax")
SPEC = """
name = "interrupted"
scenario = "li2022"
controllers = ["own_laws:DAMPER"]
repetitions = 2
seed = 3
[set]
"duration.days" = 300.0
"errors.h_rv" = 1.0
[grid]
"controller.k_inc_per_s" = [1e-6, 1e-5, 1e-4, 1e-3]
"""
ABORT_TEXT = ("terminate called", "FATAL", "Traceback")


def interrupted(argv: list[str], folder: Path, ready) -> subprocess.CompletedProcess:
    """Run ``geojax ARGV`` in ``folder``, send SIGINT once ``ready(stderr so far)`` is true, and wait for the end."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "tests")])}
    err_path = folder / f"stderr-{time.monotonic_ns()}.txt"
    with open(err_path, "w") as err_file:
        # SIGINT at its default in the child, as at a terminal: a shell that starts the tests in the background
        # (``cmd &``) ignores it, and a Python started with SIGINT ignored never raises KeyboardInterrupt
        process = subprocess.Popen([str(GEOJAX), *argv], cwd=folder, env=env, stdout=subprocess.PIPE,
                                   stderr=err_file, text=True,
                                   preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        begun = time.monotonic()
        while not ready(err_path.read_text()) and process.poll() is None and time.monotonic() - begun < 540:
            time.sleep(0.1)
        assert process.poll() is None, "the run ended before the moment to interrupt it"
        process.send_signal(signal.SIGINT)
        out, _ = process.communicate(timeout=120)
    err = err_path.read_text()
    err_path.unlink()
    return subprocess.CompletedProcess(argv, process.returncode, out, err)


def data(path):
    with h5py.File(path) as f:
        return {f"{g}/{k}": f[g][k][()] for g in ("metrics", "status", "grid") for k in f[g]}


@pytest.mark.slow
def test_ctrl_c_in_a_sweep_says_what_is_saved_and_resume_finishes_the_same_file(tmp_path):
    (tmp_path / "s.toml").write_text(SPEC)
    parts = tmp_path / "s.h5.parts"
    flags = ["--chunk", "2", "--lanes", "1"]
    # During the compilation (daemon threads inside XLA): the process aborted at exit before.
    run = interrupted(["sweep", "s.toml", "--out", "s.h5", *flags], tmp_path, lambda err: ": compiling" in err)
    assert run.returncode == 130, run.stderr
    assert not any(text in run.stderr for text in ABORT_TEXT), run.stderr
    assert run.stderr.strip().splitlines()[-1] == ("geojax sweep: interrupted; no chunk had finished, nothing is "
                                                   "saved: `geojax sweep s.toml --out s.h5 --resume` starts it afresh")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]
    # Between chunks.
    run = interrupted(["sweep", "s.toml", "--out", "s.h5", *flags], tmp_path, lambda err: any(parts.glob("*.npz")))
    assert run.returncode == 130, run.stderr
    assert not any(text in run.stderr for text in ABORT_TEXT), run.stderr
    last = run.stderr.strip().splitlines()[-1]
    chunks = len(list(parts.glob("*.npz")))
    assert 1 <= chunks < 4 and not (tmp_path / "s.h5").exists()
    assert last == (f"geojax sweep: interrupted; {chunks} chunk(s) of {2 * chunks} sample(s) are saved in "
                    f"s.h5.parts: `geojax sweep s.toml --out s.h5 --resume` continues from them")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "tests")])}
    resumed = subprocess.run([str(GEOJAX), "sweep", "s.toml", "--out", "s.h5", "--resume", "--lanes", "1", "-q"],
                             cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    sys.path.insert(0, str(ROOT / "tests"))  # own_laws, for the straight run in this process
    try:
        straight = sweep.run_sweep(sweep.load(tmp_path / "s.toml"), tmp_path / "straight.h5", progress=False,
                                   lanes=1)
    finally:
        sys.path.remove(str(ROOT / "tests"))
    got, want = data(tmp_path / "s.h5"), data(straight)
    assert got.keys() == want.keys()
    for key in want:
        np.testing.assert_array_equal(got[key], want[key], err_msg=key)


@pytest.mark.slow
def test_ctrl_c_in_a_tune_marks_the_file_interrupted_and_says_there_is_no_resume(tmp_path):
    config = scenario.load("li2022").config
    (tmp_path / "damped.toml").write_text(scenario.to_toml(
        {**config, "station": {**config["station"], "box_half_width_deg": 1.0},
         "controller": {"kind": "own_laws:DAMPER", "k_inc_per_s": 1e-4}}))
    (tmp_path / "t.toml").write_text('scenario = "damped.toml"\nparameters = ["k_inc"]\ndays = 30.0\nstarts = 2\n'
                                     'iterations = 200\n')
    out = tmp_path / "t.h5"

    def iterations() -> int:
        try:
            with h5py.File(out) as f:
                return len(f["iterations/wall_s"])
        except (OSError, KeyError):
            return 0

    run = interrupted(["tune", "t.toml", "--out", "t.h5"], tmp_path, lambda err: iterations() >= 2)
    assert run.returncode == 130, run.stderr
    assert not any(text in run.stderr for text in ABORT_TEXT), run.stderr
    with h5py.File(out) as f:
        status = f.attrs["status"]
        done = len(f["iterations/wall_s"])
    assert status.startswith(f"interrupted after {done} iteration(s)") and done >= 2
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith(f'geojax tune: interrupted; t.h5 holds the iterations done, status "{status}"')
    assert last.endswith("; a tuning cannot be resumed: `geojax tune t.toml --out t.h5` runs it again")
