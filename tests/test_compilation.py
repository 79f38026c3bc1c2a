"""Compiled and traced programs kept between runs, and durations that reuse one compiled loop.

Checks (second methods, never a stored number): a run whose loop is compiled for more cycles than it flies
(``runner.setup.cycle_slots``, a traced trip count) against the same run compiled for exactly its cycles (the scan
every sweep and tuning runs), bit for bit; a shorter run against the first cycles of a longer one that runs the
same compiled program; a run through the kept traced program (``geojax.traced``) and from a warm cache against
a run with the cache off; a lane-padded batch against its samples; the cache's failures (a folder that cannot
be written, a kept program that cannot be read) as misses with one warning line, never an error.
"""

import functools
import os
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import compilation, scenario, traced
from geojax.runner import rollout
from geojax.runner.setup import cycle_slots, prepare, reference, reference_shape

DAYS = 4


def _equal(a, b, what):
    for (path, x), y in zip(jax.tree_util.tree_flatten_with_path(a)[0], jax.tree_util.tree_leaves(b), strict=True):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y), err_msg=f"{what}: {jax.tree_util.keystr(path)}")


@pytest.fixture(scope="module")
def qffc():
    return scenario.load("li2022-qffc", {"duration.days": DAYS, "errors.h_rv": 1.0, "errors.h_att": 1.0})


@pytest.fixture(scope="module")
def padded(qffc):
    """Two samples with errors, their loop compiled for 32 cycle slots (the cache folder of the session)."""
    return rollout.simulate_batch([qffc, qffc], seeds=[0, 1])


def _environment(**settings) -> dict:
    """This process's environment for a child geojax, without a JAX cache folder of the caller's, with
    ``settings``."""
    return {**{k: v for k, v in os.environ.items() if k != "JAX_COMPILATION_CACHE_DIR"}, **settings}


def test_cycle_slots_cover_every_duration_with_half_to_spare():
    """The slot counts: at least the cycles, fewer than 1.5 times them from 32 cycles up, few distinct values."""
    for n in range(1, 3000):
        slots = cycle_slots(n)
        assert slots >= n and (n <= 32 and slots == 32 or slots < 1.5 * n)
    assert cycle_slots(10) == cycle_slots(30) == 32 and cycle_slots(366) == 384
    assert len({cycle_slots(n) for n in range(1, 3000)}) == 14


@pytest.mark.slow
def test_a_run_in_a_longer_compiled_loop_is_bit_for_bit_the_exact_loops(qffc, padded):
    """The second method: ``rollout`` (one scan over exactly the run's cycles, metrics in the same program), as
    every sweep and tuning compiles it; every metric and per-cycle record equal bit for bit."""
    batch = prepare([qffc, qffc])
    assert batch.shared.env.earth_angle_rad.shape[0] == padded.records.cycles.dv_mps.shape[1] == 4
    exact = jax.jit(jax.vmap(functools.partial(rollout.rollout, controller=batch.controller, step_s=batch.step_s,
                                               dynamics=rollout.for_lanes(batch.dynamics, 2)),
                             in_axes=(0, 0, None, None)))
    _, records, metrics = exact(batch.params, rollout.keys_of(np.arange(2)), batch.shared, None)
    status = metrics.pop("status")
    assert np.all(padded.metrics["mass_used_kg"] > 0) and not np.array_equal(*padded.metrics["dv_per_year_mps"])
    np.testing.assert_array_equal(padded.status, status)
    _equal(metrics, padded.metrics, "metrics")
    _equal(records, padded.records, "records")


@pytest.mark.slow
def test_samples_with_their_own_reference_run_padded_as_in_the_exact_loop():
    """A batch whose samples differ in their forces runs one predictor reference per sample, computed before the
    loop (``prepare(own_references=True)``): in the padded loop (32 slots for 2 cycles) it is padded to the slots
    and the run is the exact loop's (``rollout`` over exactly its cycles, given the same references), bit for
    bit."""
    scenarios = [scenario.load("ye2022-ex1", {"duration.days": 2, "spacecraft.srp_area_m2": area})
                 for area in (40.0, 160.0)]
    padded = rollout.simulate_batch(scenarios)
    batch = prepare(scenarios, own_references=True)
    assert batch.reference_per_sample and batch.references is not None
    exact = jax.jit(jax.vmap(functools.partial(rollout.rollout, controller=batch.controller, step_s=batch.step_s,
                                               dynamics=rollout.for_lanes(batch.dynamics, 2)),
                             in_axes=(0, 0, None, 0)))
    _, records, metrics = exact(batch.params, rollout.keys_of(np.arange(2)), batch.shared, batch.references)
    metrics.pop("status")
    assert not np.array_equal(*padded.metrics["dv_per_year_mps"])
    _equal(metrics, padded.metrics, "metrics")
    _equal(records, padded.records, "records")


