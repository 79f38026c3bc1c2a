"""The burns' execution errors: a planned thrust flown with a magnitude error eps and a pointing error phi
(``executed``), and the filter's covariance at a burn's start, where its (eps, phi) restart from their prior
(``reset_execution``).  Why the errors are modelled so: docs/navigation.md."""

from __future__ import annotations

import jax.numpy as jnp

from geojax.navigation.state import N_STATE


def executed(direction_rsw, thrust_n, eps, phi):
    """(direction [3], thrust N) of a planned thrust flown with magnitude error ``eps`` and pointing error ``phi``
    [3]: (d + phi x d) with d's length, (1 + eps) F.  Smooth at phi = 0 and at d = 0 (no burn)."""
    turned = direction_rsw + jnp.cross(phi, direction_rsw)
    size, turned_size = jnp.linalg.norm(direction_rsw), jnp.linalg.norm(turned)
    scale = jnp.where(turned_size > 0, size / jnp.where(turned_size > 0, turned_size, 1.0), 1.0)
    return turned * scale, (1.0 + eps) * thrust_n


def reset_execution(p, sigma):
    """P at a burn's start: the execution errors' rows and columns replaced by their prior diag(``sigma``^2),
    uncorrelated with the orbit and the biases (the last burn's errors marginalised out), the rest kept."""
    n_b = p.shape[0] - N_STATE
    kept = jnp.zeros_like(p).at[:6, :6].set(p[:6, :6]).at[6:N_STATE, 6:N_STATE].set(jnp.diag(sigma**2))
    if n_b:
        kept = kept.at[:6, N_STATE:].set(p[:6, N_STATE:]).at[N_STATE:, :6].set(p[N_STATE:, :6])
        kept = kept.at[N_STATE:, N_STATE:].set(p[N_STATE:, N_STATE:])
    return kept
