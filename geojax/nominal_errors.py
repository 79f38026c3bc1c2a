"""The errors' sizes, stated once: each error of the ``[errors]`` table has one canonical 3-sigma key
(``sigma3_r_m``, ``sigma3_v_mps``, ``sigma3_att_deg``, ``sigma3_dv_pct``) and at most one preset, Li 2022's H
multiplier of its nominal 3-sigma errors (eq. (48): ``h_rv``, ``h_att``), converted here and nowhere else.  The
loop's Gaussian fix (``navigation.fix``), the burns' execution errors (``physics.execution``) and a filter's
priors (``navigation.keys``) read what this module makes of the table."""

from __future__ import annotations

import math

NOMINAL_3SIGMA_R_M = 0.3  # orbit determination, per position component
NOMINAL_3SIGMA_V_MPS = 5e-5  # orbit determination, per velocity component
NOMINAL_3SIGMA_ATT_DEG = 0.05  # attitude (yaw and pitch) of a burn

# Each canonical key: (its preset, the preset's unit size, the unit for messages).
PRESETS = {
    "sigma3_r_m": ("h_rv", NOMINAL_3SIGMA_R_M, "m"),
    "sigma3_v_mps": ("h_rv", NOMINAL_3SIGMA_V_MPS, "m/s"),
    "sigma3_att_deg": ("h_att", NOMINAL_3SIGMA_ATT_DEG, "deg"),
}
# ``errors.att_axes``: the axes the attitude error enters (Li's eq. (47) reads both; the ablation one at a time).
AXES = {"yaw_pitch": (1.0, 1.0), "yaw": (1.0, 0.0), "pitch": (0.0, 1.0)}


def sigma3(errors: dict) -> dict:
    """{canonical key: its 3-sigma size} of a validated ``[errors]`` table: the key where given, else its preset's
    H x Li's nominal (exactly the product the loop formed from H before: the same numbers bit for bit), 0 without
    either.  ``ValueError`` naming both where a key and its preset are given and disagree (1e-9 relative)."""
    out = {}
    for key, (preset, nominal, unit) in PRESETS.items():
        h, given = errors[preset], errors[key]
        implied = h * nominal
        if given is not None and h and not math.isclose(given, implied, rel_tol=1e-9, abs_tol=0.0):
            raise ValueError(f"errors.{key}: {given:g} {unit} contradicts errors.{preset} = {h:g} x the nominal "
                             f"{nominal:g} {unit} (Li 2022 eq. (48)) = {implied:g} {unit}; give one of them")
        out[key] = float(implied if given is None else given)
    return out


def leaves(errors: dict) -> dict:
    """The SI leaves of the sizes the loop reads beside the table's own (``sigma3``; ``att_axes`` as the [2]
    yaw, pitch scales)."""
    import jax.numpy as jnp

    return {**{k: jnp.asarray(v) for k, v in sigma3(errors).items()}, "att_axes": jnp.asarray(AXES[errors["att_axes"]])}