@pytest.mark.parametrize("case", ["shared reference", "reference per sample", "no reference"])
def test_the_shapes_the_loop_compiles_for_meanwhile_are_those_of_the_arrays_computed(case):
    """``prepare(on_shapes=...)`` hands ``simulate_batch`` the shapes of the environment grid, the reference and the
    per-sample segments before computing them (the closed loop compiles meanwhile): the same tree, shapes and
    dtypes as the arrays then computed (second method: the arrays themselves), and ``reference_shape`` is what
    ``jax.eval_shape`` of the reference (a trace of it) gives."""
    kind = {"shared reference": ("li2022-qffc", [{}]), "no reference": ("katz2025-continuous", [{}]),
            "reference per sample": ("ye2022-ex1", [{"spacecraft.srp_area_m2": 40.0},
                                                    {"spacecraft.srp_area_m2": 160.0}])}[case]
    scenarios = [scenario.load(kind[0], {"duration.days": 3, **changes}) for changes in kind[1]]
    seen = []
    batch = prepare(scenarios, pad=True, on_shapes=seen.append)
    (shapes,) = seen

    def described(tree):
        leaves, structure = jax.tree_util.tree_flatten(tree)
        return structure, [(tuple(x.shape), str(x.dtype), bool(getattr(x, "weak_type", False))) for x in leaves]

    assert described(shapes.shared) == described(batch.shared)
    assert described(shapes.reference_env) == described(batch.reference_env)
    assert (batch.reference_env is not None) == (case != "no reference")
    if case == "shared reference":
        traced_shape = jax.eval_shape(functools.partial(reference, step_s=batch.step_s, dynamics=batch.dynamics,
                                                        width=batch.controller.reference_cycles),
                                      jax.tree_util.tree_map(lambda x: x[0], batch.params), batch.reference_env)
        assert described(reference_shape(batch.n_cycles, batch.controller.reference_cycles, jnp.float64)) == \
            described(traced_shape)


def test_a_shorter_run_is_the_first_cycles_of_a_longer_one_in_the_same_program(qffc, padded):
    """9 days run the program that 4 days ran (32 slots): their first 4 cycles agree bit for bit (an independent
    run of the same physics, not a slice of one result)."""
    longer = rollout.simulate_batch([scenario.load("li2022-qffc", {**_errors(), "duration.days": 9})] * 2,
                                    seeds=[0, 1])
    assert longer.records.cycles.dv_mps.shape[1] == 9
    _equal(padded.records.cycles, jax.tree_util.tree_map(lambda x: x[:, :4], longer.records.cycles), "cycles")


def test_a_shorter_run_after_a_longer_one_runs_the_longer_ones_program(qffc, monkeypatch):
    """One process, one sample: 40 days (48 cycle slots), then 4 days (32 slots of their own) run the 48-slot loop
    already compiled (``rollout.slots_compiled``): no closed loop compiled or loaded (JAX's own compilation
    events, ``Compilations``), and every metric and cycle record bit for bit those of the same 4 days in a loop
    compiled for their own 32 slots (second method: the run with reuse turned off, whose loop is counted)."""
    from geojax.compilation import Compilations

    monkeypatch.setattr(rollout, "_LOOPS_COMPILED", set())  # this test's loops only, not the session cache's
    monkeypatch.setattr(traced, "kept", lambda *args: False)
    rollout.simulate(scenario.load("li2022-qffc", {**_errors(), "duration.days": 40}))
    with Compilations(min_s=0.0) as log:
        again = rollout.simulate(qffc)
    monkeypatch.setattr(rollout, "REUSE_MAX_RATIO", 0)  # its own 32 slots
    with Compilations(min_s=0.0) as own:
        alone = rollout.simulate(qffc)
    loops = lambda log: [p for p in log.programs if p.name == "closed_loop"]  # noqa: E731
    assert not loops(log) and len(loops(own)) == 1, (log.programs, own.programs)
    assert again.records.cycles.dv_mps.shape == (DAYS,) and again.metrics["mass_used_kg"] > 0
    np.testing.assert_array_equal(again.status, alone.status)
    _equal(again.metrics, alone.metrics, "metrics")
    _equal(again.records, alone.records, "records")


