"""Scenario loading and validation: every bad input gives one ValueError naming the field."""

import math

import numpy as np
import pytest

from geojax.physics import constants as c
from geojax import scenario
from geojax.physics.elements import mee_to_cartesian
from geojax.physics.frames import eci_to_ecef, earth_rotation_angle_rad


def test_shipped_scenarios_load():
    assert {"li2022", "katz2025"} <= set(scenario.available())
    li = scenario.load("li2022")
    np.testing.assert_array_equal(li.initial_mee, [42167e3, 0.0, 1e-4, 0.0, 5e-5, 0.289893])
    assert li.force_model.c22_on == 0.0 and li.force_model.srp_on == 1.0
    assert scenario.load("katz2025").force_model.c22_on == 1.0


def test_li2022_initial_longitude_is_96_deg_east():
    # Li 2022, eqs. (43)-(44): the initial true longitude L = 0.289893 rad sits at the
    # 96 deg E target in the frame of date (0.26 deg off in EME2000).
    li = scenario.load("li2022")
    r, _ = mee_to_cartesian(li.initial_mee, c.MU_EARTH_M3_S2)
    angle = earth_rotation_angle_rad(li.epoch_tt_s, li.epoch_tt_s, li.tt_minus_ut1_s)
    r_ecef = np.asarray(eci_to_ecef(r, angle))
    assert math.degrees(math.atan2(r_ecef[1], r_ecef[0])) == pytest.approx(96.0, abs=0.02)


def test_katz2025_starts_2_km_off_station_on_each_ecef_axis():
    k = scenario.load("katz2025")
    r, v = mee_to_cartesian(k.initial_mee, c.MU_EARTH_M3_S2)
    angle = earth_rotation_angle_rad(k.epoch_tt_s, k.epoch_tt_s, k.tt_minus_ut1_s)
    station = 42164.16e3 * np.array([math.cos(math.radians(10)), math.sin(math.radians(10)), 0.0])
    np.testing.assert_allclose(np.asarray(eci_to_ecef(r, angle)) - station, [2e3, 2e3, 2e3], atol=1e-6)
    assert float(np.linalg.norm(v)) == pytest.approx(c.OMEGA_EARTH_RAD_S * 42164.16e3, rel=1e-12)


def test_overrides_and_path(tmp_path):
    li = scenario.load("li2022", {"duration.days": 30, "integration.step_s": 1800})
    assert li.days == 30.0 and li.step_s == 1800.0
    path = tmp_path / "mine.toml"
    path.write_text(scenario.to_toml(li.config))
    again = scenario.load(path)
    assert again.config == li.config


@pytest.mark.parametrize(
    "overrides, message",
    [
        ({"spacecraft.masss": 1.0}, "spacecraft.masss: unknown key; allowed: mass_kg, dry_mass_kg, srp_area_m2, reflectivity"),
        ({"spacecraft.mass_kg": -5.0}, "spacecraft.mass_kg: must be > 0 and < 1e+06, got -5.0"),
        ({"spacecraft.mass_kg": "heavy"}, "spacecraft.mass_kg: must be a number, got str 'heavy'"),
        ({"thrusters.thrust_n": -0.5}, "thrusters.thrust_n: must be > 0 and < 100000, got -0.5"),
        ({"thrusters.thrust_n": True}, "thrusters.thrust_n: must be a number, got True"),
        ({"integration.step_s": 0.0}, "integration.step_s: must be > 0"),
        ({"integration.step_s": -10.0}, "integration.step_s: must be > 0"),
        ({"integration.dynamics": "rk45"}, "integration.dynamics: must be one of 'mee', 'cartesian', got 'rk45'"),
        ({"orbit.f": 0.8, "orbit.g": 0.8}, "orbit.f, orbit.g: eccentricity sqrt(f^2 + g^2) must be < 1"),
        ({"orbit.a_km": 42164.0}, "orbit.a_km: not used when orbit.elements = 'mee'"),
        ({"forces.sun": 1}, "forces.sun: must be true or false, got int 1"),
        ({"forces.gravity_degree": 21}, "forces.gravity_degree: must be >= 2 and < 21, got 21"),
        ({"forces.gravity_degree": 4, "forces.gravity_order": 5},
         "forces.gravity_order: must be <= forces.gravity_degree = 4, got 5"),
        ({"forces.gravity_order": 3}, "forces.gravity_order: needs forces.gravity_degree"),
        ({"forces.moon_shadow": "yes"}, "forces.moon_shadow: must be true or false, got str 'yes'"),
        ({"forces.ephemeris": "de430"}, "forces.ephemeris: must be one of 'meeus', 'de421', got 'de430'"),
        ({"epoch.utc": "yesterday"}, "epoch.utc: 'yesterday' is not an ISO 8601 date-time"),
        ({"bogus.x": 1}, "bogus.x: not a scenario key; write it as TABLE.KEY"),
        ({"days": 5.0}, "days: not a scenario key"),
    ],
)
def test_bad_input_names_the_field(overrides, message):
    with pytest.raises(ValueError) as err:
        scenario.load("li2022", overrides)
    assert message in str(err.value)
    assert "\n" not in str(err.value)


