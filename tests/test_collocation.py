"""Several satellites in one slot: the closest approach between steps, the cluster's separations against the
closed forms of linearised GEO relative motion, its scenarios' checks and its file."""

import math

import h5py
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import cli, scenario
from geojax.collocation import run
from geojax.physics import constants as c
from geojax.physics.relative import closest_in_step, linear_relative_rtn
from geojax.scenario_physics import synchronous_radius_m

DAYS = 2  # one compiled cluster loop serves every run below


def test_closest_approach_of_a_straight_pass_is_the_closed_form_between_the_step_ends():
    # Independent check: a relative motion in a straight line (a cubic exactly) passes its closest point
    # |p0 x v| / |v| at t = -p0.v / |v|^2; the step ends are both far from it.
    p0, v = jnp.array([-450.0, 30.0, 5.0]), jnp.array([1.0, 0.0, 0.0])
    step_s = 900.0
    distance, at_s, below_s = closest_in_step(p0, v, p0 + step_s * v, v, step_s, 100.0)
    expected = float(jnp.linalg.norm(jnp.cross(p0, v)))
    assert float(distance) == pytest.approx(expected, rel=1e-9)
    assert float(at_s) == pytest.approx(450.0, abs=1e-6)
    assert min(float(jnp.linalg.norm(p0)), float(jnp.linalg.norm(p0 + step_s * v))) > 10 * expected
    # closer than 100 m for the 2 x sqrt(100^2 - 30.4^2) = 190.5 s of the pass; counted in 16 samples of 56 s
    assert abs(float(below_s) - 2 * math.sqrt(100**2 - expected**2)) <= step_s / 16


def test_closest_approach_of_a_node_crossing_against_the_linearised_relative_motion():
    # Independent check: the linearised cross-track motion 2 a dh sin(l) of an inclination-only separation,
    # its exact derivative at the step ends, crosses zero between them; the cubic finds the crossing to
    # metres, where the step ends alone see a x di x sin(omega h / 2).
    a, dh, omega, step_s = 42164.7e3, 2e-4, c.OMEGA_EARTH_RAD_S, 900.0
    t0 = -step_s / 2  # the node at mid-step
    rel = lambda t: linear_relative_rtn(a, 0.0, 0.0, 0.0, dh, 0.0, omega * t)  # noqa: E731
    rate = lambda t: jnp.array([0.0, 0.0, 2 * a * dh * omega * math.cos(omega * t)])  # noqa: E731
    distance, at_s, _ = closest_in_step(rel(t0), rate(t0), rel(t0 + step_s), rate(t0 + step_s), step_s, 0.0)
    sampled = 2 * a * dh * math.sin(omega * step_s / 2)
    assert sampled > 500.0
    assert float(distance) < 1.0
    assert float(at_s) == pytest.approx(step_s / 2, abs=1.0)


def _cluster(tmp_path, satellites: str, extra: str = "") -> str:
    text = scenario.read_text("collocation-2")
    text = text[:text.index("[[satellites]]")] + satellites + extra + "\n[collocation]\nalert_km = 2.0\n"
    path = tmp_path / "cluster.toml"
    path.write_text(text + f"\n[duration]\ndays = {DAYS}\n")
    return str(path)


def test_parallel_e_i_separation_keeps_a_de_apart_uncontrolled(tmp_path):
    # Independent check: the linearised relative motion of parallel e/i separation (no longitude offset) has
    # its least distance a |de| at the nodes, where the radial separation is largest (within 2 %).
    sc = scenario.load("collocation-2", {"duration.days": DAYS})
    r = run.simulate_cluster(sc, seed=0, uncontrolled=True)
    de = abs(sc.satellites[0].config["station"]["ex"] - sc.satellites[1].config["station"]["ex"])
    closed_form_km = synchronous_radius_m(c.J2) * de / 1e3
    assert r.metrics["min_separation_km"] == pytest.approx(closed_form_km, rel=0.02)
    m = r.metric_table()
    assert m["min_separation_km_A_B"] == m["min_separation_km"]
    assert m["below_alert_h"] == 0.0
    # no navigation error set: the operator's view is the truth
    assert m["max_separation_error_km"] < 1e-6
    assert r.cycles()["min_separation_km"].shape == (DAYS,)


def test_an_inclination_only_separation_finds_the_node_crossing_between_steps(tmp_path):
    # Independent check: the linearised relative motion of an inclination-only separation is cross-track,
    # 2 a |di_vec| sin(L - phi): zero at L = phi.  The relative node is put between two integration steps;
    # sampling at the steps alone would report a x di x sin(omega x offset), over 250 m here.
    base = scenario.load("collocation-2", {"duration.days": DAYS})
    step_s = c.SIDEREAL_DAY_S / round(c.SIDEREAL_DAY_S / base.step_s)
    l0 = float(base.satellites[0].initial_mee[5])
    phi = l0 + c.OMEGA_EARTH_RAD_S * 10.5 * step_s  # the node half a step after step 10
    dh, dk = 1e-4 * math.cos(phi), 1e-4 * math.sin(phi)
    path = _cluster(tmp_path, f'[[satellites]]\nname = "A"\n"station.ix" = {dh!r}\n"station.iy" = {dk!r}\n\n'
                              f'[[satellites]]\nname = "B"\n"station.ix" = {-dh!r}\n"station.iy" = {-dk!r}\n')
    r = run.simulate_cluster(scenario.load(path), seed=0, uncontrolled=True)
    sampled_km = 2 * synchronous_radius_m(c.J2) * 2e-4 * math.sin(c.OMEGA_EARTH_RAD_S * step_s / 2) / 1e3
    assert sampled_km > 0.25
    assert r.metrics["min_separation_km"] < 0.02 * sampled_km
    assert r.metric_table()["below_alert_h"] > 0.0


