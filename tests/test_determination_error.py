"""How the orbit-determination error enters the controller's fix (Li 2022 eqs. (47)-(48); ``navigation.fix``).

Independent check: the fix converted back to Cartesian (``physics.elements.mee_to_cartesian``, the inverse of
the conversion the fix goes through) differs from the true r and v by exactly the closed form
(sigma3_r_m, sigma3_v_mps) / 3 x noise per component.
"""

import jax.numpy as jnp
import numpy as np
import pytest

from geojax.navigation.fix import fix_mee
from geojax.physics.constants import MU_EARTH_M3_S2
from geojax.physics.elements import cartesian_to_mee, mee_to_cartesian
from geojax.physics.propagate import CARTESIAN, MEE

# A GEO state: r = 42164 km on x, v = 3074.7 m/s on y, a little inclined.
R0 = np.array([42164.17e3, 0.0, 0.0])
V0 = np.array([0.0, 3074.66, 5.0])
NOISE = jnp.array([0.7, -1.3, 2.1, -0.4, 1.9, -2.6])


def _fix(dynamics, sigma3_r_m, sigma3_v_mps):
    mee = cartesian_to_mee(jnp.asarray(R0), jnp.asarray(V0), MU_EARTH_M3_S2)
    orbit = dynamics.from_mee(mee, MU_EARTH_M3_S2)
    r, v = mee_to_cartesian(dynamics.to_mee(orbit, MU_EARTH_M3_S2), MU_EARTH_M3_S2)
    errors = {"sigma3_r_m": jnp.asarray(sigma3_r_m), "sigma3_v_mps": jnp.asarray(sigma3_v_mps)}
    return mee, fix_mee(dynamics.to_mee(orbit, MU_EARTH_M3_S2), r, v, NOISE, errors, MU_EARTH_M3_S2)


@pytest.mark.parametrize("dynamics", [MEE, CARTESIAN], ids=["mee", "cartesian"])
@pytest.mark.parametrize("sigma3_r_m, sigma3_v_mps", [(240.0, 0.04), (0.0, 0.04), (240.0, 0.0), (120.0, 0.08)])
def test_fix_error_is_the_stated_sigma_times_the_noise_in_each_part(dynamics, sigma3_r_m, sigma3_v_mps):
    """At Li's H_rv = 800 (3 sigma 240 m and 0.04 m/s per component) the fix is off the truth by 80 m x noise in
    position and 0.01333 m/s x noise in velocity; a part at 0 is removed exactly."""
    _, fix = _fix(dynamics, sigma3_r_m, sigma3_v_mps)
    r, v = (np.asarray(x) for x in mee_to_cartesian(fix, MU_EARTH_M3_S2))
    np.testing.assert_allclose(r - R0, sigma3_r_m / 3 * np.asarray(NOISE[:3]), atol=2e-6)  # MEE round trip: ~1e-8 m
    np.testing.assert_allclose(v - V0, sigma3_v_mps / 3 * np.asarray(NOISE[3:]), atol=1e-9)


def test_no_error_gives_the_true_state():
    mee, fix = _fix(MEE, 0.0, 0.0)
    np.testing.assert_allclose(np.asarray(fix), np.asarray(mee), rtol=1e-13, atol=1e-13)


# Errors stated as an operator states them (3 sigma per component in m, m/s, deg) and as Li's multiples of the
# nominal 0.3 m, 5e-5 m/s, 0.05 deg: the same errors.
# H = 2: its products with the nominal are the doubles of 0.6 m, 1e-4 m/s and 0.1 deg themselves (at H = 3, 3 x
# 0.3 is the double below 0.9: a preset is its product, so the numbers of the paper's H levels keep their bits).
ABSOLUTE = {"errors.sigma3_r_m": 0.6, "errors.sigma3_v_mps": 1e-4, "errors.sigma3_att_deg": 0.1}
MULTIPLES = {"errors.h_rv": 2.0, "errors.h_att": 2.0}


@pytest.mark.slow
def test_absolute_errors_give_the_numbers_of_the_equivalent_multiples_bit_for_bit():
    """Second method: the same 3-day QFFC run with the errors given as 3-sigma values and as multiples H of
    Li 2022's nominal (0.6 m = 2 x 0.3 m, ...), one batch (one compilation), the same seed; and a run without
    errors, which must differ (the errors are really flown)."""
    import geojax
    from geojax import scenario

    runs = [scenario.load("li2022-qffc", {"duration.days": 3.0, **o}) for o in (ABSOLUTE, MULTIPLES, {})]
    result = geojax.simulate_batch(runs, seeds=[7, 7, 7])
    for name, values in result.metrics.items():
        assert values[0] == values[1], name
    np.testing.assert_array_equal(result.records.cycles.means.lon_rad[0], result.records.cycles.means.lon_rad[1])
    assert result.metrics["dv_per_year_mps"][0] != result.metrics["dv_per_year_mps"][2]


@pytest.mark.parametrize("given, sizes", [
    ({"errors.sigma3_r_m": 0.6}, {"sigma3_r_m": 0.6, "sigma3_v_mps": 0.0, "sigma3_att_deg": 0.0}),  # v not given: 0
    ({"errors.h_rv": 2.0}, {"sigma3_r_m": 0.6, "sigma3_v_mps": 1e-4, "sigma3_att_deg": 0.0}),
    ({"errors.h_att": 2.0}, {"sigma3_r_m": 0.0, "sigma3_v_mps": 0.0, "sigma3_att_deg": 0.1}),
    ({"errors.h_rv": 2.0, "errors.sigma3_r_m": 0.6}, {"sigma3_r_m": 0.6, "sigma3_v_mps": 1e-4, "sigma3_att_deg": 0.0}),
])
def test_a_preset_gives_the_sizes_it_stands_for(given, sizes):
    """Closed form: a preset H stands for H x Li's nominal 3 sigma (0.3 m, 5e-5 m/s, 0.05 deg); a size given
    beside its agreeing preset is kept; the leaves the loop reads are these sizes."""
    from geojax import nominal_errors, scenario

    errors = scenario.load("li2022-qffc", given).config["errors"]
    assert nominal_errors.sigma3(errors) == pytest.approx(sizes, rel=1e-15)
    leaves = nominal_errors.leaves(errors)
    assert {k: float(leaves[k]) for k in sizes} == pytest.approx(sizes, rel=1e-15)


@pytest.mark.parametrize("args, key", [(["--h-rv", "3", "--sigma3-r-m", "0.6"], "errors.sigma3_r_m"),
                                       (["--h-att", "1", "--sigma3-att-deg", "0.1"], "errors.sigma3_att_deg")])
def test_contradicting_multiple_and_absolute_error_is_refused(args, key, capsys):
    from geojax import cli

    assert cli.main(["simulate", "li2022-qffc", "--days", "1", *args]) == 2
    err = capsys.readouterr().err
    assert key in err and "contradicts" in err and err.count("\n") == 1