@pytest.mark.slow
def test_a_shorter_run_borrows_the_longer_loop_the_cache_keeps(tmp_path):
    """Across processes: 40 days kept their 48-slot loop in the cache folder; a new process's 4 days load that loop
    (JAX's cache-hit event, through ``Compilations``) instead of compiling one of 32 slots, and get the numbers a
    process with the cache off gets (its own 32 slots, plain ``jit``), bit for bit."""
    code = ("import sys, numpy as np, geojax; from geojax import scenario; from geojax.runner import rollout; "
            "from geojax.compilation import Compilations; "
            "log = Compilations(min_s=0.0).__enter__(); "
            "r = rollout.simulate(scenario.load('li2022-qffc', {'duration.days': float(sys.argv[1]), "
            "'errors.h_rv': 1.0, 'errors.h_att': 1.0})); "
            "np.save(sys.argv[2], np.array([r.metrics[k] for k in sorted(r.metrics)])); "
            "print([p.cached for p in log.programs if p.name.startswith('closed_loop')])")  # traced or plain jit
    folder = tmp_path / "cache"

    def run(days, name, **settings):
        env = _environment(**settings)
        out = subprocess.run([sys.executable, "-c", code, str(days), str(tmp_path / f"{name}.npy")], env=env,
                             capture_output=True, text=True, check=True)
        return out.stdout.split("\n")[-2], np.load(tmp_path / f"{name}.npy")

    assert run(40, "longer", GEOJAX_CACHE_DIR=str(folder))[0] == "[False]"
    served, borrowed = run(4, "borrowed", GEOJAX_CACHE_DIR=str(folder))
    off, own = run(4, "own", GEOJAX_NO_CACHE="1")
    assert served == "[True]" and off == "[False]"
    np.testing.assert_array_equal(borrowed, own)


def test_the_slots_a_run_borrows_are_the_least_compiled_ones_within_reach(monkeypatch):
    """``slots_compiled``: its own count when none is compiled, the least compiled count at or above it, never
    one below it or beyond ``REUSE_MAX_RATIO`` times it."""
    compiled = set()
    call = lambda layout: ((None, None, layout.shared, None), {}, None)  # noqa: E731  (``_loop_call``'s shape)
    monkeypatch.setattr(rollout, "_LOOPS_COMPILED", compiled)
    monkeypatch.setattr(traced, "kept", lambda *args: False)
    layout = lambda count: rollout.Batch(*[None] * 2, count, *[None] * 5)  # noqa: E731  (``shared``: the count)
    pick = lambda own: rollout.slots_compiled(call, layout, own)  # noqa: E731
    monkeypatch.setattr(rollout, "_loop_key", lambda args, static: args[2])
    assert pick(32) == 32
    compiled |= {48, 384, 768}
    assert pick(32) == 48 and pick(64) == 384 and pick(96) == 384 and pick(512) == 768
    compiled.discard(48)
    assert pick(32) == 384 and pick(1024) == 1024  # 768 is below it
    monkeypatch.setattr(rollout, "REUSE_MAX_RATIO", 4)
    assert pick(32) == 32 and pick(96) == 384


def _errors():
    return {"errors.h_rv": 1.0, "errors.h_att": 1.0}


def test_lanes_padded_to_a_power_of_two_leave_each_sample_as_it_was(qffc, padded):
    """Three samples run in four lanes (the last repeated, then dropped): samples 0 and 1 as in a batch of two."""
    assert rollout.lane_slots(3) == 4 and rollout.lane_slots(1) == 1 and rollout.lane_slots(64) == 64
    three = rollout.simulate_batch([qffc] * 3, seeds=[0, 1, 2])
    assert three.status.shape == (3,)
    _equal(jax.tree_util.tree_map(lambda x: x[:2], three.metrics), padded.metrics, "metrics")


