"""Small loops compiled whole (``geojax.small_loops``): XLA:CPU's small-loop threshold raised before JAX starts.

Checks: the flag's text rules (added, or merged into the backend options a user gives; a user's own threshold and
every other flag kept); that ``import geojax`` sets it unless told not to; that it takes effect (XLA's optimized
program marks a loop of 64 KiB per iteration as hoisted, which XLA's default, 1 KiB, leaves to the thunks); and
the promise it keeps: the same samples flown with it and with XLA's default (``GEOJAX_XLA_LOOPS=1``, another
process) give every record and metric bit for bit (slow tier; in the default tier ``test_reference_numbers.py``
holds every shipped scenario's numbers, stored before the threshold was raised).  Independent check: XLA's own
program text, and the same flights compiled the other way.
"""

import hashlib
import os
import subprocess
import sys

import jax
import jax.numpy as jnp
import pytest

from geojax import small_loops

FLAG = f"--xla_backend_extra_options=xla_cpu_small_while_loop_byte_threshold={small_loops.SMALL_LOOP_BYTES}"


def test_the_threshold_is_added_or_merged_and_a_users_own_wins():
    assert small_loops.with_small_loops("") == FLAG
    assert small_loops.with_small_loops("--a  --b=1") == f"--a --b=1 {FLAG}"
    merged = small_loops.with_small_loops("--xla_backend_extra_options=xla_cpu_disable_loop_unrolling --a")
    assert merged == ("--xla_backend_extra_options=xla_cpu_disable_loop_unrolling,"
                      f"xla_cpu_small_while_loop_byte_threshold={small_loops.SMALL_LOOP_BYTES} --a")
    own = "--xla_backend_extra_options=xla_cpu_small_while_loop_byte_threshold=5,x --a"
    assert small_loops.with_small_loops(own) == own


def _hoisted(text: str) -> bool:
    return 'xla_cpu_small_call="true"' in text


def test_import_geojax_sets_the_threshold_and_xla_compiles_a_small_loop_whole():
    assert FLAG in os.environ["XLA_FLAGS"].split()  # conftest imported geojax first

    def loop(x):  # 1024 x 8 float64 carried: 64 KiB an iteration, over XLA's default threshold of 1 KiB
        return jax.lax.fori_loop(0, 50, lambda i, y: jnp.sin(y) * 0.5 + y, x)

    assert _hoisted(jax.jit(loop).lower(jnp.ones((1024, 8))).compile().as_text())
    code = ("import os, jax, jax.numpy as jnp, geojax; print(os.environ.get('XLA_FLAGS', ''));"
            "f = lambda x: jax.lax.fori_loop(0, 50, lambda i, y: jnp.sin(y) * 0.5 + y, x);"
            "print('xla_cpu_small_call' in jax.jit(f).lower(jnp.ones((1024, 8))).compile().as_text())")
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    default = subprocess.run([sys.executable, "-c", code], env={**env, small_loops.ENV_XLA_LOOPS: "1"},
                             capture_output=True, text=True, check=True).stdout.split("\n")
    assert FLAG not in default[0].split() and default[1] == "False"
    started = "import os, jax; jax.numpy.zeros(1); import geojax; print(os.environ.get('XLA_FLAGS', ''))"
    late = subprocess.run([sys.executable, "-c", started], env=env, capture_output=True, text=True, check=True)
    assert FLAG not in late.stdout.split() and "small loops kernel by kernel" in late.stderr


FLIGHT = """
import hashlib, sys, jax, numpy as np, geojax
sc = geojax.load_scenario(sys.argv[1], {"duration.days": 2, "errors.h_rv": 1.0, "errors.h_att": 1.0})
result = geojax.simulate_batch([sc] * 3, seeds=np.arange(3))
digest = hashlib.sha256()
for leaf in jax.tree_util.tree_leaves((result.records, result.metrics)):
    digest.update(np.ascontiguousarray(np.asarray(leaf)).tobytes())
print(digest.hexdigest())
"""


@pytest.mark.slow  # the default tier's tests/test_reference_numbers.py holds the shipped scenarios' numbers,
@pytest.mark.parametrize("name", ["li2022-qffc", "li2022-mpc"])  # written before the threshold was raised
def test_a_batch_flies_the_same_with_small_loops_whole_and_kernel_by_kernel(name):
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    digests = [subprocess.run([sys.executable, "-c", FLIGHT, name], env={**env, **extra}, capture_output=True,
                              text=True, check=True).stdout.strip() for extra in ({}, {small_loops.ENV_XLA_LOOPS: "1"})]
    assert len(digests[0]) == len(hashlib.sha256().hexdigest())
    assert digests[0] == digests[1]
