"""Write ``egm2008_n20.txt``: the EGM2008 normalised coefficients to degree and order 20, tide-free.

Source: Pavlis, Holmes, Kenyon, Factor, "The development and evaluation of the Earth Gravitational Model
2008 (EGM2008)", J. Geophys. Res. 117 (2012), B04406, doi:10.1029/2011JB008916; NGA's public-domain file
``EGM2008_to2190_TideFree``.  The numbers are read from the copy that heyoka (>= 7.12) ships of that file
(``heyoka.model.get_egm2008_CS``: rows [C, S] from degree 2, by degree then order), and checked here
against values published independently of it (the ICGEM / NGA file as quoted by MathWorks' ``gravitysphericalharmonic``
and Tudat's EGM2008 tests).  Run: ``python geojax/physics/data/make_egm2008.py`` (needs heyoka).
"""

from pathlib import Path

import heyoka
import numpy as np

MAX_DEGREE = 20
GM_M3_S2, RADIUS_M = 3.986004415e14, 6378136.3  # the model's reference values (Pavlis 2012, Table 1)
# (n, m, C, S) as printed in the published file, for the check below.
PUBLISHED = ((2, 0, -4.84165143790815e-04, 0.0), (2, 2, 2.43938357328313e-06, -1.40027370385934e-06),
             (3, 1, 2.03046201047864e-06, 2.48200415856872e-07), (4, 0, 5.39965866638991e-07, 0.0),
             (4, 4, -1.88519633023033e-07, 3.08803882149194e-07), (5, 5, 1.74811795496002e-07, -6.69379935180165e-07))


def main(path=Path(__file__).with_name(f"egm2008_n{MAX_DEGREE}.txt")):
    assert heyoka.model.get_egm2008_mu() == GM_M3_S2 and heyoka.model.get_egm2008_a() == RADIUS_M
    cs = np.asarray(heyoka.model.get_egm2008_CS())
    rows = [(n, m, *map(float, cs[n * (n + 1) // 2 + m - 3])) for n in range(2, MAX_DEGREE + 1) for m in range(n + 1)]
    table = {(n, m): (c, s) for n, m, c, s in rows}
    for n, m, c, s in PUBLISHED:
        assert table[n, m] == (c, s), (n, m, table[n, m])
    header = [
        "# EGM2008, normalised (4 pi) spherical-harmonic coefficients C_nm, S_nm, tide-free, degree and order",
        f"# 2..{MAX_DEGREE} (C_00 = 1 and degree 1 = 0 are implied).  Pavlis et al., J. Geophys. Res. 117 (2012),",
        "# B04406, doi:10.1029/2011JB008916; NGA file EGM2008_to2190_TideFree (public domain).",
        f"# GM = {GM_M3_S2!r} m^3/s^2, R = {RADIUS_M!r} m.  Written by make_egm2008.py (heyoka "
        f"{heyoka.__version__}'s copy of the file).",
        "# n m C S",
    ]
    path.write_text("\n".join(header + [f"{n} {m} {c!r} {s!r}" for n, m, c, s in rows]) + "\n")


if __name__ == "__main__":
    main()
