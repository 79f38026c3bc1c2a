"""The Earth's field to degree and order N: EGM2008 coefficients and a normalised Cunningham recursion.

The acceleration of the degrees 2..N (the central term is ``forces.point_mass_xyz``) is evaluated in the
Earth-fixed frame R_z(Earth angle) ECI that ``forces.c22_s22_xyz`` uses, by the recursion of Cunningham
(1970) in the form of Montenbruck & Gill, *Satellite Orbits* (2000), Sec. 3.2.4-3.2.5, eqs. (3.30)-(3.33),
carried out on normalised terms V_nm N_nm, W_nm N_nm, N_nm = sqrt((2 - delta_m0)(2n + 1)(n - m)! / (n + m)!),
so that every number stays O((R/r)^(n+1)) and multiplies the normalised C_nm, S_nm directly (the role
of Holmes & Featherstone's 2002 scaling; to degree 20 nothing comes near an overflow or a cancellation).
The recursion is non-singular at the poles and uses only x, y, z, r^-2: no trigonometric function.

Static structure, traced values: the degree and order are the shape of the coefficient arrays, so the
recursion's form is fixed at trace time (unrolled term by term to degree 12, a ``lax.scan`` over degrees
beyond: ``geopotential_ecef_xyz``); the coefficients are array leaves that a sweep can vary and a gradient
reach.  The constants of the recursion are exact ratios of factorials computed in Python once per shape.

EGM2008 (Pavlis et al., J. Geophys. Res. 117 (2012) B04406), tide-free, to degree 20, ships as
``data/egm2008_n20.txt`` (written by ``data/make_egm2008.py``).  Its reference GM = 3.986004415e14 m^3/s^2
differs from the IERS value the engine uses (``constants.MU_EARTH_M3_S2``) by 7.5e-10 relative; the field
is scaled by the engine's mu, which moves the harmonic terms by that fraction (at GEO below 1e-14 m/s^2).
"""

from __future__ import annotations

import functools
import importlib.resources
import math
from fractions import Fraction
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

MAX_DEGREE = 20  # the shipped table (data/egm2008_n20.txt)
UNROLLED_MAX_DEGREE = 12  # see geopotential_ecef_xyz


class Geopotential(NamedTuple):
    """Normalised spherical-harmonic coefficients, indexed [n, m]: degree 0..N, order 0..M (M <= N).

    Rows n = 0 and 1 are ignored (the central term and the origin at the centre of mass are elsewhere);
    entries with m > n are zero.  N and M are the shape: static for the compiled step.
    """

    c_nm: jnp.ndarray  # [N + 1, M + 1]
    s_nm: jnp.ndarray  # [N + 1, M + 1]

    @property
    def degree(self) -> int:
        return self.c_nm.shape[-2] - 1

    @property
    def order(self) -> int:
        return self.c_nm.shape[-1] - 1


def egm2008(degree: int, order: int | None = None) -> Geopotential:
    """EGM2008 (tide-free) truncated to ``degree`` and ``order`` (default: ``degree``), as NumPy arrays."""
    order = degree if order is None else order
    if not 2 <= degree <= MAX_DEGREE or not 0 <= order <= degree:
        raise ValueError(f"EGM2008 ships to degree {MAX_DEGREE}: need 2 <= degree <= {MAX_DEGREE} and "
                         f"0 <= order <= degree, got degree {degree}, order {order}")
    c_nm, s_nm = _egm2008_table()
    return Geopotential(c_nm[:degree + 1, :order + 1].copy(), s_nm[:degree + 1, :order + 1].copy())


@functools.lru_cache(maxsize=1)
def _egm2008_table():
    text = (importlib.resources.files("geojax") / "physics" / "data" / f"egm2008_n{MAX_DEGREE}.txt").read_text()
    rows = np.loadtxt(text.splitlines(), comments="#")
    c_nm, s_nm = np.zeros((2, MAX_DEGREE + 1, MAX_DEGREE + 1))
    n, m = rows[:, 0].astype(int), rows[:, 1].astype(int)
    c_nm[n, m], s_nm[n, m] = rows[:, 2], rows[:, 3]
    return c_nm, s_nm


