"""Sharding a batch over two simulated host devices gives the same numbers as one device."""

import os
import subprocess
import sys
import textwrap

import jax
import numpy as np
import pytest

SCRIPT = textwrap.dedent(
    """
    import sys, numpy as np, jax, jax.numpy as jnp
    import geojax
    from geojax.physics import constants as c
    from geojax.physics.dynamics import SpacecraftState
    from geojax.physics.forces import ForceModel
    from geojax.parallel import replicate, shard_batch
    from geojax.loop.simulate import propagate as propagate_cycles
    from geojax.physics.propagate import MEE, environment_grid, steps_per_cycle
    n = steps_per_cycle(3600.0); h = c.SIDEREAL_DAY_S / n
    env = environment_grid(0.0, 0.0, 69.0, h, 2, n)
    mee = jnp.array([42164e3, 1e-4, 0.0, 1e-3, 0.0, 0.0]) + jnp.arange(4)[:, None] * jnp.array([1e3, 0, 0, 0, 0, 0.5])
    states = SpacecraftState(mee, jnp.full(4, 3000.0), jnp.zeros(4))
    if len(jax.devices()) > 1:
        states, env = shard_batch(states), replicate(env)
    run = jax.jit(jax.vmap(lambda s: propagate_cycles(MEE, s, env, ForceModel(srp_area_m2=20.0), h)))
    final, means = run(states)
    np.save(sys.argv[1], np.concatenate([np.asarray(final.orbit).ravel(), np.asarray(means.lon_rad).ravel()]))
    print(len(jax.devices()))
    """
)


def run_with_devices(count, path):
    env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={count}")
    out = subprocess.run([sys.executable, "-c", SCRIPT, str(path)], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == str(count)
    return np.load(path)


HOST_DEVICES = pytest.mark.skipif(jax.default_backend() != "cpu", reason="XLA host devices: the CPU's device count")


@pytest.mark.slow
@HOST_DEVICES
def test_two_devices_match_one(tmp_path):
    one = run_with_devices(1, tmp_path / "one.npy")
    two = run_with_devices(2, tmp_path / "two.npy")
    np.testing.assert_allclose(two, one, rtol=1e-14, atol=0)


@HOST_DEVICES
def test_importing_geojax_leaves_the_device_count_to_the_command():
    """``geojax`` (the CLI) asks for one XLA CPU device per core after importing the package, so nothing in
    the package may start JAX's backend at import (a jnp array built at module level did, and every
    ``geojax sweep`` ran on one core)."""
    code = ("import geojax; from geojax import cli, sweep, tune; from geojax.parallel import use_host_cores; "
            "use_host_cores(2); import jax; print(jax.device_count())")
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "2"


def test_per_device_shared_arguments_are_read_whole_and_can_be_replaced():
    """``parallel.per_device(..., shared=...)``: the shared arguments (a grid, a force model) reach every device
    whole, after the batched ones, and ``run(..., shared=...)`` replaces them; checked against the function
    applied to the whole batch in numpy (the second method)."""
    import jax
    import jax.numpy as jnp

    from geojax.parallel import per_device

    def fn(x, table, scale):
        return {"y": x[:, None] * table[None, :] + scale}

    x = np.arange(4.0)
    table = np.array([1.0, 10.0, 100.0])
    run, compile_s = per_device(fn, (x,), jax.local_devices(), shared=(jnp.asarray(table), jnp.asarray(0.5)))
    assert compile_s >= 0.0
    np.testing.assert_array_equal(run(x)["y"], x[:, None] * table[None, :] + 0.5)
    np.testing.assert_array_equal(run(2 * x, shared=(jnp.asarray(-table), jnp.asarray(1.0)))["y"],
                                  2 * x[:, None] * -table[None, :] + 1.0)
