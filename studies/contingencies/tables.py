"""The contingency studies' README: every table made again from the results files the studies wrote.

    python studies/contingencies/tables.py

Reads ``results/arm_lost.json``, ``results/missed_burns.json`` and ``results/degradation.json`` (each written by
its study script, ``arm_lost.py``, ``missed_burns.py``, ``degradation.py``) and writes ``README.md`` beside them
(and each study's ``results/<name>.md`` again), each table by its script's own ``table`` function; a study not
yet run is named as such.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

HERE = Path(__file__).resolve().parent
STUDIES = (("arm_lost", "An arm lost on a random day, told and not told; four thrusters against two"),
           ("missed_burns", "Burns missed: the probability each controller holds its box at"),
           ("degradation", "A thruster degraded by 5–15 %, told and not told"))


def script(name: str):
    spec = importlib.util.spec_from_file_location(name, HERE / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    lines = ["# Contingencies: what a fault costs Li's satellite and each controller", "",
             "Made by `python studies/contingencies/tables.py` from the results the studies wrote "
             "(`results/*.json`); the keys and the physics: `docs/contingencies.md`.", ""]
    for name, title in STUDIES:
        lines += [f"## {title} (`{name}.py`)", ""]
        path = HERE / "results" / f"{name}.json"
        if path.exists():
            text = script(name).table(json.loads(path.read_text()))
            (HERE / "results" / f"{name}.md").write_text(text)
            lines.append(text)
        else:
            lines += [f"Not yet run: `python studies/contingencies/{name}.py`.", ""]
    (HERE / "README.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
