"""geojax: closed-loop GEO station keeping in JAX."""
import jax

jax.config.update("jax_enable_x64", True)

__version__ = "0.1.0"
