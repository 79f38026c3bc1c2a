"""The benchmarks' harness (``benchmarks/harness``): timing, results files, devices, and one benchmark run end to
end in its quick mode."""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"
sys.path.append(str(BENCHMARKS))
import harness  # noqa: E402
from harness import devices  # noqa: E402

from geojax.parallel import DEVICE_COUNT_FLAG as COUNT  # noqa: E402


def test_timing_a_jitted_function_reports_its_compilation_apart_and_the_fastest_call():
    """The result is the function's (checked against NumPy); best <= median; compilation measured apart."""
    x = jnp.linspace(0.0, 1.0, 10_000)
    compiled, compile_s = harness.compile_jitted(jax.jit(lambda v: jnp.sum(jnp.sin(v) ** 2)), x)
    result, timing = harness.measure(compiled, x, repeats=3, warmup=1, compile_s=compile_s)
    assert float(result) == pytest.approx(np.sum(np.sin(np.linspace(0.0, 1.0, 10_000)) ** 2), rel=1e-12)
    assert compile_s > 0 and timing.compile_s == compile_s
    assert 3 <= timing.attempts <= 3 + harness.timing.EXTRA_CALLS
    assert 0 < timing.best_s <= timing.median_s
    assert timing.row()["run_s"] == timing.best_s


def test_timing_waits_for_the_call_and_leaves_warm_up_calls_out():
    """A call that sleeps 50 ms takes at least that (the clock's lower bound); warm-up calls are made but not timed."""
    calls = []

    def sleeper():
        calls.append(1)
        time.sleep(0.05)

    _, timing = harness.measure(sleeper, repeats=2, warmup=2)
    assert len(calls) == 2 + timing.attempts
    assert all(0.05 <= call.wall_s < 5.0 for call in timing.calls)
    assert timing.best.cpu_s < 0.05  # sleeping costs this process no CPU time


def test_the_best_call_is_the_fastest_undisturbed_one():
    quiet_slow = harness.Call(wall_s=2.0, cpu_s=2.0, machine_busy_s=2.0, steal_s=0.0)
    disturbed_fast = harness.Call(wall_s=1.0, cpu_s=1.0, machine_busy_s=2.0, steal_s=0.0)  # another core busy
    assert disturbed_fast.disturbed and not quiet_slow.disturbed
    assert harness.Timing((disturbed_fast, quiet_slow)).best == quiet_slow
    assert harness.Timing((disturbed_fast,)).best == disturbed_fast  # none quiet: the fastest
    assert harness.total([quiet_slow, disturbed_fast]).wall_s == 3.0


def test_results_files_round_trip(tmp_path):
    """What ``write`` writes, ``read`` gives back: the data as given, the facts under ``meta``, the Markdown under
    its title with the command that made it."""
    run = harness.Run("python benchmarks/x.py --quick", "2026-01-01 00:00 UTC", [0.5, 0.4, 0.3], time.perf_counter(),
                      {"xla_flags": f"{COUNT}=1", "jax_platforms": None, "cores": [0]})
    data = {"rows": [{"batch": 64, "orbits_per_s": 12.5}], "ratio": {"a": {"b": 2.0}}}
    body = harness.table(["batch", "orbits/s"], [[64, "12.5"]])
    text = harness.write(tmp_path / "x", run, "A title", data, body, facts={"quick": True})
    meta, read_back = harness.read(tmp_path / "x")
    assert read_back == data
    assert meta["command"] == run.command and meta["quick"] is True and meta["xla_flags"] == f"{COUNT}=1"
    assert meta["load_average"]["start"] == [0.5, 0.4, 0.3] and len(meta["load_average"]["end"]) == 3
    assert meta["jax"] == jax.__version__ and meta["device"].endswith(jax.devices()[0].device_kind)
    assert meta["source_revision"] != ""
    assert (tmp_path / "x.md").read_text() == text
    lines = text.splitlines()
    assert lines[0] == "# A title" and lines[2].startswith("`python benchmarks/x.py --quick`, 2026-01-01 00:00 UTC")
    assert lines[4:] == ["| batch | orbits/s |", "|---|---:|", "| 64 | 12.5 |"]


