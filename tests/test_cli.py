"""The command line: propagate, plot, HDF5 contract, exit status 2 on bad input, -q / -v on every command, one
meaning of --days, paper comparisons with their caveat, per-grid-point sweep summaries."""

import h5py
import numpy as np
import pytest

import geojax
from geojax import cli


def test_propagate_writes_the_hdf5_contract(tmp_path, capsys):
    out = tmp_path / "run.h5"
    assert cli.main(["propagate", "li2022", "--days", "3", "--step", "1800", "--out", str(out)]) == 0
    assert "inclination-vector change" in capsys.readouterr().out
    with h5py.File(out) as f:
        for name in ("t_s", "lon_deg", "drift_deg_per_day", "ex", "ey", "ix", "iy", "a_m"):
            assert f[f"cycles/{name}"].shape == (3,)  # round(3 d / sidereal day), as in simulate
            assert f[f"cycles/{name}"].dims[0].label == "cycle"
        for attr in ("geojax_version", "jax_version", "jaxlib_version", "source_revision", "config_toml",
                     "created_utc", "wall_s", "device"):
            assert attr in f.attrs
        assert f["cycles/lon_deg"].attrs["units"] == "deg" and f["cycles/t_s"].attrs["units"] == "s"
        assert 'name = "li2022"' in f.attrs["config_toml"]
        assert "days = 3.0" in f.attrs["config_toml"]
        # One-cycle means around 96 deg E, a near the synchronous radius.
        assert np.all(np.abs(f["cycles/lon_deg"][()] - 96.0) < 0.1)
        assert np.all(np.abs(f["cycles/a_m"][()] - 42166.7e3) < 1e3)
    assert cli.main(["plot", str(out), "--out", str(tmp_path / "fig")]) == 0
    assert (tmp_path / "fig" / "run.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    "argv, message",
    [
        (["propagate", "nowhere"], "scenario 'nowhere': unknown"),
        (["propagate", "li2022", "--step", "0"], "integration.step_s: must be > 0"),
        (["propagate", "li2022", "--days", "-1"], "duration.days: must be > 0"),
        (["plot", "missing.h5"], "file 'missing.h5': no such file"),
        (["simulate", "li2022-fompc", "--horizon", "0"], "controller.horizon: must be >= 1"),
        (["simulate", "li2022", "--days", "2", "--oem", "x.oem", "--oem-step", "10"],
         "--oem-step: must be at least the integration step"),
    ],
)
def test_bad_input_exits_2_with_one_line(argv, message, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_bad_force_keys_exit_2(tmp_path, capsys):
    # The shipped `geo` scenario with a degree beyond the shipped EGM2008 table.
    assert cli.main(["scenarios", "--show", "geo"]) == 0
    text = capsys.readouterr().out.replace("gravity_degree = 8", "gravity_degree = 40")
    (tmp_path / "bad.toml").write_text(text)
    assert cli.main(["propagate", str(tmp_path / "bad.toml")]) == 2
    err = capsys.readouterr().err
    assert "forces.gravity_degree: must be >= 2 and < 21, got 40" in err and err.count("\n") == 1


@pytest.mark.slow
def test_demo_writes_its_figure(tmp_path, capsys):
    assert cli.main(["demo", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "inclination-vector change" in out and "mean longitude drift" in out
    assert (tmp_path / "li2022-uncontrolled.png").is_file()
    assert (tmp_path / "li2022-uncontrolled.h5").is_file()
    assert "burns_per_thruster_per_orbit" in out
    assert (tmp_path / "li2022-qffc.h5").is_file() and (tmp_path / "li2022-qffc.png").is_file()


@pytest.mark.slow
def test_simulate_writes_metrics_and_cycles(tmp_path, capsys):
    out = tmp_path / "sim.h5"
    assert cli.main(["simulate", "li2022-qffc", "--days", "5", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "dv_per_year_mps" in printed and "closed loop ready in" in printed and "5 cycles" in printed
    # A 5-day run beside Li's one-year numbers: said so, with what differs; its per-year figures extrapolated.
    assert "Li 2022 (its own run)" in printed and "duration.days = 5" in printed
    dv_line = next(line for line in printed.splitlines() if line.split()[:1] == ["dv_per_year_mps"])
    assert "m/s/yr" in dv_line and "extrapolated from 4.986 days (5 cycles)" in dv_line
    with h5py.File(out) as f:
        for name in ("dv_per_year_mps", "burns_total", "burns_per_thruster_per_orbit", "max_abs_dlon_deg",
                     "max_abs_dlat_deg", "max_abs_de", "max_abs_di", "mean_beta_deg", "cpu_s_per_orbit"):
            assert np.isfinite(f[f"metrics/{name}"][()])
        for name in ("v1_mps", "v2_mps", "alpha1_deg", "beta1_deg", "alpha2_deg", "beta2_deg", "l1_deg", "dv_ns_mps"):
            assert f[f"cycles/{name}"].shape == (5,)
        # Eq. (1), normal limits: thruster 1 pitch in [0, 70] deg where it fires.
        fired = f["cycles/v1_mps"][()] > 0
        assert np.all((f["cycles/beta1_deg"][()][fired] >= 0) & (f["cycles/beta1_deg"][()][fired] <= 70 + 1e-9))
        assert f["reference/ix"].shape == (6,) and f["target/iy"][()] == 3e-5
        # Second methods for the new figures.  North-south: Li 2022 eq. (45) of the planned burns (no attitude
        # error here, so the directions flown are the planned ones).  Firing time: the delivered Delta-V is the
        # thrust acceleration F/m times the time fired (m within 1e-4 of the start's over 5 days).
        m = {k: f[f"metrics/{k}"][()] for k in f["metrics"]}
        run_s, year_s = 5 * 86164.0905, 365.25 * 86400
        assert m["dv_ns_per_year_mps"] == pytest.approx(np.sum(f["cycles/dv_ns_mps"][()]) * year_s / run_s, rel=1e-4)
        parts = [m[f"dv_{axis}_per_year_mps"] for axis in ("radial", "ew", "ns")]
        assert max(parts) < m["dv_per_year_mps"] < sum(parts)  # components per axis, not a partition
        assert np.hypot(np.hypot(*parts[:2]), parts[2]) <= m["dv_per_year_mps"] * (1 + 1e-12)  # |.| of the sum
        config = geojax.scenario.tomllib.loads(f.attrs["config_toml"])
        accel_mps2 = config["thrusters"]["thrust_n"] / config["spacecraft"]["mass_kg"]
        assert m["duty_fraction"] * run_s * accel_mps2 == pytest.approx(m["dv_per_year_mps"] * run_s / year_s, rel=1e-4)
        assert "duty_x" not in m  # a planner's burns are along RSW: per-ECEF-axis counts would repeat the fraction
    ds = geojax.open_results(out)  # as labelled arrays
    assert ds.dv_per_year_mps.dims == () and ds.dv_per_year_mps.attrs["units"] == "m/s/yr"
    assert ds.cycles__lon_deg.dims == ("cycle",) and ds.cycles__lon_deg.size == 5
    assert ds.reference__ix.dims == ("reference_cycle",) and ds.attrs["scenario"] == "li2022-qffc"
    assert cli.main(["plot", str(out), "--out", str(tmp_path)]) == 0
    assert (tmp_path / "sim-station-keeping.png").stat().st_size > 10_000


def test_version_and_python_dash_m(capsys):
    """``geojax --version`` names the package's ``__version__``, which is pyproject.toml's, and
    ``python -m geojax`` is the same command."""
    import subprocess
    import sys
    from pathlib import Path

    import geojax
    from geojax.scenario import tomllib

    pyproject = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    assert pyproject["project"]["version"] == geojax.__version__

    with pytest.raises(SystemExit) as exit_:
        cli.main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.strip() == f"geojax {geojax.__version__}"
    run = subprocess.run([sys.executable, "-m", "geojax", "--version"], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == f"geojax {geojax.__version__}"


def test_scenarios_align_and_show_a_toml_that_loads_as_the_same_scenario(tmp_path, capsys):
    from geojax import scenario

    assert cli.main(["scenarios"]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if line and not line.startswith("`")]
    starts = {line.index(scenario.load(line.split()[0]).config["description"]) for line in lines}
    assert len(starts) == 1  # every description starts in the same column
    assert cli.main(["scenarios", "--show", "katz2025-discrete"]) == 0
    copy = tmp_path / "mine.toml"
    copy.write_text(capsys.readouterr().out)
    assert scenario.load(copy).config == scenario.load("katz2025-discrete").config


COMMANDS = {"demo": [], "propagate": ["li2022"], "simulate": ["li2022-qffc"], "tune": ["t.toml", "--out", "t.h5"],
            "sweep": ["s.toml", "--out", "s.h5"], "plot": ["x.h5"], "scenarios": []}


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_takes_q_and_v_and_documents_days(command, capsys):
    parser = cli._parser()
    for flag, field in (("-q", "quiet"), ("--quiet", "quiet"), ("-v", "verbose"), ("--verbose", "verbose")):
        assert getattr(parser.parse_args([command, *COMMANDS[command], flag]), field)
    with pytest.raises(SystemExit):
        parser.parse_args([command, *COMMANDS[command], "-q", "-v"])  # one or the other
    capsys.readouterr()
    with pytest.raises(SystemExit):
        parser.parse_args([command, "--help"])
    help_text = capsys.readouterr().out
    if "--days" in help_text:
        assert "sidereal-day cycles" in " ".join(help_text.split())


@pytest.mark.slow
def test_quiet_prints_only_the_files_written_and_days_mean_cycles_everywhere(tmp_path, capsys):
    sim, prop = tmp_path / "sim.h5", tmp_path / "prop.h5"
    assert cli.main(["simulate", "li2022-qffc", "--days", "4", "--out", str(sim), "-q"]) == 0
    assert cli.main(["propagate", "li2022", "--days", "4", "--out", str(prop), "-q"]) == 0
    assert capsys.readouterr().out.splitlines() == [f"wrote {sim}", f"wrote {prop}"]
    with h5py.File(sim) as a, h5py.File(prop) as b:
        assert a["cycles/lon_deg"].shape == b["cycles/lon_deg"].shape == (4,)


def test_sweep_summary_per_grid_point_and_identical_repetitions_warned():
    from types import SimpleNamespace

    spec = SimpleNamespace(controllers=("qffc", "fompc"), grid={"thrusters.beta_max_deg": [60.0, 90.0]}, repetitions=3,
                           fixed={"duration.days": 365.25})
    dv = np.array([[[62.0, 62.0, 62.0], [58.0, 58.0, 58.0]],  # qffc: every repetition the same
                   [[57.0, 58.0, 59.0], [55.0, 55.5, 56.0]]])
    metrics = {"dv_per_year_mps": dv, "max_abs_dlon_deg": np.full_like(dv, 0.01), "max_abs_dlat_deg": np.full_like(dv, 0.006)}
    status = np.zeros(dv.shape, np.int8)
    status[1, 1, 2] = 2
    lines = cli.sweep_summary(spec, {"metrics": metrics, "status": {"code": status}})
    text = "\n".join(lines)
    # the failed sample (56.0) is left out: the held 55.0 and 55.5 give 55.25 ± 0.25 (by hand)
    assert "beta_max_deg 60: ΔV 62.00 ± 0.00 m/s/yr" in text and "beta_max_deg 90: ΔV 55.25 ± 0.25 m/s/yr" in text
    assert "2 held, 1 failed (1 left the longitude box)" in text
    assert "identical for qffc:" in text and "fompc:" not in lines[-1]
    # A short sweep's yearly rate is said to be extrapolated, with the days it flew: 10 sidereal days, by hand.
    short = "\n".join(cli.sweep_summary(SimpleNamespace(**{**vars(spec), "fixed": {"duration.days": 10}}),
                                         {"metrics": metrics, "status": {"code": status}}))
    assert "beta_max_deg 60: ΔV 62.00 ± 0.00 m/s/yr (extrapolated from 9.973 days, 10 cycles), max" in short
    assert short.count("extrapolated") == 4 and "extrapolated" not in text


def test_an_installed_copy_names_the_commit_it_was_built_from(tmp_path):
    """``setup.py``'s build step records ``git rev-parse HEAD`` (the second method: git itself) in the built
    package, and a copy with no checkout around it reports that, not "unknown"."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    if not head:
        pytest.skip("not a git checkout")
    lib = tmp_path / "lib"
    subprocess.run([sys.executable, "setup.py", "-q", "build_py", "--build-lib", str(lib)], cwd=root, check=True,
                   capture_output=True)
    assert (lib / "geojax" / "_revision.txt").read_text().strip().removesuffix("+dirty") == head
    code = "from geojax.store import source_revision; print(source_revision())"
    out = subprocess.run([sys.executable, "-c", code], cwd=lib, capture_output=True, text=True, check=True,
                         env={**os.environ, "PYTHONPATH": str(lib)})
    assert out.stdout.strip().removesuffix("+dirty") == head


def test_a_thruster_count_the_controller_cannot_fly_exits_2(tmp_path, capsys):
    """``thrusters.count = 1`` on the QFFC (two arms) is refused in one line, exit 2."""
    path = tmp_path / "one.toml"
    path.write_text(geojax.scenario.read_text("li2022-qffc").replace("count = 2", "count = 1"))
    assert cli.main(["simulate", str(path), "--days", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("geojax simulate: error: thrusters.count: the qffc controller flies 2 thrusters")
    assert err.count("\n") == 1


class _Ran(Exception):
    """Raised by a stand-in for a run: the scenario it was given is in ``args[0]``."""


@pytest.mark.parametrize("command, scenario, module, name", [
    ("simulate", "li2022-qffc", "geojax.runner.rollout", "simulate"),
    ("propagate", "li2022", "geojax.uncontrolled", "propagate_scenario"),
    ("bound", "li2022-qffc", "geojax.bound", "bound"),
    ("transfer", "ma2023-boom", "geojax.transfer", "run"),
])
def test_set_gives_the_run_its_scenario_keys_as_toml_values(command, scenario, module, name, monkeypatch):
    import importlib

    def ran(sc, *args, **kwargs):
        raise _Ran(sc)

    monkeypatch.setattr(importlib.import_module(module), name, ran)
    table, key, value = ("thrusters", "beta_max_deg", 61.5) if command != "transfer" else ("spacecraft", "mass_kg",
                                                                                            4321.5)
    with pytest.raises(_Ran) as run:
        cli.main([command, scenario, "--set", f"{table}.{key}={value}", "--set", "name=mine",
                  "--set", 'description="a b"'])
    sc = run.value.args[0]
    assert sc.config[table][key] == value and sc.config["name"] == "mine" and sc.config["description"] == "a b"


@pytest.mark.parametrize("argv, message", [
    (["--set", "beta"], "--set 'beta': must be KEY=VALUE"),
    (["--set", "thrusters.beta_max_deg=abc"], "thrusters.beta_max_deg: must be a number, got str 'abc'"),
    (["--set", "duration.days=2", "--days", "3"], "--set duration.days: also given as --days; give one"),
    (["--set", "errors.h_rv=1", "--set", "errors.h_rv=2"], "--set errors.h_rv: given twice"),
    (["--set", "bogus.x=1"], "bogus.x: not a scenario key"),
])
def test_bad_set_exits_2_with_one_line(argv, message, capsys):
    assert cli.main(["simulate", "li2022-qffc", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_set_is_written_into_the_results_file(tmp_path):
    out = tmp_path / "p.h5"
    assert cli.main(["propagate", "li2022", "--days", "2", "--set", "spacecraft.srp_area_m2=0", "--set",
                     "forces.moon=false", "--out", str(out), "-q"]) == 0
    config = geojax.scenario.tomllib.loads(geojax.store.read_attrs(out)["config_toml"])
    assert config["spacecraft"]["srp_area_m2"] == 0 and config["forces"]["moon"] is False


def test_load_scenario_takes_a_name_override():
    sc = geojax.load_scenario("li2022-qffc", {"name": "mine", "thrusters.beta_max_deg": 60.0})
    assert sc.name == "mine" and sc.config["thrusters"]["beta_max_deg"] == 60.0
    with pytest.raises(ValueError, match="name: must be a string"):
        geojax.load_scenario("li2022-qffc", {"name": 3})
