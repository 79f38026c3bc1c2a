"""The filter's covariance at a burn's start, where its estimate of the burn's execution errors (eps, phi) restarts
from the prior it assumes (``reset_execution``); the errors' model: ``geojax.physics.execution``, docs/navigation.md."""

from __future__ import annotations

import jax.numpy as jnp

from geojax.navigation.state import N_STATE


def reset_execution(p, sigma):
    """P at a burn's start: the execution errors' rows and columns replaced by their prior diag(``sigma``^2),
    uncorrelated with the orbit and the biases (the last burn's errors marginalised out), the rest kept."""
    n_b = p.shape[0] - N_STATE
    kept = jnp.zeros_like(p).at[:6, :6].set(p[:6, :6]).at[6:N_STATE, 6:N_STATE].set(jnp.diag(sigma**2))
    if n_b:
        kept = kept.at[:6, N_STATE:].set(p[:6, N_STATE:]).at[N_STATE:, :6].set(p[N_STATE:, :6])
        kept = kept.at[N_STATE:, N_STATE:].set(p[N_STATE:, N_STATE:])
    return kept
