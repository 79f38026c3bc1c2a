"""Reference implementations of the geojax force model used by ``benchmarks/propagate.py``.

``numpy_model``: plain NumPy accelerations for ``scipy.integrate.solve_ivp``.
``heyoka_model``: the same dynamics as a heyoka ODE system.
"""