@pytest.mark.parametrize("satellites, message", [
    ('[[satellites]]\nname = "A"\n\n[[satellites]]\nname = "A"\n', "satellites[1].name: 'A' is given twice"),
    ('[[satellites]]\nname = "A"\n"epoch.utc" = "2027-02-01T00:00:00"\n\n[[satellites]]\nname = "B"\n',
     "satellites[0].epoch.utc: shared by every satellite"),
    ('[[satellites]]\nname = "A"\n"integration.step_s" = 600.0\n\n[[satellites]]\nname = "B"\n',
     "satellites[0].integration.step_s: shared"),
    ('[[satellites]]\nname = "A"\n"station.exx" = 1e-4\n\n[[satellites]]\nname = "B"\n',
     "satellites[0] (A): station.exx: unknown key"),
    ('[[satellites]]\nname = "A"\n', "satellites: a cluster needs at least two"),
])
def test_bad_clusters_exit_2_with_one_line_and_write_nothing(tmp_path, capsys, satellites, message):
    path = _cluster(tmp_path, satellites)
    out = tmp_path / "run.h5"
    assert cli.main(["simulate", path, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not out.exists()


def test_a_satellite_draws_by_its_name_not_its_place():
    # Adding a satellite changes no other's draws: its key is the seed's folded with its name.
    two, three = run.satellite_keys(7, ("A", "B")), run.satellite_keys(7, ("C", "A", "B"))
    assert not np.array_equal(jax.random.key_data(two[0]), jax.random.key_data(two[1]))
    assert np.array_equal(jax.random.key_data(two), jax.random.key_data(three[1:]))


def test_the_cluster_file_holds_the_separations_and_every_satellite(tmp_path, capsys):
    out = tmp_path / "c.h5"
    assert cli.main(["propagate", "collocation-2", "--days", str(DAYS), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "min_separation_km" in printed and "between A and B" in printed
    with h5py.File(out) as f:
        assert f.attrs["kind"] == "collocation" and f.attrs["satellites"] == "A,B"
        assert f["cycles/min_separation_km"].shape == (DAYS,)
        assert f["satellite_metrics/dv_per_year_mps"].shape == (2,)
        assert f["satellite_cycles/ex"].shape == (2, DAYS)
        assert float(f["metrics/min_separation_km"][()]) == pytest.approx(
            float(np.min(f["cycles/min_separation_km"][()])))


@pytest.mark.slow
def test_a_sweep_of_clusters_reports_the_separation_percentiles(tmp_path, capsys):
    # Every sample a whole cluster with its own draws: Li's nominal orbit-determination errors move each
    # repetition's separation; the summary gives the percentiles and the fraction below the alert.
    spec = tmp_path / "mc.toml"
    spec.write_text('name = "mc"\nscenario = "collocation-2"\nrepetitions = 3\n[set]\n"duration.days" = 2\n'
                    '"errors.h_rv" = 1.0\n"collocation.alert_km" = 8.43\n[grid]\n'
                    '"satellites.B.station.ex" = [-1.0e-4, -2.0e-4]\n')
    out = tmp_path / "mc.h5"
    assert cli.main(["sweep", str(spec), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "min separation" in printed and "percentiles 5/50/95" in printed
    with h5py.File(out) as f:
        sep = f["metrics/min_separation_km"][()][0]  # [grid point, repetition]
        assert sep.shape == (2, 3)
        assert len(set(np.round(sep[0], 9))) == 3  # every repetition its own draws
        # the linearised closed form, a |de|, per grid point (within 2 %)
        a_km = synchronous_radius_m(c.J2) / 1e3
        assert np.allclose(sep[0], a_km * 2e-4, rtol=0.02) and np.allclose(sep[1], a_km * 3e-4, rtol=0.02)
        assert f["metrics/dv_per_year_mps_A"][()].shape == (1, 2, 3)


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["qffc", "fompc", "mpc"])
def test_every_planner_holds_the_cluster_s_separation(kind):
    # Each satellite of collocation-2 keeps its own targets under each planner, so that the pair's relative e
    # and i vectors (what keeps them apart, the linearised relative motion) stay within a fifth of the
    # separation of the targets' over the last cycles of 20 days, and both keep the box.  The MPC holds windows
    # around the targets (controller.e_max, di_max: 2e-4 and 3.3e-4 by default, wider than this cluster's
    # separation) and parks at their edge, both satellites alike: set within the separation (half here).
    windows = {"controller.e_max": 1e-4, "controller.di_max": 1e-4} if kind == "mpc" else {}
    sc = scenario.load("collocation-2", {"duration.days": 20, "controller.kind": kind, **windows})
    r = run.simulate_cluster(sc, seed=0)
    assert np.all(r.satellites.status == 0)
    means = r.satellites.records.cycles.means
    last = np.array([[np.mean(np.asarray(getattr(means, key))[k, -5:]) for key in ("ex", "ey", "ix", "iy")]
                     for k in range(2)])
    target = np.array([[m.config["station"][key] for key in ("ex", "ey", "ix", "iy")] for m in sc.satellites])
    relative, wanted = last[0] - last[1], target[0] - target[1]
    assert np.linalg.norm(relative[:2] - wanted[:2]) < 0.2 * np.linalg.norm(wanted[:2]), (kind, relative, wanted)
    assert np.linalg.norm(relative[2:] - wanted[2:]) < 0.2 * np.linalg.norm(wanted[2:]), (kind, relative, wanted)
    if kind != "mpc":  # a planner aiming at the targets themselves
        assert np.all(np.linalg.norm(last - target, axis=1) < 0.2 * 2e-4 * np.sqrt(2)), (kind, last, target)
