"""Li 2022 Fig. 15: ΔV per year against the attitude-error level H_att (eq. 48) under the normal limits, under
two readings of eq. (47), side by side:

* ``fig15_h_att``: the error on the direction flown, the burn magnitudes as planned (the text's reading, our
  default);
* ``fig15_h_att_known``: the plan knows the error and re-fits the two magnitudes to the directions flown
  (``errors.att_known``; the reading nearest Li's "almost no effect", issue 34).

    python studies/li2022/fig15_h_att.py [--reps R] [--days D]

The mechanism behind the default reading's failures is measured in ``studies/ablation/li_attitude_error.py``
and tested in ``tests/test_attitude_error.py``.
"""

import numpy as np

from sweep_study import Figure, first_unstable, main, relative_change

READINGS = ("magnitudes as planned", "plan knows the error")


def findings(summaries):
    out = []
    for reading, s in zip(READINGS, summaries, strict=True):
        per = []
        for c in ("qffc", "fompc"):
            change = relative_change(s, c, 0.0)
            steps = ", ".join(f"{100 * change[j]:+.1f} % at {x:g}" for j, x in enumerate(s.x)
                              if 0 < x <= 500 and np.isfinite(change[j]) and s.unstable[c][j] == 0)
            no_sol = ", ".join(f"{x:g}" for j, x in enumerate(s.x) if s.no_solution[c][j] > 0) or "none"
            per.append(f"{c.upper()}: ΔV {steps or 'no level above 0 with every repetition in the box'}; first level "
                       f"with a repetition out of the box: {first_unstable(s, c)}; levels with unsolved cycles: "
                       f"{no_sol}")
        out.append(f"{reading} (`{s.name}`): " + "; ".join(per))
    return [" <br> ".join(out)]


FIGURE = Figure(
    "fig15_h_att", "Fig. 15 (attitude error)", ("fig15_h_att.toml", "fig15_h_att_known.toml"),
    ("the attitude error has almost no effect on either controller",),
    findings,
    labels=("as planned", "plan knows"),
)

if __name__ == "__main__":
    main(FIGURE)
