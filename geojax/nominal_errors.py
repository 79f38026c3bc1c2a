"""Li 2022's nominal 3-sigma errors (eq. (48)), the unit of its H multipliers (``errors.h_rv``, ``errors.h_att``):
one place for the scenario's keys, the loop's Gaussian fix and the burns' attitude error."""

NOMINAL_3SIGMA_R_M = 0.3  # orbit determination, per position component
NOMINAL_3SIGMA_V_MPS = 5e-5  # orbit determination, per velocity component
NOMINAL_3SIGMA_ATT_DEG = 0.05  # attitude (yaw and pitch) of a burn
