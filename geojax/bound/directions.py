"""The velocity-increment directions each thruster geometry allows, as LP columns and as a pricing oracle.

The fuel bound (``geojax.bound``) takes each thruster's set of unit Delta-V directions D (RSW axes) in
two forms:

* ``generators`` [G, 3]: finitely many directions of D.  Their positive combinations are a polyhedral
  *inner* approximation of the cone of D, so the LP over them is an achievable plan (an upper estimate
  of the linear problem's optimum).
* ``best(g)``: for a row of pricing vectors g [S, 3], the direction of D that maximises g . d, and an upper
  bound on that maximum over the *whole* set D.  The LP's duals turn this into a rigorous lower bound
  (``bound.program``) and into new columns (column generation), so the inner approximation's error is
  measured, not assumed.

Geometries:

* ``arms`` (Li 2022, eq. (1) and (14)): two thrusters, Delta-V direction -(cos b cos a, cos b sin a,
  sin b) over a yaw/pitch rectangle each; thruster 1 pushes south (+pitch thrust), thruster 2 north.
  Only one fires at a time (Li 2022, Sec. 3.2, constraint 4) and not in Earth shadow (constraint 6).
  The maximum of g . d over the rectangle is taken on a grid of ``PRICING_GRID_DEG`` that includes its
  edges and corners.  The continuous maximum sits at a corner (a grid point), on an edge or inside, and
  there g . d is stationary along the rectangle, so the grid point nearest it (within the covering radius
  theta) is lower by at most |g| theta^2 (the curvature of a meridian is 1, of a parallel at pitch b
  1 / cos b over a yaw step shrunk by cos b); ``best`` adds that.
* ``gimbal`` (Katz 2025, Sec. 2): one thruster pointed anywhere; the maximum of g . d is |g|, exact.
* ``fixed4`` (Gazzino 2016, Sec. 5): four fixed thrusters whose Delta-V points north-east, north-west,
  south-east and south-west (at ``cant_deg`` from the north-south axis, in the S-W plane); exact.
* ``axes`` (Katz 2025, eq. (6), the discrete law): three thruster pairs along the Earth-fixed x, y and z axes,
  firing at once, pair i up to sigma_i (its ``shares`` of F / m, sigma_i / u0); the fuel is the L1 norm of the
  Delta-V in those axes.  A geostationary satellite's RSW frame turns with the Earth, so at the station's
  longitude lon the axes are fixed in RSW: x = (cos lon, -sin lon, 0), y = (sin lon, cos lon, 0), z = W; exact.
"""

from __future__ import annotations

import math
from typing import Callable, NamedTuple

import numpy as np

PRICING_GRID_DEG = 0.25
PRICING_CHUNK = 256  # pricing vectors per matrix product (memory: 256 x grid points)


class Geometry(NamedTuple):
    """A thruster set for the bound.  ``generators[i]`` [G_i, 3] and ``best[i]`` belong to thruster i."""

    name: str
    generators: list  # per thruster, [G_i, 3] unit Delta-V directions (RSW)
    best: list  # per thruster, g [S, 3] -> (direction [S, 3], max g . d over the whole set [S], an upper bound)
    one_at_a_time: bool  # the thrusters share one firing budget per slot (time-sharing), else one each
    dark_off: bool  # no firing in Earth shadow
    exact: bool  # the generators span the whole set (no pricing needed)
    shares: tuple | None = None  # per thruster, its firing budget as a fraction of F / m (None: 1 each)


def arm_direction(alpha_rad, beta_rad):
    """Li 2022, eq. (14): unit Delta-V of thrust direction (alpha, beta), RSW, [..., 3]."""
    cos_b = np.cos(beta_rad)
    return -np.stack([cos_b * np.cos(alpha_rad), cos_b * np.sin(alpha_rad), np.sin(beta_rad)], -1)


def arms(beta_max_rad, beta_min_rad, alpha_max_rad, alpha_min_rad, coarse: int = 3) -> Geometry:
    """Li's two robotic arms (eq. (1)): thruster 1 over alpha in [-alpha_min, alpha_max], beta in [beta_min,
    beta_max]; thruster 2 the mirror (alpha in [-alpha_max, alpha_min], beta in [-beta_max, -beta_min]).
    ``coarse`` x ``coarse`` generators each (corners and interior), refined by column generation."""
    boxes = [((-alpha_min_rad, alpha_max_rad), (beta_min_rad, beta_max_rad)),
             ((-alpha_max_rad, alpha_min_rad), (-beta_max_rad, -beta_min_rad))]
    generators, best = [], []
    for (a_lo, a_hi), (b_lo, b_hi) in boxes:
        a, b = np.meshgrid(np.linspace(a_lo, a_hi, coarse), np.linspace(b_lo, b_hi, coarse))
        generators.append(arm_direction(a.ravel(), b.ravel()))
        best.append(_grid_oracle(a_lo, a_hi, b_lo, b_hi))
    return Geometry("arms", generators, best, one_at_a_time=True, dark_off=True, exact=False)


