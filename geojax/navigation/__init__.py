"""Orbit determination's pure pieces: ground stations, measurement models, tracking schedules, and the extended
Kalman filter the closed loop carries (its state, leaves, execution errors, time and measurement updates; the part
that rides the loop is ``geojax.states.navigation``).  Pure JAX functions, float64, SI (docs/navigation.md)."""
