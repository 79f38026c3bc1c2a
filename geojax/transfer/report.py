"""The file, the summary and the figure of one transfer: what ``TransferResult.save``, ``summary`` and ``plot``
give (``geojax transfer --out`` calls them; ``geojax plot`` draws the figure of the file).

The file (``kind = "transfer"``): ``/metrics`` (``run.metrics``, units in the names) and ``/records`` (per
record interval, ``run.record_table``); attributes ``scenario``, ``layout``, ``epoch_tt_s``, ``step_s`` and
``status_codes`` (``rollout.STATUS_TEXT``: 0 reached GEO, the rest failures, as a ``simulate`` file's) beside
``store.write_h5``'s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def save(result, path: str | Path) -> Path:
    """Write the transfer's file to ``path`` (atomically); returns the path."""
    from geojax import store
    from geojax.scenario import to_toml
    from geojax.transfer.rollout import STATUS_TEXT

    sc = scenario_of(result)
    return store.write_h5(path, {"metrics": {k: np.asarray(v) for k, v in result.metrics.items()},
                                 "records": result.records}, to_toml(sc.config), result.wall_s,
                          attrs={"kind": "transfer", "scenario": sc.name, "layout": sc.layout,
                                 "epoch_tt_s": sc.epoch_tt_s, "step_s": sc.step_s,
                                 "status_codes": STATUS_TEXT})


def summary(result, paper: bool = True) -> list[str]:
    """What ``geojax transfer`` prints: the scenario, the status and every metric, with ``paper`` beside Ma & Kong
    2023's published value where there is one (``geojax.papers.MA2023``)."""
    from geojax.papers import MA2023
    from geojax.transfer.rollout import STATUS_MEANINGS

    sc = scenario_of(result)
    m = result.metrics
    published = MA2023 if paper else {}
    lines = [f"{sc.name}: {sc.config['description']}", f"  status {int(m['status'])}: {STATUS_MEANINGS[int(m['status'])]}"]
    for name, value in m.items():
        if name != "status":
            beside = f"   (Ma 2023: {published[name]})" if name in published else ""
            lines.append(f"  {name:24s} {float(value):12.4f}{beside}")
    return lines


def plot(result, folder: str | Path) -> list[Path]:
    """The orbit and mass against time, ``FOLDER/NAME.png``; returns its path in a list."""
    from geojax import plots

    sc = scenario_of(result)
    return [plots.plot_transfer(result.records, Path(folder) / f"{sc.name}.png", title=f"{sc.name}, {sc.layout}")]


def scenario_of(result):
    if result.scenario is None:
        raise ValueError("scenario: this TransferResult does not carry its scenario; make it with transfer.run")
    return result.scenario
