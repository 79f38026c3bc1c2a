"""Figures from results (matplotlib, no display needed), one module per family of figures on shared helpers.

Every figure is drawn under one style, ``STYLE`` (applied per call, never to matplotlib's global state),
and written at ``dpi`` in the format its path's suffix names (``FORMATS``).  No axis carries offset text:
small quantities are shown in a power of ten named in the axis label (``e_x (10⁻⁵)``, ``decade``).

The figures: ``runs`` (one run against time: a closed loop, a feedback run, a transfer, a fuel bound's plan),
``parts`` (the loop's parts per cycle: the wheels' momentum, the navigation filter's error and consistency, each
declared by its part), ``sweeps`` (a sweep's metric against its swept parameter, with the repetitions' spread, or
the spread of a sweep of repetitions alone) and ``tuning`` (a tuning's convergence).  What they are drawn with:
``style`` (the style, and writing a figure to its file), ``labels`` (axis labels and units from the parameters'
``Field``s), ``layout`` (axis ranges, insets, legends) and ``ground_track`` (the daily libration rebuilt from
cycle means).
"""

import matplotlib

matplotlib.use("Agg")  # before pyplot is first imported, by this package or any of its modules
import matplotlib.pyplot as plt  # noqa: E402

from geojax.plots.ground_track import ground_track_deg, libration_rad  # noqa: E402
from geojax.plots.labels import QUANTITIES, decade, field_of, label_for  # noqa: E402
from geojax.plots.parts import plot_consistency, plot_navigation_error, plot_wheels  # noqa: E402
from geojax.plots.runs import plot_bound, plot_cycles, plot_feedback, plot_station_keeping, plot_transfer  # noqa: E402
from geojax.plots.style import FORMATS, STYLE, _save, styled  # noqa: E402
from geojax.plots.sweeps import plot_repetitions, plot_sweep, plot_sweeps  # noqa: E402
from geojax.plots.tuning import plot_tuning  # noqa: E402

__all__ = [
    "FORMATS", "QUANTITIES", "STYLE", "decade", "field_of", "ground_track_deg", "label_for", "libration_rad",
    "plot_bound", "plot_consistency", "plot_cycles", "plot_feedback", "plot_navigation_error", "plot_repetitions",
    "plot_station_keeping", "plot_sweep", "plot_sweeps", "plot_transfer", "plot_tuning", "plot_wheels", "styled",
    # Not the API, reachable as before: ``plots._save`` writes the figures studies/ draw themselves, and
    # ``plots.plt`` is the pyplot this package draws with (the tests keep its figures open through it).
    "_save", "plt",
]
