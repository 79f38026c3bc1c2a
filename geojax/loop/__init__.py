"""The engine: one closed loop (``simulate``) for every controller and every part the loop carries, its records,
metrics and status (``metrics``); pure JAX, no file, no figure (the runner, ``geojax.runner``, writes them)."""
