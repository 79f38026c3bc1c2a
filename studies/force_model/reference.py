"""An independent evaluation of the Earth's field and an independent orbit integrator, in NumPy/SciPy.

The field is the gradient of the potential in spherical coordinates,
U = GM/r sum_n (R/r)^n sum_m Pbar_nm(sin phi) (C_nm cos m lambda + S_nm sin m lambda), with the fully
normalised Legendre functions by the standard forward-column recursion (Holmes & Featherstone, J. Geodesy 76
(2002), eqs. (11)-(13)) and dPbar_nm/dphi = N_nm/N_n,m+1 Pbar_n,m+1 - m tan(phi) Pbar_nm: a different method
from geojax's Pines formulation in Cartesian terms (``geojax.physics.geopotential``).

The integrator is SciPy's DOP853 on the Cartesian equations of motion at a tight tolerance, with the same Sun
and Moon as geojax (its Meeus series, sampled hourly and interpolated by cubic splines), the same Earth
angle, and solar radiation pressure with the conical Earth shadow written here again (Montenbruck & Gill
2000, Sec. 3.4.2).  ``tests/test_geopotential.py`` and ``studies/force_model/propagation_check.py`` use it.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline

AU_M = 1.495978707e11
R_SUN_M = 6.957e8


def legendre_and_derivative(degree, phi):
    """Pbar_nm(sin phi) and dPbar_nm/dphi, [degree + 2, degree + 2] (Holmes & Featherstone 2002, eqs. (11)-(13))."""
    t, u = math.sin(phi), math.cos(phi)
    size = degree + 2
    p = np.zeros((size, size))
    p[0, 0] = 1.0
    p[1, 1] = math.sqrt(3) * u
    for m in range(2, size):
        p[m, m] = u * math.sqrt((2 * m + 1) / (2 * m)) * p[m - 1, m - 1]
    for m in range(size):
        for n in range(m + 1, size):
            a = math.sqrt((2 * n - 1) * (2 * n + 1) / ((n - m) * (n + m)))
            b = math.sqrt((2 * n + 1) * (n + m - 1) * (n - m - 1) / ((n - m) * (n + m) * (2 * n - 3))) if n > m + 1 else 0.0
            p[n, m] = a * t * p[n - 1, m] - (b * p[n - 2, m] if n > m + 1 else 0.0)
    dp = np.zeros_like(p)
    for n in range(size - 1):
        for m in range(n + 1):
            factor = math.sqrt((n - m) * (n + m + 1) / (2 if m == 0 else 1))
            dp[n, m] = factor * (p[n, m + 1] if m + 1 <= n else 0.0) - m * math.tan(phi) * p[n, m]
    return p, dp


def field_acceleration_ecef(r, degree, order, c_nm, s_nm, mu, radius):
    """Earth-fixed acceleration (m/s^2) of the degrees 2..``degree`` (orders <= ``order``) at Earth-fixed ``r`` (m)."""
    x, y, z = r
    rr = math.sqrt(x * x + y * y + z * z)
    phi, lam = math.asin(z / rr), math.atan2(y, x)
    p, dp = legendre_and_derivative(degree, phi)
    du_dr = du_dphi = du_dlam = 0.0
    for n in range(2, degree + 1):
        scale = mu / rr * (radius / rr) ** n
        for m in range(min(n, order) + 1):
            cos_m, sin_m = math.cos(m * lam), math.sin(m * lam)
            harmonic = c_nm[n, m] * cos_m + s_nm[n, m] * sin_m
            du_dr -= (n + 1) / rr * scale * p[n, m] * harmonic
            du_dphi += scale * dp[n, m] * harmonic
            du_dlam += scale * m * p[n, m] * (s_nm[n, m] * cos_m - c_nm[n, m] * sin_m)
    r_hat = np.array([math.cos(phi) * math.cos(lam), math.cos(phi) * math.sin(lam), math.sin(phi)])
    phi_hat = np.array([-math.sin(phi) * math.cos(lam), -math.sin(phi) * math.sin(lam), math.cos(phi)])
    lam_hat = np.array([-math.sin(lam), math.cos(lam), 0.0])
    return du_dr * r_hat + du_dphi / rr * phi_hat + du_dlam / (rr * math.cos(phi)) * lam_hat


def sunlit_fraction(r, sun, r_earth_m):
    """Visible fraction of the solar disc behind the Earth (two overlapping discs; M&G Sec. 3.4.2)."""
    to_sun = sun - r
    d_sun, d = np.linalg.norm(to_sun), np.linalg.norm(r)
    a, b = math.asin(R_SUN_M / d_sun), math.asin(r_earth_m / d)
    c = math.acos(np.clip(-np.dot(r, to_sun) / (d * d_sun), -1.0, 1.0))
    if c >= a + b:
        return 1.0
    if c <= b - a:
        return 0.0
    x = (c * c + a * a - b * b) / (2 * c)
    y = math.sqrt(max(a * a - x * x, 0.0))
    area = a * a * math.acos(x / a) + b * b * math.acos((c - x) / b) - c * y
    return 1.0 - area / (math.pi * a * a)


class Ephemeris:
    """geojax's Sun, Moon (ECI) and Earth angle over [0, span_s] from ``epoch_tt_s``, sampled every hour and
    interpolated by cubic splines."""

    def __init__(self, epoch_tt_s, tt_minus_ut1_s, span_s):
        from geojax.physics.propagate import environment_at

        t = np.arange(0.0, span_s + 7200.0, 3600.0)
        env = environment_at(epoch_tt_s + t, epoch_tt_s, tt_minus_ut1_s)
        self.sun = CubicSpline(t, np.asarray(env.r_sun_eci_m))
        self.moon = CubicSpline(t, np.asarray(env.r_moon_eci_m))
        self.angle = CubicSpline(t, np.unwrap(np.asarray(env.earth_angle_rad)))


def cartesian_rhs(forces, ephemeris: Ephemeris, mass_kg):
    """d(r, v)/dt of the Cartesian state (m, m/s) at ``t`` s from the epoch; ``forces``: a dict of mu, r_earth_m,
    c_nm, s_nm, degree, order, mu_sun, mu_moon, srp (P (1 + eta) A at 1 AU, N) and shadow (bool)."""
    f = forces

    def rhs(t, state):
        r, v = state[:3], state[3:]
        angle = float(ephemeris.angle(t))
        ca, sa = math.cos(angle), math.sin(angle)
        r_ecef = np.array([ca * r[0] + sa * r[1], -sa * r[0] + ca * r[1], r[2]])
        a_e = field_acceleration_ecef(r_ecef, f["degree"], f["order"], f["c_nm"], f["s_nm"], f["mu"], f["r_earth_m"])
        accel = -f["mu"] * r / np.linalg.norm(r) ** 3 + np.array(
            [ca * a_e[0] - sa * a_e[1], sa * a_e[0] + ca * a_e[1], a_e[2]])
        sun, moon = ephemeris.sun(t), ephemeris.moon(t)
        for body, mu_body in ((sun, f["mu_sun"]), (moon, f["mu_moon"])):
            d = body - r
            accel += mu_body * (d / np.linalg.norm(d) ** 3 - body / np.linalg.norm(body) ** 3)
        if f["srp"]:
            light = sunlit_fraction(r, sun, f["r_earth_m"]) if f["shadow"] else 1.0
            d = sun - r
            accel -= light * f["srp"] / mass_kg * AU_M**2 / np.linalg.norm(d) ** 3 * d
        return np.concatenate([v, accel])

    return rhs


def integrate(rhs, state0, times_s, rtol=1e-12, atol_m=1e-6):
    """States [len(times_s), 6] by DOP853 at the given tolerance (``atol_m`` on positions, per second on velocities)."""
    atol = np.array([atol_m] * 3 + [atol_m * 1e-4] * 3)
    sol = solve_ivp(rhs, (times_s[0], times_s[-1]), state0, method="DOP853", t_eval=times_s, rtol=rtol, atol=atol)
    assert sol.success, sol.message
    return sol.y.T
