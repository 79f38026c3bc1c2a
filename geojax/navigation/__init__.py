"""Orbit determination: ground stations, measurement models, tracking schedules and the extended
Kalman filter's pure pieces.  Pure JAX functions, float64, SI; not yet part of the closed loop
(docs/navigation.md)."""
