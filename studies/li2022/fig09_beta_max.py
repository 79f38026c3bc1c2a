"""Li 2022 Fig. 9: ΔV per year against the largest pitch angle β_max (45°-90°), weak preset otherwise.

    python studies/li2022/fig09_beta_max.py [--reps R] [--days D]
"""

from sweep_study import Figure, main, value_at


def findings(s):
    (s,) = s
    q45, q90, f45, f90 = (value_at(s, c, x) for c in ("qffc", "fompc") for x in (45, 90))
    slope = lambda c, a, b: (value_at(s, c, a) - value_at(s, c, b)) / (b - a)  # noqa: E731
    return [
        f"QFFC {q45:.1f} → {q90:.1f}; FOMPC {f45:.1f} → {f90:.1f} m/s/yr",
        f"drop per degree: QFFC {slope('qffc', 45, 80):.2f} below 80° and {slope('qffc', 80, 90):.2f} above; "
        f"FOMPC {slope('fompc', 45, 80):.2f} and {slope('fompc', 80, 90):.2f}",
    ]


FIGURE = Figure(
    "fig09_beta_max", "Fig. 9 (β_max)", ("fig09_beta_max.toml",),
    ("β_max 45° → 90°: QFFC 78.2 → 57.5, FOMPC 73.7 → 51.4 m/s/yr",
     "the drop is more apparent below 80°"),
    findings,
    paper_values={45.0: {"qffc": 78.2, "fompc": 73.7}, 90.0: {"qffc": 57.5, "fompc": 51.4}},
)

if __name__ == "__main__":
    main(FIGURE)
