"""What XLA compiles for geojax: the persistent compilation cache (on by default) and a record of every compilation.

Nearly all of a short run's wall time is XLA compiling its programs (the environment grid, the predictor's
reference run, the closed loop, the metrics); once compiled, a year of QFFC station keeping is well under a
second.  JAX can keep compiled programs on disk between processes (its *persistent compilation cache*): a
second run of the same program loads the executable instead of compiling it.  geojax turns that cache on when it
is imported, in a per-user folder:

* ``$GEOJAX_CACHE_DIR`` if set; else JAX's own ``$JAX_COMPILATION_CACHE_DIR`` (or ``jax_compilation_cache_dir``)
  if the user set one; else the platform's cache folder: ``$XDG_CACHE_HOME/geojax/jax`` or
  ``~/.cache/geojax/jax`` (Linux), ``~/Library/Caches/geojax/jax`` (macOS), ``%LOCALAPPDATA%\\geojax\\jax``
  (Windows);
* off with ``GEOJAX_NO_CACHE=1``, ``geojax --no-cache COMMAND ...`` or ``geojax.compilation.use_cache(False)``;
* at most ``$GEOJAX_CACHE_MAX_MB`` megabytes (default ``DEFAULT_MAX_MB``), the least recently used programs
  evicted first (JAX's LRU cache; it needs the ``filelock`` package, a dependency).

The cache is keyed by JAX itself: a hash of the compiled program's HLO, the compile options, the devices and the
JAX/jaxlib versions, so a changed program, flag or version is a miss, never a wrong hit, and a hit is the same
executable (results are bit-for-bit those of a fresh compilation: ``tests/test_compilation.py``).  A folder that
cannot be used (not writable, a file in its place) gives one warning line and the run goes on uncached; an entry
that cannot be read (a truncated or overwritten file) is a miss that mends itself: it is removed, its program
compiled and kept anew, and the process says so once (``_mend_unreadable_entries``: JAX alone would warn twice
per entry and run after run, since it never overwrites one).  Every program is kept, the ~40 small eager
operations a command compiles too (``MIN_COMPILE_S``).

``Compilations`` records what compiles while it is open (JAX's monitoring events): per program its name, the
seconds spent tracing, lowering and compiling (or loading from the cache), and whether the cache served it; the
command line reports from it and ``benchmarks/startup.py`` measures with it.
"""

from __future__ import annotations

import functools
import os
import sys
import tempfile
import threading
import warnings
from pathlib import Path
from typing import NamedTuple

import jax

ENV_DIR, ENV_OFF, ENV_MAX_MB = "GEOJAX_CACHE_DIR", "GEOJAX_NO_CACHE", "GEOJAX_CACHE_MAX_MB"
DEFAULT_MAX_MB = 2048  # a year's closed loop is a few MB of executable: hundreds of programs
MIN_COMPILE_S = 0.0  # every program (JAX's default, 1 s, would leave the environment grid and the ~40 eager
#                      operations a command compiles, 2-3 s in all, to compile again in every run)


# XLA's options for a single sample's programs (``simulate``: the closed loop, its metrics, the predictor's reference
# and the file's uncontrolled run, compiled for one sample): such a program runs a year in about a second once
# compiled, and its compilation is the wait.  XLA's classic CPU emitters compiled the one-sample QFFC closed loop (a
# year, RK4 stages in a loop) in 5.4-6.6 s against 8.6-8.9 s with its fusion emitters, the default (3 tries each, 2
# idle cores, by hand); the reference, its segments in turn, in 1.8 s against 3.7 s.  LLVM unoptimized (level 0)
# for all of them then took the cold one-year ``geojax simulate li2022-qffc`` from 12.3, 11.4 and 10.5 s to 10.1,
# 9.5 and 8.9 s (LLVM's default level 2 and level 0 alternated, 2 idle cores, by hand): the compiling saved
# outweighs the slower run (the year's loop took 0.7-0.9 s instead of 0.6-0.7 s; a single sample's run time is
# the loop's overhead, a few small kernels per step, not arithmetic).  A controller whose cycle is arithmetic
# (an interior-point solve) raises its closed loop's level (``Sizing.one_sample_opt_level``).  A batch keeps
# XLA's defaults: its run time is what counts there, and its numbers must not move (the classic emitters move the last
# bit; across three runs they ran the 128-lane loop from 21 % faster to 13 % slower, level 0 3.4-3.8x slower,
# ``benchmarks/results/compile_profile.md``).
ONE_SAMPLE_OPTIONS = {"xla_cpu_use_fusion_emitters": False, "xla_backend_optimization_level": 0}


