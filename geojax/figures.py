"""The figures of a results file, by what it holds (``geojax plot``): a sweep's, a tuning's convergence, a bound's
plan, a transfer's orbit, or a single run's (``runner.report.draw``: per step, per cycle, the station keeping)."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple


def plot_file(path: str | Path, out: str | Path | None = None, fmt: str = "png", dpi: int = 150) -> list[Path]:
    """Draw the figures of the geojax results file ``path`` into ``out`` (default: beside it), named after the
    file; ``ValueError`` with one line for a file that is not one or holds nothing to draw."""
    from geojax import plots, store
    from geojax.sweep import report as sweep_report
    from geojax.runner.report import draw, part_figures

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"file {str(path)!r}: no such file")
    try:
        groups, attrs = store.read_h5(path)
    except OSError:
        raise ValueError(f"file {str(path)!r}: not an HDF5 file") from None
    out = Path(out) if out else path.parent
    title = str(attrs.get("scenario", attrs.get("name", path.stem)))
    kind = attrs.get("kind")
    if kind == "sweep":
        axes = str(attrs["grid_axes"]).split(",")
        if axes == ["controller"]:  # repetitions alone: the spread of each controller's samples
            return [plots.plot_repetitions(groups, out / f"{path.stem}.{fmt}", title=sweep_report.title(attrs, axes),
                                           dpi=dpi)]
        return [plots.plot_sweep(groups, axes, out / f"{path.stem}.{fmt}", title=sweep_report.title(attrs, axes),
                                 dpi=dpi)]
    if kind == "tune":
        if "iterations" not in groups:
            raise ValueError(f"file {str(path)!r}: a tuning file without /iterations (stopped before its first)")
        from geojax import tune

        return [tune.figure(groups, attrs, out / f"{path.stem}-convergence.{fmt}", dpi=dpi)]
    if kind == "bound":
        return [plots.plot_bound(groups["slots"], box_half_width_deg(attrs), out / f"{path.stem}.{fmt}",
                                 title=f"{title}: the least Delta-V", dpi=dpi)]
    if kind == "transfer":
        return [plots.plot_transfer(groups["records"], out / f"{path.stem}.{fmt}", title=title, dpi=dpi)]
    if "steps" in groups or "cycles" in groups:
        drawn_box = "steps" in groups or {"reference", "target"} <= set(groups)
        box = box_half_width_deg(attrs) if drawn_box else 0.0
        drawn = draw(groups, box, out / path.stem, title, fmt=fmt, dpi=dpi)
        if kind == "simulate":  # a closed loop's file holds the /cycles of the parts it carried
            drawn += part_figures(FileRun.of(groups, attrs, path.stem, title, fmt, dpi), out)
        return drawn
    raise ValueError(f"file {str(path)!r}: nothing geojax can plot "
                     f"(no /cycles, /steps, sweep, tuning, bound or transfer data)")


def box_half_width_deg(attrs) -> float:
    """The box half-width (deg) of the scenario stored with a results file."""
    from geojax import scenario

    config = scenario.tomllib.loads(str(attrs["config_toml"]))
    return float(scenario.from_dict(config).config["station"]["box_half_width_deg"])


class FileRun(NamedTuple):
    """A ``simulate`` file read back as the parts' figures read a run (``states.base.Part.figures``): its /cycles
    (``cycles()``), its scenario, the ``Params`` it ran with and the parts it carried (rebuilt from the scenario
    stored with it; None where it carried none); the figures named after the file (``stem``) in its format at its
    resolution."""

    table: dict
    scenario: object
    params: object
    states: tuple
    stem: str
    title: str
    fmt: str = "png"
    dpi: int = 150

    def cycles(self) -> dict:
        return self.table

    @classmethod
    def of(cls, groups: dict, attrs: dict, stem: str, title: str, fmt: str, dpi: int) -> "FileRun":
        from geojax import scenario, states
        from geojax.runner.setup import controller_of, params_of

        sc = scenario.from_dict(scenario.tomllib.loads(str(attrs["config_toml"])))
        models = states.of_config(sc.config)
        params = params_of(sc, controller_of([sc])) if models else None  # nothing to draw: no parameters built
        return cls(groups["cycles"], sc, params, models, stem, title, fmt, dpi)
