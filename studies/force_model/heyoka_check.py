"""The field against heyoka's ``model.egm2008_acc`` (Taylor-integrator library, its own EGM2008 evaluation),
a second independent check beside ``tests/test_geopotential.py``'s spherical-gradient reference.

    python studies/force_model/heyoka_check.py   (needs heyoka, the ``bench`` extra)

300 random points from 6,600 to 50,000 km, Earth-fixed, degree = order = 2, 4, 8, 12, 16, 20, both with
heyoka's GM and radius.  heyoka returns the total acceleration (central term included); the difference is
reported relative to the total and relative to the non-central part (the latter limited by the rounding of
the central term, about 1e-16 of GM/r^2).  Results: ``results/heyoka_check.json`` and ``.md``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import heyoka as hy
import jax
import jax.numpy as jnp
import numpy as np

import geojax  # noqa: F401  (x64)
from geojax.physics.forces import point_mass
from geojax.physics.geopotential import egm2008, geopotential_acceleration

HERE = Path(__file__).resolve().parent
DEGREES = (2, 4, 8, 12, 16, 20)


def main():
    rng = np.random.default_rng(2012)
    direction = rng.normal(size=(300, 3))
    points = direction / np.linalg.norm(direction, axis=1, keepdims=True) * rng.uniform(6.6e6, 5.0e7, size=(300, 1))
    mu, radius = hy.model.get_egm2008_mu(), hy.model.get_egm2008_a()
    x, y, z = hy.make_vars("x", "y", "z")
    results = {"command": "python studies/force_model/heyoka_check.py " + " ".join(sys.argv[1:]),
               "heyoka": hy.__version__, "points": len(points), "degrees": {}}
    for degree in DEGREES:
        theirs = hy.cfunc(hy.model.egm2008_acc([x, y, z], degree, degree), [x, y, z])(points.T.copy()).T
        field = jax.tree_util.tree_map(jnp.asarray, egm2008(degree))
        central = np.asarray(point_mass(jnp.asarray(points), mu))
        ours = np.asarray(geopotential_acceleration(jnp.asarray(points), 0.0, mu, radius, field)) + central
        diff = np.linalg.norm(ours - theirs, axis=1)
        results["degrees"][str(degree)] = {
            "max_relative_to_total": float(np.max(diff / np.linalg.norm(theirs, axis=1))),
            "max_relative_to_noncentral": float(np.max(diff / np.linalg.norm(theirs - central, axis=1)))}
        print(degree, results["degrees"][str(degree)], flush=True)
    lines = ["# The field against heyoka's egm2008_acc", "",
             f"`{results['command']}`: heyoka {results['heyoka']}, {len(points)} random points from 6,600 to "
             "50,000 km, Earth-fixed, GM and radius of heyoka's EGM2008.", "",
             "| degree = order | max difference / total | max difference / non-central part |", "|---:|---:|---:|"]
    lines += [f"| {d} | {r['max_relative_to_total']:.1e} | {r['max_relative_to_noncentral']:.1e} |"
              for d, r in results["degrees"].items()]
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "heyoka_check.json").write_text(json.dumps(results, indent=1))
    (HERE / "results" / "heyoka_check.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