def _grid_oracle(a_lo, a_hi, b_lo, b_hi) -> Callable:
    step = math.radians(PRICING_GRID_DEG)
    n_a, n_b = max(2, math.ceil((a_hi - a_lo) / step) + 1), max(2, math.ceil((b_hi - b_lo) / step) + 1)
    a, b = np.meshgrid(np.linspace(a_lo, a_hi, n_a), np.linspace(b_lo, b_hi, n_b))
    grid = arm_direction(a.ravel(), b.ravel())  # [M, 3]
    # Any direction of the rectangle is within half a cell diagonal (in yaw and pitch, so at most that
    # angle on the sphere) of a grid point; the maximum is missed by at most |g| radius^2 (module docstring).
    radius = 0.5 * math.hypot((a_hi - a_lo) / (n_a - 1), (b_hi - b_lo) / (n_b - 1))

    def best(g):
        index = np.empty(len(g), int)
        for lo in range(0, len(g), PRICING_CHUNK):  # [chunk, M] at a time: a year of slots x 100 k directions
            index[lo:lo + PRICING_CHUNK] = np.argmax(g[lo:lo + PRICING_CHUNK] @ grid.T, axis=1)
        top = np.sum(g * grid[index], axis=1)
        return grid[index], top + np.linalg.norm(g, axis=1) * radius**2

    return best


def gimbal(n_start: int = 26) -> Geometry:
    """One gimballed thruster, any direction (Katz 2025): starts from the 26 directions of a cube's faces,
    edges and corners; the best direction for g is g / |g|."""
    cube = np.array([(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1) if (x, y, z) != (0, 0, 0)],
                    float)[:n_start]

    def best(g):
        norm = np.linalg.norm(g, axis=1)
        unit = np.where(norm[:, None] > 0, g / np.maximum(norm, 1e-300)[:, None], np.array([1.0, 0.0, 0.0]))
        return unit, norm

    return Geometry("gimbal", [cube / np.linalg.norm(cube, axis=1, keepdims=True)], [best], one_at_a_time=True,
                    dark_off=False, exact=False)


def fixed4(cant_deg: float = 45.0) -> Geometry:
    """Gazzino's four fixed thrusters: Delta-V along +-S sin(cant) +- W cos(cant) (east/west, north/south)."""
    s, c = math.sin(math.radians(cant_deg)), math.cos(math.radians(cant_deg))
    dirs = [np.array([[0.0, e * s, n * c]]) for n in (1, -1) for e in (1, -1)]  # NE, NW, SE, SW

    def oracle(d):
        return lambda g: (np.broadcast_to(d, g.shape), g @ d[0])

    # Gazzino's relaxed problem (Problem 3) lets them fire together; "no simultaneous thrust" is an operational
    # constraint of its step (B).
    return Geometry("fixed4", dirs, [oracle(d) for d in dirs], one_at_a_time=False, dark_off=False, exact=True)


def axes(lon_rad: float, shares=(1.0, 1.0, 1.0)) -> Geometry:
    """Katz's per-axis thrusters (eq. (6)) at a station of longitude ``lon_rad``: pair i fires +-(ECEF axis i),
    up to ``shares[i]`` x F / m (sigma_i / u0), all three at once; the generators are the six directions."""
    c, s = math.cos(lon_rad), math.sin(lon_rad)
    axes_rsw = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])  # ECEF x, y, z in RSW at the station
    dirs = [np.stack([a, -a]) for a in axes_rsw]

    def oracle(d):
        def best(g):
            dot = g @ d.T  # [S, 2]: the + and - direction of the pair
            pick = np.argmax(dot, axis=1)
            return d[pick], dot[np.arange(len(g)), pick]
        return best

    if len(shares) != 3 or min(shares) <= 0:
        raise ValueError(f"axes: three positive shares of F / m, got {shares!r}")
    return Geometry("axes", dirs, [oracle(d) for d in dirs], one_at_a_time=False, dark_off=False, exact=True,
                    shares=tuple(float(x) for x in shares))


GEOMETRIES = ("arms", "gimbal", "fixed4", "axes")


def geometry_of(config: dict, name: str | None = None) -> Geometry:
    """The thruster geometry of a scenario's validated ``config``: ``name`` if given, else its
    ``thrusters.layout``, else its controller's ``bound_geometry`` (the gimbal for a Lyapunov law (Katz) or a
    zone NSSK manipulator (Ye), the per-axis pairs for Katz's discrete law, the arms for Li's planners).  ``axes``
    takes its shares from the discrete law's thresholds (sigma / u0), or 1 each for another controller."""
    name = name or config["thrusters"].get("layout")
    controller = config["controller"]
    discrete = controller["kind"] == "lyapunov" and controller.get("thrust_mode") == "discrete"
    if name is None:
        from geojax.control import lookup

        name = lookup(config["controller"]["kind"]).make([config["controller"]]).spec.bound_geometry
    if name not in GEOMETRIES:
        raise ValueError(f"bound.thrusters: must be one of {', '.join(GEOMETRIES)}, got {name!r}")
    if name == "arms":
        t = config["thrusters"]
        return arms(*(math.radians(float(t[k])) for k in ("beta_max_deg", "beta_min_deg", "alpha_max_deg",
                                                           "alpha_min_deg")))
    if name == "axes":
        shares = ([float(x) / float(controller["u0_km_per_s2"]) for x in controller["sigma_km_per_s2"]] if discrete
                  else (1.0, 1.0, 1.0))
        return axes(math.radians(float(config["station"]["lon_deg"])), shares)
    return gimbal() if name == "gimbal" else fixed4(float(config["thrusters"].get("cant_deg", 45.0)))
