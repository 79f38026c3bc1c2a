"""The width of a compiled batch (``geojax.lanes``): chosen by the device, never in the numbers.

Checks: a sweep forced to a wide batch on the CPU writes the same file bit for bit as the default width (the
second method is the same sweep at another width); the memory model against XLA's own ``memory_analysis``
of a compiled batch (an independent measurement); the width rules on a GPU's memory (arithmetic); a width
that cannot fit refused before anything is written; the vectorised keys against ``jax.random.key`` one seed
at a time.
"""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import cli, lanes, store, sweep
from geojax.control import qffc
from geojax.control.base import Sizing
from geojax.runner.rollout import keys_of

SPEC = """
name = "wide"
scenario = "li2022-qffc"
controllers = ["qffc"]
repetitions = 6
seed = 11
cycles = true
[set]
"duration.days" = 20
"errors.h_rv" = 1.0
"errors.h_att" = 1.0
[grid]
"thrusters.beta_max_deg" = [60.0, 80.0]
"""


@pytest.mark.slow
def test_a_wide_batch_writes_the_same_file_bit_for_bit(tmp_path):
    """1024 QFFC lanes against the default 128, 20 days with errors: before the cycle sums were taken in order
    (``loop.metrics.sum_over_cycles``) ``mean_beta_deg`` moved by 4.5e-16 between these widths."""
    path = tmp_path / "wide.toml"
    path.write_text(SPEC)
    spec = sweep.load(path)
    default = store.read_h5(sweep.run_sweep(spec, tmp_path / "default.h5", progress=False))[0]
    wide = store.read_h5(sweep.run_sweep(spec, tmp_path / "wide.h5", progress=False, lanes=1024))[0]
    assert np.all(default["metrics"]["mean_beta_deg"] > 0)  # burns flown: the sums are not trivial
    for group in ("metrics", "cycles", "status"):
        for name in default[group]:
            np.testing.assert_array_equal(wide[group][name], default[group][name], err_msg=f"{group}/{name}")


@pytest.mark.slow
def test_the_memory_model_covers_what_xla_allocates():
    """The model's bytes per lane (margin taken off) against ``memory_analysis`` of the compiled QFFC batch on
    the CPU (temporaries, arguments, outputs): at least what XLA plans, and not wildly more."""
    from geojax import scenario
    from geojax.runner.rollout import record_bytes_per_cycle, rollout_fn
    from geojax.runner.setup import prepare

    width, days = 64, 12
    batch = prepare([scenario.load("li2022-qffc", {"duration.days": days})])
    one = rollout_fn(batch, lanes=width)
    params = jax.tree_util.tree_map(lambda x: jnp.repeat(x, width, 0), batch.params)
    compiled = jax.jit(jax.vmap(lambda p, k: one(p, k)[2])).lower(params, keys_of(np.arange(width))).compile()
    use = compiled.memory_analysis()
    measured = (use.temp_size_in_bytes + use.argument_size_in_bytes + use.output_size_in_bytes) / width
    model = lanes.bytes_per_lane(batch.controller, batch.n_cycles, record_bytes_per_cycle(batch)) / lanes.MEMORY_MARGIN
    assert measured <= model <= 3 * measured


