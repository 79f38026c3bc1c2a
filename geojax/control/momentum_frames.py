"""The frames of the momentum MPC (``control.mpc_momentum``): RSW at a state, the nadir body's axes in RSW, a basis
across a thrust line, and vectors given at a burn turned to the RSW axes of the cycle's start."""

import jax.numpy as jnp


def rsw_basis(r_eci_m, v_eci_mps):
    """Rows R, S, W [3, 3] of the RSW frame at (r, v) in ECI."""
    radial = r_eci_m / jnp.linalg.norm(r_eci_m)
    normal = jnp.cross(r_eci_m, v_eci_mps)
    normal = normal / jnp.linalg.norm(normal)
    return jnp.stack([radial, jnp.cross(normal, radial), normal])


def body_to_rsw(h_body):
    """A vector in the nadir body's axes (x = S, y = -W, z = -R, ``physics.attitude.nadir_frame``) in RSW."""
    return jnp.stack([-h_body[2], h_body[0], -h_body[1]])


def across_basis(lines):
    """[2, 2, 3] two unit vectors across each line of ``lines`` [2, 3], (e_1, e_2, u) right-handed: e_1 across
    the line from the axis least along it."""
    axes = jnp.eye(3)[jnp.argmin(jnp.abs(lines), axis=-1)]
    e1 = jnp.cross(lines, axes)
    e1 = e1 / jnp.linalg.norm(e1, axis=-1, keepdims=True)
    e2 = jnp.cross(lines, e1)
    return jnp.stack([e1, e2], 1)


def rotate_to_start(vectors_rsw, past_rad):
    """Vectors [..., 3] given in the RSW axes at right ascensions ``past_rad`` [...] past the cycle's start, in
    the RSW axes of the start (a turn about W)."""
    c, s = jnp.cos(past_rad), jnp.sin(past_rad)
    r, t, n = vectors_rsw[..., 0], vectors_rsw[..., 1], vectors_rsw[..., 2]
    return jnp.stack([c * r - s * t, s * r + c * t, n], -1)