def test_ratios_divide_each_rate_by_each_peers():
    table = harness.ratios({"geojax 900 s": 300.0, "geojax 1800 s": 600.0}, {"heyoka": 60.0, "scipy": 0.2})
    assert table == {"geojax 900 s": {"heyoka": 5.0, "scipy": 1500.0},
                     "geojax 1800 s": {"heyoka": 10.0, "scipy": 3000.0}}
    assert harness.ratio_table(table, "geojax")[2] == "| geojax 900 s | 5 | 1.5e+03 |"


def test_xla_flags_keep_the_users_flags():
    def flags(user: str, devices_: harness.Devices) -> str:
        return harness.environment(devices_, base={"XLA_FLAGS": user})["XLA_FLAGS"]

    user = "--xla_cpu_enable_xprof_traceme --xla_cpu_parallel_codegen_split_count=4"
    assert flags(user, harness.Devices(host_device_count=2)) == f"{user} {COUNT}=2"
    assert flags("", harness.Devices(host_device_count=2)) == f"{COUNT}=2"
    assert flags("", harness.Devices(cores=(0,))) == f"{COUNT}=1"  # by default one device per core
    # a device count the user gave wins, unless the measurement needs exactly its own
    assert flags(f"--a {COUNT}=8 --b", harness.Devices(host_device_count=2)) == f"--a {COUNT}=8 --b"
    assert flags(f"--a {COUNT}=8 --b", harness.Devices(1, replace_count=True)) == f"--a --b {COUNT}=1"
    env = harness.environment(harness.Devices(host_device_count=3, platform="cpu"), base={"XLA_FLAGS": "--a", "X": "y"})
    assert env == {"XLA_FLAGS": f"--a {COUNT}=3", "JAX_PLATFORMS": "cpu", "X": "y"}


def test_devices_are_not_set_up_once_jax_has_started():
    jax.devices()  # JAX's backend exists in this process from here on
    before = os.environ.get("XLA_FLAGS")
    with pytest.raises(RuntimeError, match="after JAX started"):
        devices.set_up(harness.Devices(host_device_count=7))
    assert os.environ.get("XLA_FLAGS") == before


@pytest.mark.filterwarnings("ignore:os.fork:RuntimeWarning")  # JAX's threads here; the child only pins and execs
def test_a_child_gets_its_devices_and_its_core():
    code = ("import json, os; print('noise'); print(json.dumps([os.environ['XLA_FLAGS'], "
            "os.environ['JAX_PLATFORMS'], sorted(os.sched_getaffinity(0))]))")
    core = harness.usable_cores()[-1]
    flags, platform, cores = harness.run_json(
        ["-c", code], harness.Devices(host_device_count=1, replace_count=True, platform="cpu", cores=(core,)))
    assert flags.split()[-1] == f"{COUNT}=1" and platform == "cpu" and cores == [core]


@pytest.mark.slow
def test_a_benchmark_runs_end_to_end_in_its_quick_mode(tmp_path):
    """``benchmarks/core.py`` at its smallest (no baselines, batch 1, one cycle, no closed loop, one round) writes
    its two files in the harness's format, under ``--out``."""
    command = ["benchmarks/core.py", "--baseline", "--batches", "1", "--cycles", "1", "--loop-days", "0", "--rounds",
               "1", "--out", str(tmp_path)]
    env = {**os.environ, "PYTHONPATH": str(BENCHMARKS.parent)}
    subprocess.run([sys.executable, *command], cwd=BENCHMARKS.parent, env=env, check=True, capture_output=True,
                   timeout=300)
    meta, data = harness.read(tmp_path / "core")
    assert meta["command"] == "python " + " ".join(command)
    assert meta["xla_flags"].split()[-1] == f"{COUNT}=1" and len(meta["cores"]) == 1
    assert set(data["step"]) == {"geojax", "minimal"}
    for rows in data["step"].values():
        assert rows["1"]["ns_per_rhs_per_sample"] > 0 and rows["1"]["fusions_per_step"] > 0
    text = (tmp_path / "core.md").read_text()
    assert text.startswith("# The integration step\n\n`python benchmarks/core.py --baseline --batches 1")
    assert json.loads((tmp_path / "core.json").read_text())["meta"] == meta
