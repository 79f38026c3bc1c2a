"""The extended Kalman filter's state in the loop: what it carries (``Navigation``), its per-cycle record
(``NavigationCycle``) and the static layout that fixes their shapes (``Layout``).  The part that carries it:
``geojax.states.navigation``; the filter's design: docs/navigation.md."""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

N_STATE = 10  # the elements, eps, phi [3]; then the measurement biases where they are estimated (``n_estimated``)


class Layout(NamedTuple):
    """What fixes the filter's compiled shape (static): each station's measurement types, the receiver, the
    prediction model."""

    stations: tuple[tuple[str, ...], ...]
    gnss: bool
    filter_forces: str
    biases: bool = False  # the measurement biases estimated (``navigation.estimate_biases``)


class Navigation(NamedTuple):
    """The carried state."""

    x: jnp.ndarray  # [6] the estimate: ECI position (m) and velocity (m/s)
    execution: jnp.ndarray  # [4] the estimate of the current burn's (eps, phi rad)
    p: jnp.ndarray  # [10, 10] the covariance of (r m, v m/s, eps, phi), r and v ECI
    key: jnp.ndarray  # the cycle's key (``cycle``), its draws folded from it
    step_index: jnp.ndarray  # [] int, steps since the cycle start
    bias: jnp.ndarray  # [n_components] the sample's measurement biases (drawn at cycle 0)
    truth_execution: jnp.ndarray  # [4] the current burn's true (eps, phi)
    firing: jnp.ndarray  # [] bool, whether the latest step fired
    planned_direction_rsw: jnp.ndarray  # [3] the thrust planned over the current step (``thrust``)
    planned_thrust_n: jnp.ndarray  # []
    planned_on_fraction: jnp.ndarray  # []
    isp_s: jnp.ndarray  # []
    error_rsw: jnp.ndarray  # [6] estimate - truth at the cycle start, RSW (m, m/s)
    sigma_rsw: jnp.ndarray  # [6] the filter's 1-sigma there, RSW (m, m/s)
    nees: jnp.ndarray  # [] at the cycle start
    nis_sum: jnp.ndarray  # [] over the cycle so far
    nis_dof: jnp.ndarray  # [] degrees of freedom of those NIS
    measurements: jnp.ndarray  # [] measurement components used over the cycle so far
    # where the biases are estimated (``Layout.biases``), else None (no leaves: the filter is today's, bit for bit)
    bias_estimate: jnp.ndarray | None = None  # [n_components]
    bias_error: jnp.ndarray | None = None  # [n_components] bias_estimate - bias at the cycle start
    bias_sigma: jnp.ndarray | None = None  # [n_components] the filter's 1-sigma of it there


class NavigationCycle(NamedTuple):
    """Per cycle (always kept)."""

    error_rsw: jnp.ndarray  # [6] at the cycle start
    sigma_rsw: jnp.ndarray  # [6]
    nees: jnp.ndarray  # []
    nis_sum: jnp.ndarray  # [] over the cycle
    nis_dof: jnp.ndarray  # []
    measurements: jnp.ndarray  # []
    bias_error: jnp.ndarray | None = None  # [n_components] the biases' estimation error at the cycle start, where
    bias_sigma: jnp.ndarray | None = None  # [n_components] estimated (else None), and the filter's 1-sigma of it


def n_estimated(state: Navigation) -> int:
    """The biases ``state`` estimates (static: its shape)."""
    return 0 if state.bias_estimate is None else state.bias_estimate.shape[0]