def test_kepler_eccentricity_of_one_is_refused():
    config = scenario.load("li2022").config
    config["orbit"] = {"elements": "kepler", "a_km": 42164.0, "e": 1.0, "i_deg": 0.1, "raan_deg": 0.0,
                       "argp_deg": 0.0, "true_anomaly_deg": 0.0}
    with pytest.raises(ValueError, match=r"orbit.e: must be >= 0 and < 1, got 1.0"):
        scenario.from_dict(config)


def test_unknown_scenario_lists_the_names():
    with pytest.raises(ValueError, match="scenario .li2021.: unknown; named scenarios: collocation-2, collocation-4, gazzino2016, geo, katz2025, katz2025-constant, katz2025-continuous, katz2025-discrete, li2022"):
        scenario.load("li2021")


def _unread_cases():
    """(scenario, controller kind, key, a value other than its default) for every key a registered controller
    declares it does not read (``control.base.Spec.unread``)."""
    from geojax.control import REGISTRY

    shipped = {"lyapunov": "katz2025-continuous", "zone_nssk": "ye2022-ex1", "mpc_momentum": "li2022-momentum-mpc"}
    for kind, module in REGISTRY.items():
        for key in module.SPEC.unread:
            table, name = key.split(".")
            field = scenario.SCHEMA[table][name]
            default = field.default
            if field.choices:  # a switch of words: another of its choices
                yield shipped[kind], kind, key, next(c for c in field.choices if c != default)
                continue
            value = 1.0 if default is None else (not default) if isinstance(default, bool) else default + 0.5
            if field.upper is not None and not isinstance(default, bool) and value >= field.upper:
                value = default / 2  # within the key's own bounds, so the refusal is the controller's
            yield shipped[kind], kind, key, value


@pytest.mark.parametrize("name, kind, key, value", list(_unread_cases()))
def test_a_key_the_controller_does_not_read_is_refused(name, kind, key, value):
    """Every key is honoured or refused.  A key a controller's rollout never reads, set to
    anything but its default, is refused in one line naming it and the controller."""
    with pytest.raises(ValueError) as err:
        scenario.load(name, {key: value})
    assert str(err.value).startswith(f"{key}: the {kind} controller does not read it")
    assert "\n" not in str(err.value)


def test_every_controller_declares_what_it_flies_and_the_count_must_match():
    """``thrusters.count`` is checked against what the controller flies: each
    registered controller that flies thrusters says how many (the arms' planners 2, a gimbal or a manipulator
    1), a different count is refused, and an unset count takes the controller's."""
    from geojax.control import REGISTRY

    flown = {kind: (module.SPEC.thrusters or (None,))[0] for kind, module in REGISTRY.items()}
    assert flown == {"none": None, "qffc": 2, "fompc": 2, "mpc": 2, "mpc_momentum": 2, "lyapunov": 1, "zone_nssk": 1}
    for name, count in [("li2022-qffc", 1), ("li2022-fompc", 3), ("katz2025-continuous", 3), ("ye2022-ex1", 2)]:
        with pytest.raises(ValueError, match=r"^thrusters\.count: the \w+ controller flies \d thrusters? \(.*\), "
                                             rf"got {count}; leave it out or set \d"
                                             r"( or [24] \((two per arm|a spare).*\))?$"):
            scenario.load(name, {"thrusters.count": count})
    # the arms' planners also fly two thrusters per arm (``control.burns.allocated``)
    assert scenario.load("li2022-fompc", {"thrusters.count": 4}).config["thrusters"]["count"] == 4
    assert scenario.load("katz2025-continuous", {"thrusters.count": 1}).config["thrusters"]["count"] == 1
    assert scenario.load("katz2025-continuous", {"thrusters.count": 2}).config["thrusters"]["count"] == 2  # a spare
    # The arms' limits are the fuel bound's where the layout is the arms, whatever flies the rollout.
    scenario.load("katz2025-continuous", {"thrusters.layout": "arms", "thrusters.beta_max_deg": 50.0})