def test_the_width_follows_the_platform_and_the_memory():
    gib = 1 << 30
    records = lanes.RecordBytes(450, 256)  # li2022-qffc's, record_bytes_per_cycle
    per_lane = lanes.bytes_per_lane(qffc.CONTROLLER, 366, records)
    assert lanes.plan(qffc.CONTROLLER, 366, 10_000, records, platform="cpu", available=8 * gib).lanes == 128
    narrow = dataclasses.replace(qffc.CONTROLLER, sizing=Sizing(lanes_cpu=32))
    asked = []
    assert lanes.plan(narrow, 366, 3, lambda: asked.append(1) or records, platform="cpu",
                      available=8 * gib)[::4] == (32, "measured")
    assert not asked  # fits at any record size: nothing traced
    assert lanes.plan(narrow, 36_600, 3, records, platform="cpu", available=gib // 4).lanes < 32  # capped by memory
    gpu = lanes.plan(qffc.CONTROLLER, 366, 131_072, records, platform="gpu", available=70 * gib)
    assert gpu.lanes == lanes.ACCELERATOR_MAX_LANES  # 65,536 lanes x 361 kB = 23.7 GB: fits 80 % of 70 GiB
    small = lanes.plan(qffc.CONTROLLER, 366, 131_072, records, platform="gpu", available=2 * gib)
    assert small.lanes * per_lane <= lanes.FREE_FRACTION * 2 * gib < 2 * small.lanes * per_lane  # the widest power of 2
    assert small.lanes & (small.lanes - 1) == 0
    few = lanes.plan(qffc.CONTROLLER, 366, 3000, records, platform="gpu", available=70 * gib)
    assert few.lanes == 4096  # no wider than the sweep needs (rounded up to a power of two)
    assert lanes.plan(qffc.CONTROLLER, 366, 5, records, platform="gpu", available=70 * gib).lanes == \
        lanes.ACCELERATOR_MIN_LANES
    with pytest.raises(ValueError, match="lanes: 65536 lanes need about .* at most"):
        lanes.plan(qffc.CONTROLLER, 366, 10, records, platform="gpu", available=2 * gib, requested=65536)
    with pytest.raises(ValueError, match="lanes: must be an integer"):
        lanes.plan(qffc.CONTROLLER, 366, 10, records, requested=0)


def test_controllers_declare_their_widths():
    from geojax import scenario
    from geojax.runner.setup import controller_of

    made = {name: controller_of([scenario.load(f"li2022-{name}")]) for name in ("qffc", "fompc", "mpc")}
    assert {name: c.sizing.lanes_cpu for name, c in made.items()} == {"qffc": 128, "fompc": 32, "mpc": 8}
    assert made["mpc"].sizing.working_bytes > 50 * made["qffc"].sizing.working_bytes  # the interior point's matrices


def test_a_batch_that_cannot_fit_is_refused_before_anything_is_written(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text(SPEC)
    out = tmp_path / "out.h5"
    assert cli.main(["sweep", str(path), "--out", str(out), "--lanes", "4000000", "-q"]) == cli.EXIT_BAD_INPUT
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "lanes: 4000000 lanes need about" in err[0] and "at most" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]
    path.write_text(SPEC.replace('seed = 11', 'seed = 11\nlanes = 0'))
    assert cli.main(["sweep", str(path), "--out", str(out), "-q"]) == cli.EXIT_BAD_INPUT
    assert "lanes: must be an integer from 1" in capsys.readouterr().err


def test_keys_made_on_the_device_are_jax_random_key_of_each_seed():
    seeds = [0, 1, 7, 2**31 - 1, 2**31, 2**32 + 5, 2**62 + 3, -1, -(2**40)]
    one_by_one = jnp.stack([jax.random.key(s) for s in seeds])
    np.testing.assert_array_equal(jax.random.key_data(keys_of(seeds)), jax.random.key_data(one_by_one))
    with pytest.raises(ValueError, match="seeds: must be a list of integers"):
        keys_of([0.5, 1.0])


def test_a_sweep_runs_on_as_few_devices_as_its_samples_fill():
    """``sweep.batch.devices_for``: a device left with padding alone would compile its copy of the program for
    nothing, so a call uses ceil(samples / lanes) devices, at least one and at most the local ones (counted
    here against ``jax.local_devices()``, whatever this process has)."""
    from geojax.sweep.batch import devices_for

    local = jax.local_devices()
    for samples, lanes_per_device in [(1, 64), (4, 64), (64, 64), (65, 64), (10, 4), (10**6, 1)]:
        used = devices_for(samples, lanes_per_device)
        assert used == local[:min(len(local), -(-samples // lanes_per_device))]
        assert len(used) * lanes_per_device >= min(samples, len(local) * lanes_per_device)


@pytest.mark.parametrize("name, changes", [pytest.param("li2022-momentum", {}, marks=pytest.mark.slow),
                                           ("li2022-qffc-ranging", {}),
                                           pytest.param("li2022-qffc-ranging", {"navigation.estimate_biases": True},
                                                        marks=pytest.mark.slow)])
def test_the_record_bytes_are_those_a_run_returns(name, changes):
    """Second method: the memory model's bytes per cycle (``record_bytes_per_cycle``, ``jax.eval_shape`` over a
    ``Batch`` of shapes, nothing computed) against the records one sample's run returns (its arrays' bytes, two
    cycles); and the kept columns per cycle each further state states (``StateModel.columns_per_cycle``) against
    the columns a sweep keeps of its records (``loop.metrics.state_columns``)."""
    from geojax import scenario
    from geojax.loop.metrics import state_columns
    from geojax.runner.rollout import loop, record_bytes_per_cycle
    from geojax.runner.setup import prepare

    sc = scenario.load(name, {"duration.days": 2, **changes})
    batch = prepare([sc])
    params = jax.tree_util.tree_map(lambda x: x[0], batch.params)
    _, records = jax.jit(lambda p, k: loop(p, k, batch.shared, controller=batch.controller, step_s=batch.step_s,
                                           dynamics=batch.dynamics, states=batch.states))(params, jax.random.key(0))
    n_cycles = records.cycles.dv_mps.shape[0]
    returned = sum(np.asarray(x).nbytes for x in jax.tree_util.tree_leaves(records.cycles)) // n_cycles
    assert record_bytes_per_cycle(prepare([sc], shapes_only=True)).loop == returned
    assert batch.states
    for model in batch.states:
        record = records.cycles.states[model.name]
        columns = jax.eval_shape(lambda r: state_columns({model.name: r}), record)
        assert model.columns_per_cycle == len(columns), (model.name, model.columns_per_cycle, len(columns))


@pytest.mark.parametrize("name, overrides, n, days", [
    pytest.param("li2022-qffc", {"errors.h_rv": 1.0, "errors.h_att": 1.0}, 40, 10,  # 1-2 of 40 an ulp apart before
                 marks=pytest.mark.slow),  # the slow tier: the default tier's second longest test
    pytest.param("li2022-qffc-ranging", {}, 24, 6, marks=pytest.mark.slow),  # the filter's RMS and NEES: 5-12 of
    # 24 an ulp apart before (the slow tier: 112 s of the default tier's longest worker)
])
def test_every_metric_is_the_same_at_every_lane_width(name, overrides, n, days):
    """The metrics program of one batch's records compiled at n, 64 and 1024 lanes gives every metric bit for bit
    (the Delta-V per RTN axis, the filter's RMS, percentiles and means included: ``geojax.reductions`` stores the
    values before it adds them, in the cycles' order). Independent check: the same records, three compiled
    widths."""
    from geojax import scenario, simulate_batch
    from geojax.runner import rollout

    sc = [scenario.load(name, {"duration.days": days, **overrides})] * n
    result = simulate_batch(sc, seeds=np.arange(n))
    batch = rollout.prepare(sc)
    records = jax.tree_util.tree_map(jnp.asarray, result.records)
    final = jax.tree_util.tree_map(jnp.asarray, result.final)
    widths = {}
    for width in (n, 64, 1024):
        p, f, r = (rollout.pad_lanes(t, width) for t in (batch.params, final, records))
        m = rollout.metrics_batch(p, f, r, n_cycles=batch.n_cycles, step_s=batch.step_s,
                                  steps_per_cycle=batch.shared.env.earth_angle_rad.shape[1], states=batch.states,
                                  controller_metrics=batch.controller.metrics)
        widths[width] = {k: np.asarray(v)[:n] for k, v in m.items()}
    for width in (64, 1024):
        differ = [k for k in widths[n] if not np.array_equal(widths[n][k], widths[width][k])]
        assert not differ, (width, differ)
    assert np.all(widths[n]["dv_per_year_mps"] > 0)