def test_one_sample_compiled_for_start_up_is_the_batch_sample_to_rounding(qffc, padded):
    """A single sample's programs are compiled for start-up (no lane axis, XLA's classic emitters, LLVM
    unoptimized, the reference's segments one after another): second method, the same sample in the two-lane
    batch (vmapped, XLA's defaults, the reference's segments side by side): every metric and cycle record to 1e-9
    relative (the programs' own rounding, ~1e-13).  A controller that solves a program each cycle keeps LLVM's
    optimization for its closed loop (``Sizing.one_sample_opt_level``)."""
    from geojax.control import qffc as qffc_law
    from geojax.runner.setup import controller_of

    assert rollout.compiler_options(1) == compilation.ONE_SAMPLE_OPTIONS and rollout.compiler_options(2) is None
    assert compilation.ONE_SAMPLE_OPTIONS["xla_backend_optimization_level"] == 0
    assert rollout.compiler_options(1, qffc_law.CONTROLLER) == compilation.ONE_SAMPLE_OPTIONS
    mpc_loop = rollout.compiler_options(1, controller_of([scenario.load("li2022-mpc")]))
    assert mpc_loop["xla_backend_optimization_level"] == 1 and rollout.compiler_options(2, qffc_law.CONTROLLER) is None
    one = rollout.simulate_batch([qffc], seeds=[0])
    first = lambda tree: jax.tree_util.tree_map(lambda x: np.asarray(x)[:1], tree)  # noqa: E731
    assert one.metrics["mass_used_kg"][0] > 0
    for what, a, b in (("metrics", one.metrics, first(padded.metrics)),
                       ("cycles", one.records.cycles, first(padded.records.cycles))):
        for (path, x), y in zip(jax.tree_util.tree_flatten_with_path(a)[0], jax.tree_util.tree_leaves(b), strict=True):
            x, y = np.asarray(x, float), np.asarray(y, float)
            np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-9 * np.max(np.abs(y), initial=1e-300),
                                       err_msg=f"{what}: {jax.tree_util.keystr(path)}")


def test_the_command_lines_uncontrolled_run_computed_while_compiling_is_the_files(tmp_path, qffc):
    """``geojax simulate --out`` computes the file's uncontrolled ``/reference`` while the closed loop compiles
    (``simulate(meanwhile=...)``): the same datasets as ``reference_and_target`` called on its own afterwards."""
    from geojax import cli, store
    from geojax.runner.report import reference_and_target

    out = tmp_path / "run.h5"
    assert cli.main(["simulate", "li2022-qffc", "--days", "3", "--out", str(out), "-q"]) == 0
    groups, _ = store.read_h5(out)
    uncontrolled, target = reference_and_target(scenario.load("li2022-qffc", {"duration.days": 3}), 3)
    assert groups["reference"]["ix"].shape == (4,)
    _equal(uncontrolled, groups["reference"], "reference")
    _equal(target, groups["target"], "target")


@pytest.mark.slow
def test_the_cache_serves_the_same_numbers_as_no_cache(tmp_path, qffc, padded):
    """A cold cache (the program traced, kept, compiled), a warm one in the same folder (loaded), and the cache
    off (plain ``jit``): the same bits.  Each run in its own process, as a user's runs are."""
    code = ("import sys, numpy as np, geojax; from geojax import scenario, compilation; "
            "from geojax.runner import rollout; "
            f"sc = scenario.load('li2022-qffc', {{'duration.days': {DAYS}, 'errors.h_rv': 1.0, 'errors.h_att': 1.0}}); "
            "r = rollout.simulate_batch([sc, sc], seeds=[0, 1]); "
            "kept = sorted(p.name for p in compilation.cache_dir().glob('*-geojax-traced')) "
            "if compilation.cache_dir() else []; "
            "np.save(sys.argv[1], np.array([r.metrics[k] for k in sorted(r.metrics)])); print(len(kept))")
    env = _environment()
    folder = tmp_path / "cache"
    kept = []
    for name, extra in (("cold", {"GEOJAX_CACHE_DIR": str(folder)}), ("warm", {"GEOJAX_CACHE_DIR": str(folder)}),
                        ("off", {"GEOJAX_NO_CACHE": "1"})):
        out = subprocess.run([sys.executable, "-c", code, str(tmp_path / f"{name}.npy")], env={**env, **extra},
                             capture_output=True, text=True, check=True)
        kept.append(int(out.stdout.split()[-1]))
    assert kept[0] >= 3 and kept[1] == kept[0] and kept[2] == 0  # closed loop, metrics, reference: kept, reused
    cold, warm, off = (np.load(tmp_path / f"{name}.npy") for name in ("cold", "warm", "off"))
    expected = np.array([padded.metrics[k] for k in sorted(padded.metrics)])
    for name, got in (("cold", cold), ("warm", warm), ("off", off)):
        np.testing.assert_array_equal(got, expected, err_msg=name)


