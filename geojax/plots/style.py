"""The one style every figure is drawn under (``STYLE``, ``styled``) and how a figure is written to its file
(``_save``: the format its suffix names, one of ``FORMATS``, a grid, no offset text, a title)."""

from __future__ import annotations

import functools
from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
from matplotlib.ticker import ScalarFormatter

FORMATS = ("png", "pdf", "svg")

STYLE = {
    "font.size": 9, "axes.labelsize": 9, "axes.titlesize": 9, "figure.titlesize": 10,
    "xtick.labelsize": 8, "ytick.labelsize": 8, "legend.fontsize": 8, "legend.framealpha": 0.85,
    "axes.formatter.useoffset": False, "axes.formatter.use_mathtext": True,
    "axes.grid": True, "grid.alpha": 0.3, "grid.linewidth": 0.5, "lines.linewidth": 1.0,
    "savefig.bbox": "tight", "savefig.pad_inches": 0.03,
    "pdf.fonttype": 42,  # TrueType in the PDF: text stays text, as journals ask
}


def styled(plot):
    """``plot`` drawn under ``STYLE`` whatever the caller's rcParams, which it leaves as they were."""
    @functools.wraps(plot)
    def styled(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return plot(*args, **kwargs)
    return styled


def _save(fig, axes, title: str, path: str | Path, dpi: int = 150) -> Path:
    """Write ``fig`` to ``path`` in the format of its suffix (one of ``FORMATS``) at ``dpi`` under ``STYLE``, with a
    grid on ``axes``, no offset text on any axes and ``title`` above; closes ``fig``."""
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower()
    try:
        if fmt not in FORMATS:
            raise ValueError(f"figure {str(path)!r}: the suffix must be one of {', '.join('.' + f for f in FORMATS)}")
        with matplotlib.rc_context(STYLE):
            for a in axes:
                a.grid(True, alpha=STYLE["grid.alpha"], linewidth=STYLE["grid.linewidth"])
            for parent in fig.axes:  # insets, and figures built outside STYLE (studies/), included
                for axis in (axis for a in (parent, *parent.child_axes) for axis in (a.xaxis, a.yaxis)):
                    if isinstance(axis.get_major_formatter(), ScalarFormatter):
                        axis.get_major_formatter().set_useOffset(False)
            if title:
                fig.suptitle(title)
            path.parent.mkdir(parents=True, exist_ok=True)
            fig.savefig(path, dpi=dpi, format=fmt)
    finally:
        plt.close(fig)
    return path
