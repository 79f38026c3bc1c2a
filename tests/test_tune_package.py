"""geojax.tune knows no controller: a user's law, named by import path, tuned through the public entry point; the
tuning file's documentation built from its Fields; the short-horizon warning."""

import ast
import dataclasses
import re
import sys
from pathlib import Path

import h5py
import pytest

from geojax import cli, plots, scenario, tune
from geojax.control import REGISTRY
from test_result_files import assert_same_file

# A user's inclination damper, outside the package: tests/own_laws.py (its gain is its only tunable field, with an
# alias and a unit, and the one a tuning moves by default).


@pytest.fixture
def own_scenario(tmp_path):
    """li2022 flown by ``own_laws:DAMPER`` (``tests/own_laws.py``), with a 1 deg box that it keeps."""
    path = tmp_path / "damped.toml"
    config = scenario.load("li2022").config
    path.write_text(scenario.to_toml({**config, "station": {**config["station"], "box_half_width_deg": 1.0},
                                      "controller": {"kind": "own_laws:DAMPER", "k_inc_per_s": 1e-4}}))
    return path


@pytest.mark.slow
def test_a_controller_of_ones_own_is_tuned_through_the_command_line(own_scenario, tmp_path, capsys):
    """The law's own gain, named by its alias in the file and in Python alike, tuned over 2 days by the CLI.
    Physics as the check: the thrust only damps the out-of-plane velocity and grows with the gain, so every
    start keeps the 1 deg box and a smaller gain spends less; the descent must lower the gain and the Delta-V.
    The tuned scenario loads back with the best gain and says what was tuned, where, over how long, to what."""
    file = tmp_path / "t.toml"
    file.write_text(f'scenario = "{own_scenario}"\nparameters = ["k_inc"]\ndays = 2.0\nstarts = 2\niterations = 2\n')
    assert cli.main(["tune", str(file), "--out", str(tmp_path / "t.h5")]) == 0
    printed = capsys.readouterr()
    err = printed.out.splitlines(), printed.err
    printed, err = err
    assert "geojax tune: warning: days = 2: the tuning horizon is under half a year" in err
    with h5py.File(tmp_path / "t.h5") as f:
        assert f.attrs["parameters"] == "controller.k_inc_per_s" and f.attrs["controller"] == "own_laws:DAMPER"
        dv = f["iterations/dv_per_year_mps"][()]  # [iteration, start]
        best_gain, best_dv = f["best/k_inc_per_s"][()], f["metrics/dv_per_year_mps"][()]
    assert best_gain < 1e-4 and best_dv < dv[0, 0]
    tuned = scenario.load(tmp_path / "t-tuned.toml")
    assert tuned.config["controller"]["k_inc_per_s"] == pytest.approx(best_gain, rel=1e-12)
    description = tuned.config["description"]
    assert description.startswith("controller.k_inc_per_s tuned by geojax tune (sqp, 2 starts, 2 iterations) on "
                                  "scenario li2022 over 2 days") and f"{best_dv:.3f} m/s/yr" in description
    # The figure: the name as the file wrote it, the unit as the Field declares it.
    assert cli.main(["plot", str(tmp_path / "t.h5"), "--out", str(tmp_path / "fig"), "-q"]) == 0
    spec = tune.load(file)
    # A Python user's tuning writes the command's file and prints its lines (a result owns its file).
    with pytest.warns(tune.ShortHorizonWarning):
        result = tune.tune(spec, verbose=False)
    assert result.save(tmp_path / "library.h5") == tmp_path / "library.h5"
    assert_same_file(tmp_path / "t.h5", tmp_path / "library.h5")
    assert (tmp_path / "library-tuned.toml").read_text() == (tmp_path / "t-tuned.toml").read_text()
    untimed = lambda lines: [re.sub(r"[0-9.]+ s wall", "", line) for line in lines]  # noqa: E731
    assert untimed(result.summary()) == untimed(printed[-len(result.summary()) - 1:-1])
    figure, = result.plot(tmp_path / "fig")
    assert figure.name == "li2022-convergence.png" and figure.stat().st_size > 10_000
    assert spec.parameters == ["controller.k_inc_per_s"]
    assert [e.name for e in tune.Problem(spec.scenario, ["k_inc"]).entries] == spec.parameters
    # The best point's legend: the key by its Field's symbol and unit (the controller found by its import path).
    assert plots.label_for("controller.k_inc_per_s", ("own_laws:DAMPER",)) == "k_inc (1/s)"


def test_the_default_parameters_and_the_horizon_warning_come_from_the_controller(own_scenario):
    """No ``parameters``: the controller's ``tuned_fields``.  A year of horizon: no warning, unless the
    controller plans over a longer window than the run (a plan then reaches past its end).  (``tune`` itself
    warning is checked through the command line above.)"""
    spec = tune.from_dict({"scenario": str(own_scenario)})
    assert spec.parameters == ["controller.k_inc_per_s"] and spec.days == 365.25
    assert tune.horizon_warning(spec) is None
    import own_laws

    planner = dataclasses.replace(own_laws.DAMPER, reference_cycles=400)
    spec = tune.from_dict({"scenario": str(own_scenario)}, controller=planner)
    assert "shorter than the controller's prediction window (400 cycles)" in tune.horizon_warning(spec)


def test_nothing_in_the_tuning_package_names_a_controller():
    """Read from the code itself (names, imports, attributes and string constants, docstrings aside): no
    registered controller's name and no key or alias of its fields appears in geojax/tune/."""
    forbidden = set(REGISTRY) - {"none"}
    for module in REGISTRY.values():  # keys of more than one word (one word, "iterations", is not a name)
        forbidden |= {key for key in module.FIELDS if "_" in key} | {f.alias for f in module.FIELDS.values() if f.alias}
    forbidden -= set(tune.FIELDS)  # the tuner's own keys (its penalty_mps is not the MPC's)
    package = Path(tune.__file__).parent
    for path in sorted(package.glob("*.py")):
        tree = ast.parse(path.read_text())
        docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                      if isinstance(node, (ast.Module, ast.FunctionDef, ast.ClassDef)) and node.body
                      and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}
        words = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Name):
                words.add(node.id)
            elif isinstance(node, ast.Attribute):
                words.add(node.attr)
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                words |= {part for alias in node.names for part in alias.name.split(".")}
                words |= set((getattr(node, "module", None) or "").split("."))
            elif isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
                words |= {part for token in node.value.replace(",", " ").split() for part in token.split(".")}
        assert not words & forbidden, (path.name, sorted(words & forbidden))
    assert len(forbidden) > 20  # the check reads the registry's fields (Katz's k_h, the MPC's horizon, ...)


def test_the_tuning_files_documentation_is_built_from_its_fields():
    """The documentation's table of the tuning file's keys (docs/hooks.py, shown in docs/feedback.md beside the
    sweep's) is generated from ``FIELDS``: every key with its default and its one-line meaning."""
    root = Path(__file__).resolve().parent.parent
    sys.path.insert(0, str(root / "docs"))
    try:
        import hooks
    finally:
        sys.path.remove(str(root / "docs"))
    table = hooks.tuning_keys()
    for key, field in tune.FIELDS.items():
        assert field.doc and f"| `{key}` |" in table and field.doc in table
    assert "<!-- generated: tuning-keys -->" in (root / "docs" / "feedback.md").read_text()
