"""The controller protocol from a user's side, status codes computed in the rollout, sweeps over any leaf."""

import os
import sys

import h5py
import jax.numpy as jnp
import numpy as np
import pytest

from geojax import scenario, sweep, tune
from geojax.control import Controller, Spec
from geojax.control.base import no_plan, stateless_init
from geojax.physics.dynamics import Thrust
from geojax.physics.elements import wrap_angle
from geojax.physics.frames import rotate_z
from geojax.loop.metrics import STATUS_LEFT_LAT_BOX, STATUS_LEFT_LON_BOX, STATUS_OK
from geojax.runner.rollout import simulate
from geojax.params import LOG, Field


def proportional_thrust(params, plan, t, state, environment):
    """East of the station: thrust along +S (raises a, so the satellite drifts west) and the reverse;
    out of plane: thrust against the velocity's ECEF z, damping the daily north-south swing."""
    c = params.controller
    r_ecef = rotate_z(environment.r_eci_m, environment.env.earth_angle_rad[0])
    dlon = wrap_angle(jnp.arctan2(r_ecef[1], r_ecef[0]) - params.station["lon_rad"])
    accel = jnp.stack([0.0, c["k_lon"] * dlon, -c["k_inc"] * environment.v_eci_mps[2]])
    u_max = params.thrusters["thrust_n"] / state.mass_kg
    norm = jnp.maximum(jnp.linalg.norm(accel), 1e-30)
    magnitude = jnp.minimum(norm, u_max)
    return Thrust(accel / norm, magnitude * state.mass_kg, params.thrusters["isp_s"], jnp.asarray(1.0))


MINE = Controller(stateless_init, no_plan, proportional_thrust, Spec(fields={
    "k_lon_mps2_per_rad": Field((int, float), 1e-3, lower=0.0, si="k_lon", transform=LOG),
    "k_inc_per_s": Field((int, float), 1e-5, lower=0.0, si="k_inc", transform=LOG),
}))


@pytest.mark.slow
def test_a_controller_written_in_a_test_runs_through_simulate_sweep_and_tune(tmp_path):
    """Conservation check: with no thrust the same loop gives no Delta-V; with the law, the Delta-V equals
    the mass spent through the rocket equation (m0 (1 - exp(-dv / (Isp g0)))), and a stiffer inclination
    gain spends more."""
    from geojax.physics.constants import G0_MPS2

    sc = scenario.load("li2022", {"duration.days": 3, "controller.k_inc_per_s": 1e-5}, controller=MINE)
    result = simulate(sc, controller=MINE)
    dv = float(result.metrics["dv_per_year_mps"]) * 3 * 86164.0905 / (365.25 * 86400)
    m0, isp = float(result.params.initial.mass_kg), float(result.params.thrusters["isp_s"])
    assert float(result.metrics["mass_used_kg"]) == pytest.approx(m0 * (1 - np.exp(-dv / (isp * G0_MPS2))), rel=1e-6)
    assert dv > 0

    spec_path = tmp_path / "s.toml"
    spec_path.write_text('scenario = "li2022"\ncontrollers = ["mine"]\n[set]\n"duration.days" = 2.0\n'
                         '[grid]\n"controller.k_inc_per_s" = [1e-6, 1e-4]\n')
    spec = sweep.load(spec_path, controllers={"mine": MINE})
    with h5py.File(sweep.run_sweep(spec, tmp_path / "s.h5", progress=False)) as f:
        dv = f["metrics/dv_per_year_mps"][0, :, 0]
    assert dv[1] > dv[0] > 0

    raw = {"scenario": "li2022", "parameters": ["controller.k_lon_mps2_per_rad", "controller.k_inc_per_s"],
           "starts": 2, "iterations": 2, "days": 2.0, "method": "adam"}
    result = tune.tune(tune.from_dict(raw, controller=MINE), verbose=False)
    assert result.history["theta"].shape[-1] == 2