def default_dir() -> Path:
    """The platform's per-user cache folder for geojax's compiled programs."""
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "geojax" / "jax"


def use_cache(path: str | os.PathLike | bool | None = None, max_mb: float | None = None) -> Path | None:
    """Turn the persistent compilation cache on at ``path`` (None: the folder the environment names, else
    ``default_dir()``), or off (``False``).  Returns the folder in use, or None when the cache is off.

    A folder that cannot be created or written gives one warning line on stderr and leaves the cache off.
    """
    if path is False:
        _set_dir(None)
        return None
    folder = Path(path) if path not in (None, True) else configured_dir()
    problem = _unusable(folder)
    if problem:
        print(f"geojax: warning: compilation cache {folder}: {problem}; running without it", file=sys.stderr)
        _set_dir(None)
        return None
    max_mb = float(os.environ.get(ENV_MAX_MB, DEFAULT_MAX_MB)) if max_mb is None else max_mb
    jax.config.update("jax_compilation_cache_max_size", int(max_mb * 2**20) if max_mb >= 0 else -1)
    if "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS" not in os.environ:  # the user's setting wins
        jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_S)
    _set_dir(folder)
    _mend_unreadable_entries()
    return folder


def configured_dir() -> Path:
    """The folder the environment asks for: ``$GEOJAX_CACHE_DIR``, else JAX's own setting, else ``default_dir()``."""
    named = os.environ.get(ENV_DIR) or jax.config.jax_compilation_cache_dir
    return Path(named) if named else default_dir()


def use_default() -> Path | None:
    """What ``import geojax`` does: the cache on in ``configured_dir()``, unless ``$GEOJAX_NO_CACHE`` is set."""
    if os.environ.get(ENV_OFF, "").strip() not in ("", "0"):
        return use_cache(False)
    return use_cache()


def cache_dir() -> Path | None:
    """The cache folder in use, None when the cache is off."""
    named = jax.config.jax_compilation_cache_dir
    return Path(named) if named and jax.config.jax_enable_compilation_cache else None


def _set_dir(folder: Path | None) -> None:
    from jax._src import compilation_cache  # the cache is opened once per process: re-open it after a change

    jax.config.update("jax_enable_compilation_cache", folder is not None)
    jax.config.update("jax_compilation_cache_dir", None if folder is None else str(folder))
    compilation_cache.reset_cache()


# JAX's words when it cannot read an entry (``jax._src.compiler``); geojax says it once instead
_JAX_READ_WARNING = "Error reading persistent compilation cache entry"


def _mend_unreadable_entries() -> None:
    """Make an unreadable cache entry a miss that mends itself: JAX's reading of an entry
    (``jax._src.compilation_cache.get_executable_and_time``, private) wrapped so that an entry that fails is
    removed before JAX compiles its program (JAX then keeps the new executable: it never overwrites an entry, so
    a corrupt one would otherwise fail in every later run too), with one warning line per process in place of
    JAX's two per entry.  Installed once; on a JAX without that function nothing changes (JAX warns as before)."""
    from jax._src import compilation_cache as jax_cache

    read = getattr(jax_cache, "get_executable_and_time", None)
    if read is None or getattr(read, "mends_unreadable", False):
        return
    said, saying = [], threading.Lock()  # one line per process, whichever compiling thread meets an entry first

    @functools.wraps(read)
    def mending(cache_key, *args, **kwargs):
        try:
            return read(cache_key, *args, **kwargs)
        except Exception as err:
            folder = cache_dir()
            if folder is not None and not isinstance(err, getattr(jax_cache, "CacheVerificationError", ())):
                for suffix in ("-cache", "-atime"):  # ``jax._src.lru_cache``'s entry and its access time
                    try:
                        (folder / f"{cache_key}{suffix}").unlink(missing_ok=True)
                    except OSError:
                        pass  # left as it is: a miss again next run, as JAX alone would have it
                with saying:
                    first, said[:] = not said, [True]
                if first:
                    why = f"{type(err).__name__}: {err}"
                    print(f"geojax: warning: compilation cache {folder}: an entry could not be read "
                          f"({why[:80]}); it and any other such entry are compiled again and replaced",
                          file=sys.stderr)
            raise  # JAX counts it a miss, compiles and keeps the program

    mending.mends_unreadable = True
    jax_cache.get_executable_and_time = mending
    warnings.filterwarnings("ignore", message=_JAX_READ_WARNING, category=UserWarning)


