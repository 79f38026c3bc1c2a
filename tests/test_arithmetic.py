"""One rounding at every width (``geojax.arithmetic``): XLA:CPU kept from fusing multiply-adds.

Checks: the flag's text rules (appended on x86-64 only, a user's own ISA flag and every other flag kept), that it
is in effect in this process, and the promise it keeps: a sample's every record bit for bit in batches of 2 and 70
lanes (below and above both width tiers of ``physics.propagate.for_lanes``).  Independent check: the same samples
flown at another width; with XLA's fused multiply-adds (``GEOJAX_FMA=1``) the same batches differed in the
predicted mean e vector from the second cycle; with XLA's own ``tan``/``atan``, its reductions and batched dots in
the interior points, the MPCs' plans differed from the first cycle.
"""

import platform
import subprocess
import sys

import jax
import numpy as np
import pytest

from geojax import arithmetic, parallel


def test_the_flag_is_appended_on_x86_64_only_and_a_users_own_wins():
    assert arithmetic.with_separate_roundings("", "x86_64") == "--xla_cpu_max_isa=AVX"
    assert arithmetic.with_separate_roundings("--a  --b=1", "AMD64") == "--a --b=1 --xla_cpu_max_isa=AVX"
    assert arithmetic.with_separate_roundings("--xla_cpu_max_isa=AVX512", "x86_64") == "--xla_cpu_max_isa=AVX512"
    assert arithmetic.with_separate_roundings("--a", "aarch64") == "--a"
    both = parallel.with_host_device_count(arithmetic.with_separate_roundings("", "x86_64"), 3)
    assert both == "--xla_cpu_max_isa=AVX --xla_force_host_platform_device_count=3"


@pytest.mark.skipif(platform.machine().lower() not in ("x86_64", "amd64"), reason="the flag exists on x86-64 only")
def test_import_geojax_asks_for_separate_roundings_unless_told_not_to():
    import os

    assert arithmetic.SEPARATE_ROUNDINGS in os.environ["XLA_FLAGS"].split()  # conftest imported geojax first
    code = "import os, geojax; print(os.environ.get('XLA_FLAGS', ''))"
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    fused = subprocess.run([sys.executable, "-c", code], env={**env, "GEOJAX_FMA": "1"}, capture_output=True,
                           text=True, check=True)
    assert arithmetic.SEPARATE_ROUNDINGS not in fused.stdout.split()  # (geojax.small_loops' flag is another's)
    started = "import os, jax; jax.numpy.zeros(1); import geojax; print(os.environ.get('XLA_FLAGS', ''))"
    late = subprocess.run([sys.executable, "-c", started], env=env, capture_output=True, text=True, check=True)
    assert late.stdout.strip() == "" and "JAX started before geojax" in late.stderr


@pytest.mark.parametrize("name, overrides", [
    ("li2022-qffc", {"errors.h_rv": 1.0, "errors.h_att": 1.0}),  # the Gaussian fix
    pytest.param("li2022-qffc-ranging", {}, marks=pytest.mark.slow),  # the navigation filter: 58 records apart with FMA
    # the interior points: the MPC's solve lane by lane (per_lane), the momentum MPC's sums in a fixed order
    pytest.param("li2022-mpc", {"errors.h_rv": 1.0, "errors.h_att": 1.0}, marks=pytest.mark.slow),
    pytest.param("li2022-momentum-mpc", {}, marks=pytest.mark.slow),
])
def test_a_sample_flies_the_same_at_2_and_70_lanes(name, overrides):
    from geojax import scenario, simulate_batch

    sc = scenario.load(name, {"duration.days": 3, **overrides})
    narrow, wide = (simulate_batch([sc] * n, seeds=np.arange(n) % 2) for n in (2, 70))
    assert np.all(np.asarray(narrow.metrics["dv_per_year_mps"]) > 0)
    for (path, a), b in zip(jax.tree_util.tree_leaves_with_path(narrow.records),
                            jax.tree_util.tree_leaves(wide.records)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b)[:2], err_msg=jax.tree_util.keystr(path))
    for name, value in narrow.metrics.items():
        np.testing.assert_array_equal(np.asarray(value), np.asarray(wide.metrics[name])[:2], err_msg=name)
