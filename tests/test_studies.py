"""``studies/reproduce.py``: every script it would run exists and each setting is listed once; a filter that matches
nothing is refused (exit 2), so a renamed study cannot silently drop out of "reproduce all"."""

import importlib.util
from pathlib import Path

STUDIES = Path(__file__).resolve().parents[1] / "studies"


def load():
    spec = importlib.util.spec_from_file_location("reproduce", STUDIES / "reproduce.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_listed_study_exists_and_each_script_of_a_paper_folder_is_listed(capsys):
    reproduce = load()
    entries = [(script, tuple(args)) for script, args in reproduce.selected(["all"], None)]
    assert len(entries) == len(set(entries))  # a script may run with several settings, each once
    scripts = [script for script, _ in entries]
    assert all((STUDIES / script).is_file() for script in scripts)
    # every runnable script of the paper folders (not the shared sweep helper) is in the list
    runnable = {str(p.relative_to(STUDIES)) for folder in ("li2022", "katz2025", "ye2022", "ma2023", "ablation", "bounds",
                                                                             "longrun", "lifetime", "compare", "momentum",
                                                                             "navigation", "contingencies")
                for p in (STUDIES / folder).glob("*.py") if "__main__" in p.read_text() and p.name != "sweep_study.py"}
    assert runnable <= set(scripts), runnable - set(scripts)
    assert reproduce.main(["all", "--list"]) == 0
    assert f"[{len(entries)}/{len(entries)}]" in capsys.readouterr().out


def test_a_filter_matching_nothing_is_refused(capsys):
    assert load().main(["li2022", "--only", "no-such-study"]) == 2
    assert "no script" in capsys.readouterr().err