def _unusable(folder: Path) -> str:
    """Why ``folder`` cannot hold the cache ("" if it can): created if missing, a file written and removed."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".probe-"):
            pass
    except OSError as err:
        return err.strerror or type(err).__name__
    return ""


class Program(NamedTuple):
    """One compilation: JAX's name of the function, and where its seconds went."""

    name: str  # e.g. "_batched" (the closed loop), "reference", "_environment_grid"
    trace_s: float  # Python tracing to a jaxpr
    lower_s: float  # jaxpr to StableHLO
    compile_s: float  # XLA compiling, or loading the executable from the cache when ``cached``
    cached: bool  # the persistent cache served it


_TRACE, _LOWER, _COMPILE = ("/jax/core/compile/jaxpr_trace_duration", "/jax/core/compile/jaxpr_to_mlir_module_duration",
                            "/jax/core/compile/backend_compile_duration")
_HIT = "/jax/compilation_cache/cache_hits"


class Compilations:
    """``with Compilations() as log: ...``: ``log.programs`` lists every program compiled inside (``Program``).

    A program is counted when XLA's compilation (or the cache's load) ends; its tracing and lowering are the
    latest ones of the same function name before it.  Eager operations that compile in under ``min_s`` are
    left out of ``programs`` (their time is in ``other_s``).
    """

    def __init__(self, min_s: float = 0.05):
        self.min_s = min_s
        self.programs: list[Program] = []
        self.other_s = 0.0
        self._pending: dict[str, dict[str, float]] = {}
        self._hit: set[int] = set()  # the threads whose compilation in progress the cache served (programs compile
        #                              in threads of their own: ``rollout.simulate_batch``, ``parallel.per_device``)

    def __enter__(self):
        jax.monitoring.register_event_duration_secs_listener(self._duration)
        jax.monitoring.register_event_listener(self._event)
        return self

    def __exit__(self, *exc):
        jax.monitoring.unregister_event_duration_listener(self._duration)
        jax.monitoring.unregister_event_listener(self._event)
        return False

    def _event(self, event: str, **kwargs) -> None:
        if event == _HIT:
            self._hit.add(threading.get_ident())

    def _duration(self, event: str, seconds: float, fun_name: str = "", **kwargs) -> None:
        name = fun_name.removeprefix("jit(").removesuffix(")")
        if event in (_TRACE, _LOWER):
            self._pending.setdefault(name, {})[event] = seconds
        elif event == _COMPILE:
            parts = self._pending.pop(name, {})
            hit = threading.get_ident() in self._hit
            self._hit.discard(threading.get_ident())
            program = Program(name, parts.get(_TRACE, 0.0), parts.get(_LOWER, 0.0), seconds, hit)
            if program.trace_s + program.lower_s + program.compile_s >= self.min_s:
                self.programs.append(program)
            else:
                self.other_s += program.trace_s + program.lower_s + program.compile_s

    def total_s(self) -> float:
        """Seconds of tracing, lowering and compiling (or loading) of every program recorded, eager ones included."""
        return self.other_s + sum(p.trace_s + p.lower_s + p.compile_s for p in self.programs)

    def compiled(self) -> list[Program]:
        """The programs XLA compiled (the cache did not serve)."""
        return [p for p in self.programs if not p.cached]

    def made(self) -> str:
        """How the programs recorded so far were made ready, for a progress line: "compiled", "loaded from the
        cache", "compiled 2 and loaded 5 from the cache", or "made ready" where none was recorded (this process
        had them already)."""
        fresh, cached = len(self.compiled()), sum(p.cached for p in self.programs)
        if fresh and cached:
            return f"compiled {fresh} and loaded {cached} from the cache"
        return "compiled" if fresh else "loaded from the cache" if cached else "made ready"

    def summary(self) -> str:
        """One line: how many programs XLA compiled and in how long, how many the cache served."""
        fresh, cached = self.compiled(), [p for p in self.programs if p.cached]
        parts = []
        if fresh:
            parts.append(f"compiled {len(fresh)} program{'s' * (len(fresh) != 1)} in "
                         f"{sum(p.compile_s for p in fresh):.1f} s")
        if cached:
            parts.append(f"loaded {len(cached)} from the cache in {sum(p.compile_s for p in cached):.1f} s")
        traced = sum(p.trace_s + p.lower_s for p in self.programs)
        return ", ".join(parts or ["nothing compiled"]) + f" (tracing and lowering {traced:.1f} s)"


def waiting_note() -> str:
    """What a command says while it compiles: why it waits, and what the next run will do."""
    folder = cache_dir()
    if folder is None:
        return "the compilation cache is off: every run compiles afresh"
    return (f"a program's first run compiles it (a minute or more on a CPU; XLA may print 'Very slow compile?', "
            f"which is expected here, not a fault); later runs load it from the cache in {folder}")