def status_sweep(tmp_path, grid: str, name: str, controller: str = "qffc", days: float = 3.0):
    path = tmp_path / f"{name}.toml"
    path.write_text(f'scenario = "li2022-qffc"\ncontrollers = ["{controller}"]\nrepetitions = 2\nseed = 1\n'
                    f'[set]\n"duration.days" = {days}\n[grid]\n{grid}\n')
    with h5py.File(sweep.run_sweep(sweep.load(path), tmp_path / f"{name}.h5", progress=False)) as f:
        return {k: f[f"metrics/{k}"][()] for k in f["metrics"]}, f["status/code"][()]


@pytest.mark.slow
def test_box_exits_get_their_own_status_and_leave_neighbours_unchanged(tmp_path):
    """A station 0.2 deg east of where the satellite is held leaves the longitude box at once; an uncontrolled
    start inclined 0.069 deg (MEE k = 6e-4; the latitude swings by i every orbit) leaves the latitude box
    within two days while the longitude drifts < 0.03 deg; the neighbouring grid point's metrics equal a sweep
    of that point alone (each sample's key is (seed, index)), to rounding: stations that differ give each sample
    its own predictor reference inside the batch (its segments re-start at its own station), the point alone
    the shared one."""
    metrics, status = status_sweep(tmp_path, '"station.lon_deg" = [96.0, 96.2]', "lon")
    assert np.all(status[0, 0] == STATUS_OK) and np.all(status[0, 1] == STATUS_LEFT_LON_BOX)
    alone, alone_status = status_sweep(tmp_path, '"station.lon_deg" = [96.0]', "alone")
    for k, v in alone.items():
        np.testing.assert_allclose(metrics[k][:, :1], v, rtol=1e-9, atol=1e-15, err_msg=k)
    _, status = status_sweep(tmp_path, '"orbit.k" = [5e-5, 6e-4]', "lat", controller="none", days=2.0)
    assert np.all(status[0, 0] == STATUS_OK) and np.all(status[0, 1] == STATUS_LEFT_LAT_BOX)


@pytest.mark.slow
def test_sweeps_over_srp_area_and_an_initial_state_dispersion(tmp_path):
    """Second method: a sweep over the SRP area runs each sample's own predictor reference inside the batch;
    at the scenario's own area it must give the single run's Delta-V (shared reference), and without SRP
    another.  A dispersed initial position gives each repetition its own orbit and Delta-V, no other error."""
    path = tmp_path / "srp.toml"
    # 3 days, 2 points x 2 repetitions, a reference per lane: the program of the station sweep above (compiled once)
    path.write_text('scenario = "li2022-qffc"\nrepetitions = 2\nseed = 1\n[set]\n"duration.days" = 3.0\n'
                    '[grid]\n"spacecraft.srp_area_m2" = [200.0, 0.0]\n')
    spec = sweep.load(path)
    with h5py.File(sweep.run_sweep(spec, tmp_path / "srp.h5", progress=False)) as f:
        dv = f["metrics/dv_per_year_mps"][0, :, 0]
        assert np.all(f["status/code"][()] == STATUS_OK)
    single = simulate(scenario.load("li2022-qffc", {"duration.days": 3.0}))
    assert dv[0] == pytest.approx(float(single.metrics["dv_per_year_mps"]), rel=1e-9)
    assert abs(dv[1] - dv[0]) > 1e-3
    path = tmp_path / "disp.toml"
    path.write_text('scenario = "li2022-qffc"\nrepetitions = 3\n[set]\n"duration.days" = 2.0\n'
                    '[grid]\n"thrusters.thrust_n" = [0.5]\n[dispersion]\noffset_ecef_1sigma_km = [1.0, 1.0, 1.0]\n')
    with h5py.File(sweep.run_sweep(sweep.load(path), tmp_path / "disp.h5", progress=False)) as f:
        dv = f["metrics/dv_per_year_mps"][0, 0]
    assert len(set(np.round(dv, 9))) == 3


