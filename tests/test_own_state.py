"""A state of one's own, written outside the package on the public protocol (``geojax.StateModel``: five
functions), runs through ``geojax.simulate``; its metrics reach the result under its names and its failure is a
status code of its own after the shipped ones.

Independent check: the documentation's own example (docs/python.md, "A state of one's own", run as written from
a module outside the repository) sums the rocket equation's ΔV of the thrust it is told about, step by step; the
loop integrates the same thrust and the mass's flow with RK4, a second method, so the two agree to 1e-9.
"""

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def _docs_example(tmp_path, replace=()):
    page = (ROOT / "docs" / "python.md").read_text()
    section = page.split("## A state of one's own", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    for old, new in replace:
        assert old in code
        code = code.replace(old, new)
    path = tmp_path / "wear_example.py"
    path.write_text(code)
    spec = importlib.util.spec_from_file_location("wear_example", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_state_of_ones_own_runs_and_its_delta_v_is_the_loops(tmp_path):
    example = _docs_example(tmp_path)
    m, r = example.result.metrics, example.result
    assert m["dv_per_year_mps"] > 0 and m["wear_firing_hours"] > 0
    run_years = round(10 * 86400 / 86164.0905) * 86164.0905 / (365.25 * 86400)
    assert np.isclose(m["wear_dv_mps"], float(r.final.dv_mps), rtol=1e-9), (m["wear_dv_mps"], r.final.dv_mps)
    assert np.isclose(m["wear_dv_mps"], m["dv_per_year_mps"] * run_years, rtol=1e-9)
    assert r.status_meanings[int(r.status)] == "ok"
    assert "wear" in r.records.cycles.states


def test_its_failure_is_a_status_code_of_its_own(tmp_path):
    example = _docs_example(tmp_path, (("QUALIFIED_HOURS = 8000.0", "QUALIFIED_HOURS = 1e-3"),))
    r = example.result
    assert r.status_meanings[int(r.status)] == "thruster past its qualified hours"
    assert int(r.status) == len(r.status_meanings) - 1 > 6  # after the loop's and the shipped parts' codes


def test_a_part_of_ones_own_declares_its_figures(tmp_path):
    """A user's ``Part`` (its model, its descriptions, its figures) passed to ``simulate``: ``Result.plot`` draws
    its figure beside the run's, from the records the part made."""
    import geojax

    (tmp_path / "module").mkdir()
    example = _docs_example(tmp_path / "module", replace=(('"duration.days": 10', '"duration.days": 3'),))

    def figure(result, folder):
        path = folder / "wear.txt"
        path.write_text(str(float(result.records.cycles.states["wear"]["firing_s"][-1])))
        return [path]

    part = geojax.Part("wear", model=example.WEAR, figures=figure)
    sc = geojax.load_scenario("li2022-qffc", {"duration.days": 3})
    r = geojax.simulate(sc, seed=0, states=(part,))
    drawn = r.plot(tmp_path / "figs")
    assert tmp_path / "figs" / "wear.txt" in drawn
    assert np.isclose(float((tmp_path / "figs" / "wear.txt").read_text()), r.metrics["wear_firing_hours"] * 3600.0,
                      rtol=1e-14)


def _wear_module(folder: Path) -> str:
    """The docs example's definitions (up to its ``WEAR``, without its run) as a module ``wear_part`` in
    ``folder``; returns its import path."""
    page = (ROOT / "docs" / "python.md").read_text()
    code = re.search(r"```python\n(.*?)```", page.split("## A state of one's own", 1)[1], re.S).group(1)
    (folder / "wear_part.py").write_text(code.split("\nsc = ", 1)[0] + "\n")
    return "wear_part:WEAR"


def test_a_scenario_file_names_a_part_of_ones_own_by_import_path(tmp_path, monkeypatch):
    """``states = ["wear_part:WEAR"]`` at a scenario file's top carries the part as ``simulate(states=...)``
    does: the same metrics bit for bit; a path that is not one is refused in one line naming it."""
    import geojax

    monkeypatch.syspath_prepend(str(tmp_path))
    path = _wear_module(tmp_path)
    text = geojax.scenario.read_text("li2022-qffc")
    (tmp_path / "mine.toml").write_text(f'states = ["{path}"]\n' + text)
    named = geojax.simulate(geojax.load_scenario(str(tmp_path / "mine.toml"), {"duration.days": 3}), seed=1)
    import wear_part

    given = geojax.simulate(geojax.load_scenario("li2022-qffc", {"duration.days": 3}), seed=1,
                            states=(wear_part.WEAR,))
    assert named.metrics["wear_firing_hours"] > 0
    assert {k: float(v) for k, v in named.metrics.items() if k != "cpu_s_per_orbit"} == \
        {k: float(v) for k, v in given.metrics.items() if k != "cpu_s_per_orbit"}
    (tmp_path / "bad.toml").write_text('states = ["wear_part:NOPE"]\n' + text)
    with pytest.raises(ValueError, match="states: cannot import 'wear_part:NOPE'"):
        geojax.load_scenario(str(tmp_path / "bad.toml"))


def test_a_sweep_carries_a_part_of_ones_own(tmp_path, monkeypatch):
    """``load_sweep(..., states={"wear": WEAR})``: every sample carries the part, its metric in the file."""
    import geojax
    from geojax import store

    monkeypatch.syspath_prepend(str(tmp_path))
    _wear_module(tmp_path)
    import wear_part

    (tmp_path / "s.toml").write_text('name = "wear"\nscenario = "li2022-qffc"\ncontrollers = ["qffc"]\n'
                                     'repetitions = 2\n[set]\n"duration.days" = 3\n')
    spec = geojax.load_sweep(tmp_path / "s.toml", states={"wear": wear_part.WEAR})
    out = geojax.run_sweep(spec, tmp_path / "s.h5")
    data, _ = store.read_h5(out)
    hours = np.asarray(data["metrics"]["wear_firing_hours"])
    assert hours.size == 2 and np.all(hours > 0)
    with pytest.raises(ValueError, match="named 'wear'"):
        geojax.load_sweep(tmp_path / "s.toml", states={"other": wear_part.WEAR})
