"""Traced programs kept between runs: what JAX's compilation cache cannot skip.

JAX's persistent cache (``geojax.compilation``) keeps the *compiled* executable, but finds it by the program's
StableHLO, so every run still traces the Python code to a program and lowers it before it can look: for the
closed loop and the predictor's reference run, 5-8 s of a warm run on 2 cores.  ``call`` keeps the lowered program
itself (``jax.export``: serialized StableHLO, a few MB) beside the compiled ones, and a later run that asks for
the same program calls it from the file: no tracing, no lowering, and the executable from JAX's cache.

A program is found again only by what fixes it: a digest of geojax's own source files, the JAX and jaxlib
versions, the platform, the program's name and its caller's ``identity`` (the static settings that choose the
code: controller kind and its static keys, step, dynamics, lanes), and the tree, shapes and dtypes of its
arguments.  A changed source file, version or setting is a miss, never a wrong hit.  A controller from outside
the package (its code is not in the digest) is never kept: its caller passes ``identity=None``.  A file that
cannot be read or written is a miss (the program is traced as usual).  The results are bit-for-bit those of the
jitted function (``tests/test_compilation.py``).
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from pathlib import Path

import jax
from jax import export

from geojax.compilation import cache_dir

SUFFIX = "-geojax-traced"  # beside JAX's "-cache" entries, which its LRU eviction alone manages
MAX_FILES = 64  # the traced programs kept (the oldest removed first); a few MB each


def call(jitted, name: str, identity, *args, compiler_options: dict | None = None, **static):
    """``jitted(*args, **static)``; its traced program kept in the cache folder when ``identity`` is not None
    (and compiled with XLA's ``compiler_options``, those ``jitted`` was made with)."""
    program = _program(jitted, name, identity, args, static, compiler_options)
    return jitted(*args, **static) if program is None else program(*args)


def compiled(jitted, name: str, identity, *args, **static):
    """``jitted`` compiled for ``args`` ahead of its call (to time the compilation apart): a callable of ``args``."""
    return lowered(jitted, name, identity, *args, **static).compile()


def lowered(jitted, name: str, identity, *args, **static):
    """``jitted`` lowered for ``args`` (arrays or their ``jax.ShapeDtypeStruct``): ``.compile()`` and ``.out_info``
    (the results' shapes)."""
    program = _program(jitted, name, identity, args, static)
    return jitted.lower(*args, **static) if program is None else program.lower(*args)


def jitted(jitted, name: str, identity, *args):
    """A jitted callable with ``jitted``'s results for arguments shaped as ``args`` (no static arguments): the kept
    traced program's when ``identity`` is not None and the cache is on, else ``jitted`` itself.  Either has
    ``.lower(...)`` (``geojax.parallel.per_device`` compiles it once per device)."""
    program = _program(jitted, name, identity, args, {})
    return jitted if program is None else program


def kept(name: str, identity, *args) -> bool:
    """Whether the traced program ``name`` of ``identity`` for arguments shaped as ``args`` is kept (loaded in this
    process or in the cache folder): what a later call would find without tracing it."""
    folder = cache_dir()
    if folder is None or identity is None:
        return False
    key = _key(name, identity, args)
    return key in _IN_PROCESS or (folder / f"{key}{SUFFIX}").is_file()


_IN_PROCESS: dict[str, object] = {}  # key -> jitted call of the loaded program (one lowering per process)


def _program(jitted, name: str, identity, args, static, compiler_options: dict | None = None):
    """The jitted call of the kept program of ``jitted`` for ``args`` (loaded, or traced and kept now); None when
    the cache is off or ``identity`` is None."""
    folder = cache_dir()
    if folder is None or identity is None:
        return None
    _register(args)
    key = _key(name, identity, args)
    if key not in _IN_PROCESS:
        path = folder / f"{key}{SUFFIX}"
        program = _load(path)
        if program is None:
            program = export.export(jitted)(*args, **static)
            _save(path, program)

        def run(*values):
            return program.call(*values)

        run.__name__ = run.__qualname__ = name  # JAX names the compiled program after it (geojax.compilation)
        _IN_PROCESS[key] = jax.jit(run, compiler_options=compiler_options)
    return _IN_PROCESS[key]


def _key(name: str, identity, args) -> str:
    leaves, tree = jax.tree_util.tree_flatten(args)
    avals = [(tuple(x.shape), str(x.dtype), bool(getattr(x, "weak_type", False))) for x in leaves]
    parts = (_source_digest(), jax.__version__, jax.lib.__version__, jax.default_backend(), name, repr(identity),
             str(tree), repr(avals), jax.config.jax_enable_x64)
    return hashlib.sha256(repr(parts).encode()).hexdigest()


@functools.cache
def _source_digest() -> str:
    """A digest of every Python file of the package (the code a traced program was made from)."""
    digest = hashlib.sha256()
    root = Path(__file__).resolve().parent
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _load(path: Path):
    try:
        blob = path.read_bytes()
    except OSError:
        return None
    try:
        classes, _, data = blob.partition(b"\n")
        for qualified in filter(None, classes.decode().split(",")):
            _register_class(qualified)
        program = export.deserialize(bytearray(data))
        os.utime(path)  # recently used: kept longest
        return program
    except Exception:  # noqa: BLE001  (an unreadable entry is a miss, never an error)
        return None


def _save(path: Path, program) -> None:
    """Write ``program`` (after the NamedTuple classes of its outputs, which reading it needs registered first)."""
    classes = sorted(_namedtuples(jax.tree_util.tree_unflatten(program.out_tree, [0] * program.out_tree.num_leaves)))
    for qualified in classes:
        _register_class(qualified)
    try:
        data = program.serialize()
        with tempfile.NamedTemporaryFile(dir=path.parent, delete=False, prefix=".traced-") as out:
            out.write(",".join(classes).encode() + b"\n" + bytes(data))
        os.replace(out.name, path)
        kept = sorted(path.parent.glob(f"*{SUFFIX}"), key=lambda p: p.stat().st_mtime)
        for old in kept[:-MAX_FILES]:
            old.unlink(missing_ok=True)
    except Exception:  # noqa: BLE001  (a cache that cannot be written costs a trace next time, nothing else)
        pass


def _register(args) -> None:
    for qualified in _namedtuples(args):
        _register_class(qualified)


def _namedtuples(tree) -> set[str]:
    """``module:qualname`` of every NamedTuple class in ``tree`` (containers: tuples, lists, dicts)."""
    found = set()
    if isinstance(tree, tuple) and hasattr(tree, "_fields"):
        found.add(f"{type(tree).__module__}:{type(tree).__qualname__}")
    if isinstance(tree, (tuple, list)):
        for item in tree:
            found |= _namedtuples(item)
    elif isinstance(tree, dict):
        for item in tree.values():
            found |= _namedtuples(item)
    return found


@functools.cache
def _register_class(qualified: str) -> None:
    import importlib

    module, _, name = qualified.partition(":")
    cls = importlib.import_module(module)
    for part in name.split("."):
        cls = getattr(cls, part)
    try:
        export.register_namedtuple_serialization(cls, serialized_name=qualified)
    except ValueError:  # registered already (by another caller)
        pass