def geopotential_xyz(x, y, z, cos_angle, sin_angle, mu, r_earth_m, field: Geopotential):
    """ECI acceleration (m/s^2) of the degrees 2..N of ``field`` at ECI (x, y, z) (m), as components.

    ``cos_angle``, ``sin_angle``: of the Earth rotation angle (ECI x axis to Greenwich).
    """
    xe, ye = cos_angle * x + sin_angle * y, -sin_angle * x + cos_angle * y
    ae, an, az = geopotential_ecef_xyz(xe, ye, z, mu, r_earth_m, field)
    return cos_angle * ae - sin_angle * an, sin_angle * ae + cos_angle * an, az


def geopotential_ecef_xyz(x, y, z, mu, r_earth_m, field: Geopotential):
    """Earth-fixed acceleration of the degrees 2..N at Earth-fixed (x, y, z): M&G eqs. (3.30)-(3.33), normalised.

    Two evaluations of the same recursion, chosen by the degree (static).  To ``UNROLLED_MAX_DEGREE`` the
    terms are unrolled one by one and XLA fuses them into a few kernels over the lanes.  Beyond, one
    ``lax.scan`` step per degree: unrolled, the two-term recursion is a graph whose paths grow as about 1.6^N,
    and XLA's CPU compilation grew with it (alone, the field at degree 16 ran out of 20 GB while compiling).
    Measured in the MEE step at batch 1024, one core, both forms in one process, fastest of 10 (ns per
    right-hand side per sample, compile s; the J2 + C22/S22 step beside it, the machine shared): degree 10
    unrolled 336 (27.5 s) against the scan's 1866 (14.0 s), step 102; degree 12: 438 (37.4 s) against 2503
    (9.2 s), step 65; degree 14: 507 (70.6 s, 0.85 GB) against 3125 (15.4 s), step 94.  The unrolled form
    stops at 12, where its compilation is still under a minute.
    """
    if field.degree <= UNROLLED_MAX_DEGREE:
        return _unrolled(x, y, z, mu, r_earth_m, field)
    return _scanned(x, y, z, mu, r_earth_m, field)


def _unrolled(x, y, z, mu, r_earth_m, field: Geopotential):
    """The recursion term by term (degree and order static): V[j][i], W[j][i] for j <= N + 1, i <= min(j, M + 1)."""
    degree, order = field.degree, field.order
    k = _constants(degree, order)
    t = _tables(field, k)
    inv_r2 = 1.0 / (x * x + y * y + z * z)
    rho = r_earth_m * inv_r2
    xr, yr, zr, rr = x * rho, y * rho, z * rho, r_earth_m * rho
    # W_j0 = 0 is left out (None).
    v, w = [[r_earth_m * jnp.sqrt(inv_r2)]], [[None]]
    acc = [0.0, 0.0, 0.0]
    for j in range(1, degree + 2):
        vj, wj = [], []
        for i in range(min(j, order + 1) + 1):
            if i == j:  # sectoral, eq. (3.30)
                a, vp, wp = k.sectoral[j - 1, 0], v[j - 1][j - 1], w[j - 1][j - 1]
                vj.append(a * (xr * vp - (0.0 if wp is None else yr * wp)))
                wj.append(a * (yr * vp + (0.0 if wp is None else xr * wp)))
                continue
            a, b = k.a[j - 1, i], k.b[j - 1, i]
            vj.append(a * zr * v[j - 1][i] - (b * rr * v[j - 2][i] if b else 0.0))
            wj.append(None if i == 0 else a * zr * w[j - 1][i] - (b * rr * w[j - 2][i] if b else 0.0))
        v.append(vj), w.append(wj)
        if j >= 3:  # eq. (3.33): this row's share
            for axis in range(3):
                for i, (vji, wji) in enumerate(zip(vj, wj)):
                    acc[axis] = acc[axis] + t.weights_v[axis][j - 1, i] * vji
                    if wji is not None:
                        acc[axis] = acc[axis] + t.weights_w[axis][j - 1, i] * wji
    scale = mu / (r_earth_m * r_earth_m)
    return tuple(scale * a for a in acc)


