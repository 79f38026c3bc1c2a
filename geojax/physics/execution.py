"""The burns' execution errors, the one model of the truth: each of a cycle's two burns is flown with a thrust-level
error and a pointing error (yaw and pitch of its thrust angles), drawn once per cycle from the cycle's key, with
the 3-sigma sizes of the scenario's ``[errors]`` table (Li 2022 eqs. (47)-(48); docs/closed-loop.md, "Errors").
A navigation filter knows their statistics (its own keys), never the draws: it reads the truth back from the
planned and the flown thrust (``truth_of``) as the point its prediction is expanded about."""

from __future__ import annotations

import jax
import jax.numpy as jnp

# ``fold_in`` constant of the magnitude errors' draw from the cycle's key (the FOMPC's search takes 1; the parts
# their own named streams, ``states.base.stream_id``); the pointing errors are row 1 of ``normal(key, (2, 6))``
# (row 0: the Gaussian fix, ``navigation.fix``).
MAGNITUDE_KEY = 2


def magnitude_scale(errors, key):
    """The thrust level [2] each of a cycle's two burns flies, over the planned: 1 + e with e ~ N(0, (sigma3 /
    3)^2), ``errors["sigma3_dv_frac"]`` the 3-sigma fraction (exactly 1 at 0)."""
    draws = jax.random.normal(jax.random.fold_in(key, MAGNITUDE_KEY), (2,))
    return 1.0 + errors["sigma3_dv_frac"] / 3 * draws


def attitude_error_rad(errors, key):
    """The yaw (row 0) and pitch (row 1) errors [2, 2] of a cycle's two burns (columns), rad: 1-sigma
    ``errors["sigma3_att_deg"]`` / 3 (Li 2022 eq. (47); eq. (48)'s nominal times H_att where H_att states it),
    an axis ``errors.att_axes`` leaves out scaled by 0 (its leaf: the [2] scales), burn 1's draw used for both
    when ``att_shared``."""
    sigma_att_rad = jnp.deg2rad(errors["sigma3_att_deg"] / 3)
    draws = jax.random.normal(key, (2, 6))[1, :4].reshape(2, 2)
    draws = jnp.where(errors["att_shared"] > 0, draws[:, :1], draws)
    return sigma_att_rad * errors["att_axes"][:, None] * draws


def executed(direction_rsw, thrust_n, eps, phi):
    """(direction [3], thrust N) of a planned thrust flown with magnitude error ``eps`` and pointing error ``phi``
    [3] (a small rotation vector): (d + phi x d) with d's length, (1 + eps) F.  Smooth at phi = 0 and at d = 0 (no
    burn).  The navigation filter's model of a burn (its prediction and its Jacobian)."""
    turned = direction_rsw + jnp.cross(phi, direction_rsw)
    size, turned_size = jnp.linalg.norm(direction_rsw), jnp.linalg.norm(turned)
    scale = jnp.where(turned_size > 0, size / jnp.where(turned_size > 0, turned_size, 1.0), 1.0)
    return turned * scale, (1.0 + eps) * thrust_n


def truth_of(planned_rsw, planned_n, flown_rsw, flown_n):
    """(eps, phi [3]) with ``executed(planned_rsw, planned_n, eps, phi) == (flown_rsw, flown_n)``: eps = F'/F - 1 and
    phi = (d x d') / (d . d'), the rotation perpendicular to d that turns d onto d' (exact for directions of one
    length; d + phi x d = d' / (d . d')).  0 where nothing is planned."""
    dot = jnp.dot(planned_rsw, flown_rsw)
    safe = jnp.where(dot > 0, dot, 1.0)
    phi = jnp.where(dot > 0, jnp.cross(planned_rsw, flown_rsw) / safe, 0.0)
    eps = jnp.where(planned_n > 0, flown_n / jnp.where(planned_n > 0, planned_n, 1.0) - 1.0, 0.0)
    return eps, phi