def test_shape_setting_keys_cannot_be_swept(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('scenario = "li2022-qffc"\n[grid]\n"integration.step_s" = [900.0, 1800.0]\n')
    with pytest.raises(ValueError, match="integration.step_s: sets the shape"):
        sweep.load(path)
    path.write_text('scenario = "li2022-fompc"\ncontrollers = ["fompc"]\n[grid]\n"controller.horizon" = [2.5]\n')
    with pytest.raises(ValueError, match="controller.horizon: must be an integer"):
        sweep.load(path)


def test_the_thrusters_stop_when_the_propellant_is_gone():
    """The mass never goes below the dry mass, even at Isp 1e-3 s.  Conservation: with 0.5 kg of propellant the
    QFFC spends it, the thrusters stop at the dry mass (overshoot below one step's flow), the sample gets
    status 5, and the Delta-V delivered is the rocket equation's for the mass used."""
    from geojax.physics.constants import G0_MPS2
    from geojax.loop.metrics import STATUS_NO_PROPELLANT

    days = 20.0
    sc = scenario.load("li2022-qffc", {"duration.days": days, "spacecraft.dry_mass_kg": 4999.5})
    result = simulate(sc)
    used = float(result.metrics["mass_used_kg"])
    thrusters = sc.config["thrusters"]
    one_step_kg = thrusters["count"] * thrusters["thrust_n"] * sc.step_s / (thrusters["isp_s"] * G0_MPS2)
    assert int(result.status) == STATUS_NO_PROPELLANT
    assert 0.5 <= used < 0.5 + one_step_kg
    dv = np.sum(result.records.cycles.dv_mps)
    assert dv == pytest.approx(thrusters["isp_s"] * G0_MPS2 * np.log(5000.0 / (5000.0 - used)), rel=1e-6)
    assert np.all(result.records.cycles.dv_mps[-3:] == 0.0)  # nothing flies once the propellant is gone


@pytest.mark.parametrize("overrides, message", [
    ({"thrusters.isp_s": 1e-3}, "thrusters.isp_s: 2 thrusters of 0.5 N at Isp 0.001 s burn 9.177e+04 kg in one"),
    ({"spacecraft.dry_mass_kg": 5000.0}, "spacecraft.dry_mass_kg: must be less than spacecraft.mass_kg = 5000"),
])
def test_a_propellant_that_cannot_last_one_step_is_refused_at_load(overrides, message):
    with pytest.raises(ValueError, match=message.replace("+", r"\+").replace(".", r"\.")):
        scenario.load("li2022-qffc", overrides)




@pytest.mark.slow
def test_a_controller_of_ones_own_is_named_by_import_path(tmp_path, capsys):
    """``controller.kind = "module:NAME"`` in a scenario file and a sweep's ``controllers``, through the command
    line, with the width the controller declares (16 lanes); bad paths are one line, exit 2."""
    import h5py

    from geojax import cli

    scenario_path = tmp_path / "damped.toml"
    scenario_path.write_text(scenario.to_toml({**scenario.load("li2022").config,
                                               "controller": {"kind": "own_laws:DAMPER", "k_inc_per_s": 2e-5}}))
    assert cli.main(["simulate", str(scenario_path), "--days", "2", "-q", "--out", str(tmp_path / "one.h5")]) == 0
    with h5py.File(tmp_path / "one.h5") as f:
        assert f["metrics/dv_per_year_mps"][()] > 0  # the law fired
        assert "steps" in f and "reference" not in f  # a feedback law (no reference) keeps its steps by default
    from geojax.bound.directions import geometry_of

    # The bound's thruster geometry is the controller's fact, not a name the bound knows.
    assert geometry_of(scenario.load(scenario_path).config).name == "gimbal"
    assert geometry_of(scenario.load("li2022-qffc").config).name == "arms"
    assert geometry_of(scenario.load("katz2025-continuous").config).name == "gimbal"
    assert geometry_of(scenario.load("katz2025-discrete").config).name == "axes"  # eq. (6): per-axis pairs
    # ... and the bound flies it: the least fuel over 2 days with the gimbal the controller declares; the box
    # holds for 2 days uncontrolled, so the free-end bound is zero (a conservation check: no drift to undo).
    assert cli.main(["bound", str(scenario_path), "--days", "2", "--free-end", "-q", "--out",
                     str(tmp_path / "bound.h5")]) == 0
    with h5py.File(tmp_path / "bound.h5") as f:
        assert f.attrs["geometry"] == "gimbal" and f["metrics/bound_per_year_mps"][()] < 1e-3
        assert f["metrics/gap_percent"][()] == 0.0
    spec = tmp_path / "s.toml"
    spec.write_text(f'scenario = "{scenario_path}"\ncontrollers = ["own_laws:DAMPER"]\n[set]\n"duration.days" = 2.0\n'
                    '[grid]\n"controller.k_inc_per_s" = [1e-6, 1e-4]\n')
    assert cli.main(["sweep", str(spec), "--out", str(tmp_path / "s.h5"), "-q"]) == 0
    with h5py.File(tmp_path / "s.h5") as f:
        dv = f["metrics/dv_per_year_mps"][0, :, 0]
        assert f.attrs["lanes_per_device"] == "own_laws:DAMPER 16"
    assert dv[1] > dv[0] > 0  # a stiffer gain spends more
    capsys.readouterr()
    for kind, message in [("own_laws:NOT_A_CONTROLLER", "is not a geojax Controller (found int)"),
                          ("no_such_module:X", "cannot import 'no_such_module'"),
                          ("qfc", "must be a non-empty list of distinct names")]:
        spec.write_text(f'scenario = "{scenario_path}"\ncontrollers = ["{kind}"]\n'
                        '[grid]\n"controller.k_inc_per_s" = [1e-6]\n')
        assert cli.main(["sweep", str(spec), "--out", str(tmp_path / "bad.h5"), "-q"]) == cli.EXIT_BAD_INPUT
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err


OWN_MODULE = '''
import geojax
from geojax.control.base import coast, no_plan, stateless_init

LAW = geojax.Controller(stateless_init, no_plan, coast)  # no keys of its own
'''


def test_a_controller_without_keys_runs_when_passed_in_python():
    """A controller of one's own with no fields runs (no error naming a controller kind the user never
    typed): a coasting one flies the uncontrolled orbit, no propellant used."""
    ns = {}
    exec(OWN_MODULE, ns)
    sc = scenario.load("li2022", {"duration.days": 1}, controller=ns["LAW"])
    result = simulate(sc, controller=ns["LAW"])
    assert int(result.status) == 0 and float(result.metrics["mass_used_kg"]) == 0.0


@pytest.mark.slow
def test_the_command_imports_ones_own_module_from_the_current_folder(tmp_path):
    """``geojax sweep`` finds ``my_laws:LAW`` without ``PYTHONPATH=.``: the real console script, run in the
    folder of ``my_laws.py`` with the sweep file elsewhere, imports it."""
    import os
    import subprocess
    from pathlib import Path

    import geojax as package

    (tmp_path / "my_laws.py").write_text(OWN_MODULE)
    (tmp_path / "sweeps").mkdir()
    (tmp_path / "sweeps" / "s.toml").write_text('scenario = "li2022"\ncontrollers = ["my_laws:LAW"]\n'
                                                '[set]\n"duration.days" = 1.0\n[grid]\n"errors.h_rv" = [0.0]\n')
    root = str(Path(package.__file__).parents[1])  # this checkout, not the folder of my_laws.py
    env = {**os.environ, "PYTHONPATH": root}
    geojax_command = Path(sys.executable).with_name("geojax")
    run = subprocess.run([str(geojax_command), "sweep", "sweeps/s.toml", "--out", "s.h5", "-q"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "s.h5").is_file()


def test_the_folder_of_the_file_a_command_reads_is_searched_too(tmp_path, monkeypatch):
    """A module beside the scenario or sweep file (not in the current folder) is found as well, after the
    installed packages, and the processes a run starts (Ray's workers) find it through ``PYTHONPATH``."""
    import argparse
    import importlib

    from geojax import cli

    (tmp_path / "study").mkdir()
    (tmp_path / "study" / "beside_laws.py").write_text(OWN_MODULE)
    (tmp_path / "study" / "s.toml").write_text("")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", list(sys.path))
    monkeypatch.setenv("PYTHONPATH", "/elsewhere")
    cli.user_modules_importable(argparse.Namespace(file="study/s.toml"))
    assert sys.path[-2:] == [str(tmp_path), str(tmp_path / "study")]
    assert os.environ["PYTHONPATH"] == os.pathsep.join(["/elsewhere", str(tmp_path), str(tmp_path / "study")])
    assert importlib.import_module("beside_laws").LAW.fields == {}