def _scanned(x, y, z, mu, r_earth_m, field: Geopotential):
    """The recursion by degree: one ``lax.scan`` step per degree j = 1..N + 1 carries the rows V_j., W_j. over
    the orders 0..M + 1 (eq. (3.31); the sectoral term of eq. (3.30) is kept beside the rows so that no step
    indexes by j) and adds the row's share of eq. (3.33) to per-order sums."""
    tables = _tables(field, _constants(field.degree, field.order))
    inv_r2 = 1.0 / (x * x + y * y + z * z)
    rho = r_earth_m * inv_r2
    xr, yr, zr, rr = x * rho, y * rho, z * rho, r_earth_m * rho
    v00 = r_earth_m * jnp.sqrt(inv_r2)
    first = (jnp.arange(field.order + 2) == 0)
    row0 = jnp.where(first, v00[..., None], 0.0)  # V_0. = (R/r, 0, ...), W_0. = 0
    zeros = jnp.zeros_like(row0)
    xr, yr, zr, rr = (q[..., None] for q in (xr, yr, zr, rr))

    def degree_step(carry, t):
        (v1, w1, v2, w2, vs, ws, acc) = carry  # rows j - 1 and j - 2; the sectoral V, W of row j - 1
        vs, ws = t.sectoral * (xr * vs - yr * ws), t.sectoral * (yr * vs + xr * ws)
        v = t.a * zr * v1 - t.b * rr * v2 + t.onehot * vs
        w = t.a * zr * w1 - t.b * rr * w2 + t.onehot * ws
        acc = tuple(a + wv * v + ww * w for a, wv, ww in zip(acc, t.weights_v, t.weights_w))
        return (v, w, v1, w1, vs, ws, acc), None

    carry = (row0, zeros, zeros, zeros, v00[..., None], zeros[..., :1], (zeros, zeros, zeros))
    (*_, acc), _ = jax.lax.scan(degree_step, carry, tables)
    scale = mu / (r_earth_m * r_earth_m)
    return tuple(scale * jnp.sum(a, axis=-1) for a in acc)


class _Constants(NamedTuple):
    """Per degree j = 1..N + 1 (leading axis) and order i = 0..M + 1 (trailing axis), M&G eqs. (3.30)-(3.31)
    in normalised terms (V_ji N_ji), and the multipliers of C_nm, S_nm in eq. (3.33)."""

    a: np.ndarray  # [J, P] (2j - 1)/(j - i) N_ji/N_{j-1,i} for i < j, else 0
    b: np.ndarray  # [J, P] (j + i - 1)/(j - i) N_ji/N_{j-2,i} for i <= j - 2, else 0
    sectoral: np.ndarray  # [J, 1] (2j - 1) N_jj/N_{j-1,j-1} for j <= M + 1, else 0
    onehot: np.ndarray  # [J, P] 1 at i = j (j <= M + 1)
    # [N + 1, M + 1], index [n, m]: the multipliers of C_nm, S_nm, read at the (j, i) of the V, W they multiply.
    plus: np.ndarray  # (n, m) -> (n + 1, m + 1): N_nm / N_{n+1,m+1} (times 1/2 for m > 0)
    minus: np.ndarray  # (n, m) -> (n + 1, m - 1): (n - m + 2)(n - m + 1) / 2 N_nm / N_{n+1,m-1}, m > 0
    same: np.ndarray  # (n, m) -> (n + 1, m): (n - m + 1) N_nm / N_{n+1,m}


class _Tables(NamedTuple):
    """What ``lax.scan`` reads per degree (leading axis j = 1..N + 1)."""

    a: jnp.ndarray
    b: jnp.ndarray
    sectoral: jnp.ndarray
    onehot: jnp.ndarray
    weights_v: tuple  # x, y, z multipliers of V_j. [J, P] each
    weights_w: tuple  # x, y, z multipliers of W_j. [J, P] each


def _norm2(n: int, m: int) -> Fraction:
    """N_nm^2 = (2 - delta_m0)(2n + 1)(n - m)! / (n + m)!, exactly."""
    return Fraction((1 if m == 0 else 2) * (2 * n + 1) * math.factorial(n - m), math.factorial(n + m))


def _ratio(n1, m1, n2, m2) -> float:
    """N_{n1 m1} / N_{n2 m2}."""
    return math.sqrt(_norm2(n1, m1) / _norm2(n2, m2))


