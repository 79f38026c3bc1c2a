"""Li 2022 Fig. 10: ΔV per year against the smallest pitch angle β_min (0°-60°), weak preset otherwise.

    python studies/li2022/fig10_beta_min.py [--reps R] [--days D]
"""

from sweep_study import Figure, main, relative_change


def findings(s):
    (s,) = s
    out = []
    for c in ("qffc", "fompc"):
        change = relative_change(s, c, 0.0)
        big = s.x[change > 0.01]
        out.append(f"{c.upper()}: first β_min raising ΔV by more than 1 %: {big.min():g}°" if big.size else
                   f"{c.upper()}: no β_min up to {s.x.max():g}° raises ΔV by more than 1 %")
    return [" ; ".join(out)]


FIGURE = Figure(
    "fig10_beta_min", "Fig. 10 (β_min)", ("fig10_beta_min.toml",),
    ("β_min has almost no influence on ΔV until it reaches 40°",),
    findings,
)

if __name__ == "__main__":
    main(FIGURE)
