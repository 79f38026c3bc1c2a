"""The filter's covariance at a burn's start, where its estimate of the burn's execution errors (eps, phi) restarts
from the prior it assumes (``reset_execution``); the errors' model: ``geojax.physics.execution``, docs/navigation.md."""

from __future__ import annotations

import jax.numpy as jnp

from geojax.navigation.state import N_STATE


def execution_prior(magnitude_sigma, pointing_sigma_rad, planned_rsw):
    """[4, 4] the prior covariance of a burn's (eps, phi) along the planned direction d (RSW): eps ~ N(0,
    magnitude_sigma^2), and the pointing error as the truth's model has it (``physics.execution``: yaw and pitch
    errors of sigma added to the direction's angles alpha, beta), a rotation phi with d + phi x d the flown
    direction: sigma^2 about the pitch axis, (sigma cos beta)^2 about the yaw axis (a turn of alpha moves d by
    cos beta of it), and sigma^2 about d itself (a roll, which moves nothing)."""
    size = jnp.linalg.norm(planned_rsw)
    d = jnp.where(size > 0, planned_rsw / jnp.where(size > 0, size, 1.0), jnp.array([1.0, 0.0, 0.0]))
    horizontal = jnp.cross(jnp.array([0.0, 0.0, 1.0]), d)  # along d's change with alpha (R-S plane)
    h_size = jnp.linalg.norm(horizontal)
    u_alpha = jnp.where(h_size > 1e-12, horizontal / jnp.where(h_size > 1e-12, h_size, 1.0), jnp.array([0.0, 1.0, 0.0]))
    yaw_axis = jnp.cross(d, u_alpha)  # a rotation about it moves d along u_alpha
    cos2_beta = 1.0 - d[2] ** 2
    phi = pointing_sigma_rad**2 * (jnp.eye(3) - (1.0 - cos2_beta) * jnp.outer(yaw_axis, yaw_axis))
    return jnp.zeros((4, 4)).at[0, 0].set(magnitude_sigma**2).at[1:, 1:].set(phi)


def reset_execution(p, prior):
    """P at a burn's start: the execution errors' rows and columns replaced by their prior ``prior`` [4, 4]
    (``execution_prior``), uncorrelated with the orbit and the biases (the last burn's errors marginalised out), the
    rest kept."""
    n_b = p.shape[0] - N_STATE
    kept = jnp.zeros_like(p).at[:6, :6].set(p[:6, :6]).at[6:N_STATE, 6:N_STATE].set(prior)
    if n_b:
        kept = kept.at[:6, N_STATE:].set(p[:6, N_STATE:]).at[N_STATE:, :6].set(p[N_STATE:, :6])
        kept = kept.at[N_STATE:, N_STATE:].set(p[N_STATE:, N_STATE:])
    return kept