@functools.lru_cache(maxsize=None)
def _constants(degree: int, order: int) -> _Constants:
    rows, width = degree + 1, order + 2
    a, b, onehot = np.zeros((3, rows, width))
    sectoral = np.zeros((rows, 1))
    for j in range(1, degree + 2):
        if j <= order + 1:
            sectoral[j - 1, 0] = (2 * j - 1) * _ratio(j, j, j - 1, j - 1)
            onehot[j - 1, j] = 1.0
        for i in range(min(j - 1, order + 1) + 1):
            a[j - 1, i] = (2 * j - 1) / (j - i) * _ratio(j, i, j - 1, i)
            if i <= j - 2:
                b[j - 1, i] = (j + i - 1) / (j - i) * _ratio(j, i, j - 2, i)
    plus, minus, same = np.zeros((3, degree + 1, order + 1))
    for n in range(2, degree + 1):
        for m in range(min(n, order) + 1):
            plus[n, m] = _ratio(n, m, n + 1, m + 1) * (1.0 if m == 0 else 0.5)
            if m > 0:
                minus[n, m] = 0.5 * (n - m + 2) * (n - m + 1) * _ratio(n, m, n + 1, m - 1)
            same[n, m] = (n - m + 1) * _ratio(n, m, n + 1, m)
    return _Constants(a, b, sectoral, onehot, plus, minus, same)


def _tables(field: Geopotential, k: _Constants) -> _Tables:
    """The scan's per-degree inputs; the multipliers of eq. (3.33) per axis, for m >= 0:

    x: -C V_{n+1,m+1} - S W_{n+1,m+1} (halved for m > 0) + (n-m+2)!/(n-m)!/2 (C V_{n+1,m-1} + S W_{n+1,m-1})
    y: -C W_{n+1,m+1} + S V_{n+1,m+1} (halved for m > 0) + (n-m+2)!/(n-m)!/2 (-C W_{n+1,m-1} + S V_{n+1,m-1})
    z: (n - m + 1)(-C V_{n+1,m} - S W_{n+1,m})
    (the S V_{n+1,1} term of m = 0 vanishes with S_n0 = 0), placed at the row j = n + 1 and order i of the
    V, W they multiply.  Batch-invariant work on [N + 1, M + 2] values (degrees 0 and 1 get zeros).
    """
    c, s = jnp.asarray(field.c_nm), jnp.asarray(field.s_nm)
    cp, sp, cm, sm, cz, sz = c * k.plus, s * k.plus, c * k.minus, s * k.minus, c * k.same, s * k.same

    def placed(values, di):
        """[n, m] -> row j - 1 = n (j = n + 1), order i = m + di, in an [N + 1, M + 2] array (i < 0 dropped)."""
        out = jnp.zeros(values.shape[:-1] + (values.shape[-1] + 1,), values.dtype)
        if di >= 0:
            return out.at[..., di:di + values.shape[-1]].set(values)
        return out.at[..., :values.shape[-1] - 1].set(values[..., 1:])

    weights_v = (placed(-cp, 1) + placed(cm, -1), placed(sp, 1) + placed(sm, -1), placed(-cz, 0))
    weights_w = (placed(-sp, 1) + placed(sm, -1), placed(-cp, 1) + placed(-cm, -1), placed(-sz, 0))
    return _Tables(k.a, k.b, k.sectoral, k.onehot, weights_v, weights_w)


def geopotential_acceleration(r_eci, earth_angle_rad, mu, r_earth_m, field: Geopotential):
    """``geopotential_xyz`` on a position [..., 3] (m); returns [..., 3] (m/s^2)."""
    angle = jnp.asarray(earth_angle_rad)
    ax, ay, az = geopotential_xyz(r_eci[..., 0], r_eci[..., 1], r_eci[..., 2], jnp.cos(angle), jnp.sin(angle),
                                  mu, r_earth_m, field)
    return jnp.stack(jnp.broadcast_arrays(ax, ay, az), -1)


def longitude_acceleration_rad_s2(lon_rad, radius_m, mu, r_earth_m, field: Geopotential):
    """d^2(lambda)/dt^2 of a circular equatorial orbit of ``radius_m`` at Earth-fixed longitude ``lon_rad`` from
    the field alone: -3 a_east / radius (with da/dt = 2 a_T / n and d(lambda)/dt = n - omega_E, d^2(lambda)/dt^2
    = -3/2 n/a da/dt; e.g. Soop, *Handbook of Geostationary Orbits* (1994), Sec. 3.4).  Its zeros are the
    equilibrium longitudes: stable where it decreases through zero."""
    lon = jnp.asarray(lon_rad)
    cos_lon, sin_lon = jnp.cos(lon), jnp.sin(lon)
    ax, ay, _ = geopotential_ecef_xyz(radius_m * cos_lon, radius_m * sin_lon, jnp.zeros_like(lon), mu, r_earth_m, field)
    return -3.0 * (-sin_lon * ax + cos_lon * ay) / radius_m
