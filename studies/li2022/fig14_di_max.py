"""Li 2022 Fig. 14: FOMPC ΔV per year against Δi_max (MEE (h, k)) under the normal limits.

    python studies/li2022/fig14_di_max.py [--reps R] [--days D]
"""

from sweep_study import Figure, main, value_at


def findings(summaries):
    (s,) = summaries
    lo, hi = s.x.min(), s.x.max()
    return [f"FOMPC {value_at(s, 'fompc', lo):.2f} at Δi_max = {lo:g}, {value_at(s, 'fompc', 8e-5):.2f} at 8e-5, "
            f"{value_at(s, 'fompc', hi):.2f} at {hi:g} (QFFC {value_at(s, 'qffc', lo):.2f})"]


FIGURE = Figure(
    "fig14_di_max", "Fig. 14 (Δi_max)", ("fig14_di_max.toml",),
    ("Δi_max significantly affects ΔV: it sets the degree of optimisation",),
    findings,
)

if __name__ == "__main__":
    main(FIGURE)
