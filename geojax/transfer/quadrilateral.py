"""The traditional quadrilateral layout of Ma & Kong 2023 (Sec. 4.1, "the traditional quadrilateral layout in
fixed direction", their ref. [9]): four thrusters fixed on the body, fired in pairs.

Geometry (a marked choice; the paper gives none).  The four thrusters sit on one face, north-east, north-west,
south-east and south-west of its centre, as in the layout of Ma & Kong's ref. [9] (Gazzino et al. 2019) and
geojax's ``gazzino2016`` scenario (``bound.directions.fixed4``), each pointing through the centre of mass and
canted by ``cant`` from the face's north-south axis t, towards its east-west axis l.  In the (t, l) frame the
unit thrust of each is

    NE = ( cos c,  sin c),  NW = ( cos c, -sin c),  SE = (-cos c,  sin c),  SW = (-cos c, -sin c).

A pair that fires together with the two thrusters' lateral parts cancelling delivers, per unit of the pair's
total thrust (the mean of the two unit vectors):

    north (NE + NW): +t cos c     south (SE + SW): -t cos c
    east  (NE + SE): +l sin c     west  (NW + SW): -l sin c

so the cosine loss of the north/south pairs is 1 - cos c (23.4 % at 40 deg, 29.3 % at 45 deg) and the mass
flow is that of the two thrusters, F / (Isp g0).  The cant: a GEO quadrilateral trades north-south efficiency
(cos c) against east-west authority (sin c) and plume impingement on the arrays.  The layout's usual source
is the HS 702 xenon-ion quadrilateral with its diagonal pairs through the centre of mass (Anzel,
"Stationkeeping the Hughes HS 702 satellite with a xenon ion propulsion system", IAF-98-A.1.09, 1998, the
configuration the SK literature cited by Gazzino takes as typical); the sources at hand here do not print
its cant.  Our default is 45 deg (a marked choice, ``thruster.cant_deg``), the symmetric quadrilateral whose
north/south and east/west pairs have the same authority, as geojax's ``gazzino2016`` flies it; the map in
``studies/ma2023/transfer.py`` sweeps 0-50 deg.  Beyond 45 deg the east/west pairs are the stronger
(sin c > cos c): the body then rolls 90 deg and uses them, so the layout's best pair delivers
max(cos c, sin c) and a cant c and its complement 90 deg - c fly alike.

In a transfer (``rollout``) the body points the strong pairs' axis t along the wish, or against it when that
is the nearer slew, and the pair whose resultant lies closest to the wish fires: forward and backward
burns are a change of pair, not a half-turn of the body.
"""

from __future__ import annotations

import jax.numpy as jnp


def thruster_units(cant_rad):
    """The four thrusters' unit thrusts [4, 2] in the (t, l) frame, in the order NE, NW, SE, SW."""
    c, s = jnp.cos(cant_rad), jnp.sin(cant_rad)
    return jnp.array([[c, s], [c, -s], [-c, s], [-c, -s]])


def pair_axis_efficiency(cant_rad):
    """Resultant per unit pair thrust [4] of the pairs whose resultants lie along +t', -t', +l', -l', where t' is
    the strong pairs' axis (t when cos c >= sin c, else l): (eta_strong, eta_strong, eta_weak, eta_weak) with
    eta_strong = max(cos c, sin c) (the module docstring's resultants, the body rolled onto the stronger)."""
    c, s = jnp.abs(jnp.cos(cant_rad)), jnp.abs(jnp.sin(cant_rad))
    strong, weak = jnp.maximum(c, s), jnp.minimum(c, s)
    return jnp.stack([strong, strong, weak, weak])


def best_pair(strong_axis, weak_axis, wish, efficiency):
    """The pair that delivers most thrust along the unit ``wish`` [3]: the candidates are +-``strong_axis`` and
    +-``weak_axis`` (unit vectors [3]) with ``efficiency`` [4] (``pair_axis_efficiency``; a zero entry is a pair
    the layout lacks).  Returns (index, the resultant per unit thrust [3]: the pair's axis times its
    efficiency, so its norm is the pair's resultant fraction)."""
    axes = jnp.stack([strong_axis, -strong_axis, weak_axis, -weak_axis])
    along = efficiency * (axes @ wish)
    index = jnp.argmax(along)
    return index, efficiency[index] * axes[index]