def test_an_unusable_cache_folder_warns_once_and_the_run_goes_on(tmp_path):
    """A file where the folder should be: one warning line, the cache off, exit 0."""
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("x")
    env = _environment(GEOJAX_CACHE_DIR=str(blocker / "cache"))
    out = subprocess.run([sys.executable, "-m", "geojax", "scenarios"], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    warnings = [line for line in out.stderr.splitlines() if line.strip()]
    assert len(warnings) == 1 and warnings[0].startswith("geojax: warning: compilation cache") \
        and "running without it" in warnings[0], out.stderr


def test_a_kept_program_that_cannot_be_read_is_a_miss(tmp_path, monkeypatch):
    """A corrupt kept program is traced again (and kept anew); the result is the plain ``jit``'s."""
    monkeypatch.setattr(compilation, "cache_dir", lambda: tmp_path)
    monkeypatch.setattr(traced, "cache_dir", lambda: tmp_path)
    monkeypatch.setattr(traced, "_IN_PROCESS", {})
    double = jax.jit(lambda x: 2.0 * x)
    x = np.arange(3.0)
    np.testing.assert_array_equal(traced.call(double, "double", ("test",), x), 2 * x)
    (kept,) = tmp_path.glob(f"*{traced.SUFFIX}")
    kept.write_bytes(b"not a program")
    monkeypatch.setattr(traced, "_IN_PROCESS", {})
    np.testing.assert_array_equal(traced.call(double, "double", ("test",), x), 2 * x)
    assert kept.read_bytes() != b"not a program"  # kept anew
    assert traced.call(double, "double", None, x) is not None  # no identity: never kept
    assert len(list(tmp_path.glob(f"*{traced.SUFFIX}"))) == 1


def test_compilations_are_recorded_with_their_cache_hits(tmp_path):
    """``Compilations`` counts a program XLA compiled and, in a second process with the same folder, the same
    program served by the cache (JAX's own monitoring events, an independent count)."""
    code = ("import jax, jax.numpy as jnp, geojax; from geojax.compilation import Compilations; "
            "f = jax.jit(lambda x: jnp.cumsum(jnp.sin(x) ** 2)); "
            "log = Compilations(min_s=0.0).__enter__(); f(jnp.arange(5000.0)).block_until_ready(); "
            "p = [q for q in log.programs if '<lambda>' in q.name]; print(len(p), p[0].cached); print(log.summary()); "
            "print(log.made())")
    env = _environment(GEOJAX_CACHE_DIR=str(tmp_path), JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0")
    first, second = (subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                                     check=True).stdout.splitlines() for _ in range(2))
    assert first[0] == "1 False" and "compiled" in first[1]
    assert second[0] == "1 True" and "loaded" in second[1]
    assert first[2].startswith("compiled") and second[2] == "loaded from the cache"  # what progress lines say


def test_unreadable_cache_entries_warn_once_and_are_replaced(tmp_path):
    """Every entry of a filled cache overwritten or cut short (a process killed while JAX wrote it: JAX writes
    in place): the run says so in one line (not JAX's two per entry), gets the uncached program's numbers, exit 0;
    the entries are compiled again and replaced, so the next process is served by the cache (JAX's own hit
    events, through ``Compilations``) and warns no more."""
    code = ("import jax, jax.numpy as jnp, geojax; from geojax.compilation import Compilations; "
            "log = Compilations(min_s=0.0).__enter__(); "
            "print(repr(float(jax.jit(lambda x: jnp.sum(jnp.sin(x) ** 2))(jnp.arange(500.0))))); "
            "print(sum(p.cached for p in log.programs), len(log.programs))")
    env = _environment(GEOJAX_CACHE_DIR=str(tmp_path), JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0")

    def run():
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        value, counts = out.stdout.splitlines()
        return value, [int(n) for n in counts.split()], [line for line in out.stderr.splitlines() if line.strip()]

    value, (hits, programs), warned = run()
    assert hits == 0 and programs >= 1 and not warned
    entries = sorted(tmp_path.glob("*-cache"))
    assert len(entries) >= programs
    spoilt = {}
    for i, entry in enumerate(entries):
        whole = entry.read_bytes()
        spoilt[entry] = b"overwritten" if i % 2 else whole[:len(whole) // 2]
        entry.write_bytes(spoilt[entry])
    again, (hits, _), warned = run()
    assert again == value and hits == 0
    assert len(warned) == 1 and warned[0].startswith(f"geojax: warning: compilation cache {tmp_path}"), warned
    assert all(entry.read_bytes() != bad for entry, bad in spoilt.items() if entry.exists())
    served, (hits, programs), warned = run()
    assert served == value and hits == programs and not warned


SWEEP_TOML = """name = "kept"
scenario = "li2022-qffc"
controllers = ["qffc"]
repetitions = 2
seed = {seed}
lanes = 8
[set]
"duration.days" = 2
"errors.h_rv" = 1.0
[grid]
"thrusters.beta_max_deg" = [70.0, 90.0]
"""


def test_a_sweeps_kept_program_is_found_only_by_what_fixes_it(tmp_path):
    """The identity of a sweep's kept traced program (``sweep.batch._identity``) changes with everything the
    program bakes in beside its arguments' shapes (seed, dispersion, cycle records), and not with what reaches it
    as an argument (the grid's values), so a kept program is never served to a sweep it does not compute."""
    from geojax import sweep
    from geojax.sweep.batch import _identity
    from geojax.sweep.spec import _points, _scenario

    def identity(seed=1, **changes):
        path = tmp_path / f"s{seed}.toml"
        path.write_text(SWEEP_TOML.format(seed=seed))
        spec = sweep.load(path)
        spec = spec.__class__(**{**spec.__dict__, **changes})
        sc = _scenario(spec, "qffc", next(iter(_points(spec))))
        return _identity(spec, "qffc", sc, prepare([sc]))

    base = identity()
    assert base is not None and base == identity()
    assert identity(seed=2) != base
    assert identity(cycles=True) != base
    assert identity(dispersion={"mee_1sigma": [1.0, 0, 0, 0, 0, 0], "offset_ecef_1sigma_km": [0.0, 0, 0]}) != base


@pytest.mark.slow
def test_a_sweep_through_its_kept_program_is_bit_for_bit_the_traced_one(tmp_path):
    """A sweep cold (its program traced and kept), warm (loaded from the folder), with another seed in the same
    folder (another program, not the kept one), and with the cache off: each the same bits as with the cache off."""
    code = ("import sys, numpy as np; from geojax import sweep, store; "
            "out = sweep.run_sweep(sweep.load(sys.argv[1]), sys.argv[2], progress=False); "
            "np.save(sys.argv[3], store.read_h5(out)[0]['metrics']['dv_per_year_mps'])")
    env = _environment()
    folder = tmp_path / "cache"
    for seed in (1, 2):
        (tmp_path / f"s{seed}.toml").write_text(SWEEP_TOML.format(seed=seed))

    def run(name, seed, cache):
        extra = {"GEOJAX_CACHE_DIR": str(folder)} if cache else {"GEOJAX_NO_CACHE": "1"}
        subprocess.run([sys.executable, "-c", code, str(tmp_path / f"s{seed}.toml"), str(tmp_path / f"{name}.h5"),
                        str(tmp_path / f"{name}.npy")], env={**env, **extra}, check=True, capture_output=True)
        return np.load(tmp_path / f"{name}.npy")

    cold, warm, other = run("cold", 1, True), run("warm", 1, True), run("other", 2, True)
    assert len(list(folder.glob(f"*{traced.SUFFIX}"))) >= 2  # the sweep's program of each seed kept
    np.testing.assert_array_equal(cold, run("off", 1, False))
    np.testing.assert_array_equal(warm, cold)
    np.testing.assert_array_equal(other, run("other-off", 2, False))
    assert not np.array_equal(other, cold)  # the seed reaches the numbers: a wrong hit would show


def test_results_cut_on_an_accelerator_are_the_views_a_cpu_gives():
    """``rollout.to_host``: the device-side cut an accelerator takes (``_cut``, run here on the CPU) gives the
    same arrays as the CPU's NumPy views, lanes and cycles alike."""
    tree = {"a": jnp.arange(24.0).reshape(4, 6), "b": (jnp.arange(48).reshape(4, 6, 2), jnp.ones((4, 6, 3, 2)))}
    for cycles in (None, 5):
        views = rollout.to_host(tree, 3, cycles)
        cut = jax.tree_util.tree_map(np.asarray, rollout._cut(tree, 3, cycles))
        _equal(views, cut, f"cycles {cycles}")
        assert views["a"].shape == ((3, 6) if cycles is None else (3, 5))
