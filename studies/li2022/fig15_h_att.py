"""Li 2022 Fig. 15: ΔV per year against the attitude-error level H_att (eq. 48) under the normal limits.

    python studies/li2022/fig15_h_att.py [--reps R] [--days D]
"""

import numpy as np

from sweep_study import Figure, first_unstable, main, relative_change


def findings(summaries):
    (s,) = summaries
    return ["; ".join(f"{c.upper()}: ΔV within {100 * np.nanmax(np.abs(relative_change(s, c, 0.0))):.1f} % of "
                      f"H_att = 0 up to {s.x.max():g}, first unstable level {first_unstable(s, c)}"
                      for c in ("qffc", "fompc"))]


FIGURE = Figure(
    "fig15_h_att", "Fig. 15 (attitude error)", ("fig15_h_att.toml",),
    ("the attitude error has almost no effect on either controller",),
    findings,
)

if __name__ == "__main__":
    main(FIGURE)
