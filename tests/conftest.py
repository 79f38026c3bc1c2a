"""Suite-wide set-up.

The tests that run ``geojax`` in subprocesses (kill -9 and resume, Ray workers, the command line) compile the
same programs again in every process.  One persistent compilation cache for the session (JAX's and geojax's
kept traced programs, ``geojax.compilation``), in a temporary folder removed at its end, never the user's, lets
each later process load them instead (a cache hit is the same executable, so
bit-for-bit comparisons are unaffected); it halves ``test_kill.py``.  The variables are set before JAX is
imported, and subprocesses inherit them.  The suite runs in two processes (``-n 2`` in ``pyproject.toml``),
each test file whole in one of them.
"""

import atexit
import os
import shutil
import tempfile

if "JAX_COMPILATION_CACHE_DIR" not in os.environ:
    _cache = tempfile.mkdtemp(prefix="geojax-test-jax-cache-")
    atexit.register(shutil.rmtree, _cache, ignore_errors=True)
    os.environ["JAX_COMPILATION_CACHE_DIR"] = _cache
    os.environ["GEOJAX_CACHE_DIR"] = _cache  # geojax's own cache (geojax.compilation): the session's, never the user's
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0")
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES", "0")

# Two test processes (pytest-xdist) share a GPU: neither may take three quarters of its memory up front.
os.environ.setdefault("XLA_PYTHON_CLIENT_PREALLOCATE", "false")

import geojax  # noqa: E402,F401  (turns on float64 before any test builds arrays)
