"""Li 2022 Fig. 15: ΔV per year against the attitude-error level H_att (eq. 48) under the normal limits.

    python studies/li2022/fig15_h_att.py [--reps R] [--days D]
"""

import numpy as np

from sweep_study import Figure, first_unstable, main, relative_change


def findings(summaries):
    (s,) = summaries
    out = []
    for c in ("qffc", "fompc"):
        change = relative_change(s, c, 0.0)
        steps = ", ".join(f"{100 * change[j]:+.1f} % at {x:g} (3σ = {0.05 * x:g}°)"
                          for j, x in enumerate(s.x) if 0 < x and np.isfinite(change[j]) and s.unstable[c][j] == 0)
        out.append(f"{c.upper()}: ΔV {steps}; first level with a repetition out of the box: {first_unstable(s, c)}")
    return ["; ".join(out)]


FIGURE = Figure(
    "fig15_h_att", "Fig. 15 (attitude error)", ("fig15_h_att.toml",),
    ("the attitude error has almost no effect on either controller",),
    findings,
)

if __name__ == "__main__":
    main(FIGURE)
