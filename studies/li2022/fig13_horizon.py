"""Li 2022 Fig. 13: FOMPC ΔV per year against the horizon N = 1..10 under weak, normal and strong limits.

    python studies/li2022/fig13_horizon.py [--reps R] [--days D]

The QFFC does not depend on N; its line is the reference of each level.
"""

import numpy as np

from sweep_study import Figure, main

LEVELS = ("weak", "normal", "strong")


def findings(summaries):
    best = []
    for level, s in zip(LEVELS, summaries, strict=True):
        m = s.mean["fompc"]
        j = int(np.nanargmin(m))
        best.append(f"{level} N = {s.x[j]:g} ({m[j]:.2f}; N = 1: {m[0]:.2f}, N = 10: {m[-1]:.2f}; "
                    f"QFFC {np.nanmean(s.mean['qffc']):.2f})")
    return ["best " + "; ".join(best)]


FIGURE = Figure(
    "fig13_horizon", "Fig. 13 (horizon N)", tuple(f"fig13_horizon_{level}.toml" for level in LEVELS),
    ("an optimal N exists: 3, 6 and 7 under weak, normal and strong constraints",),
    findings,
    labels=LEVELS,
)

if __name__ == "__main__":
    main(FIGURE)
