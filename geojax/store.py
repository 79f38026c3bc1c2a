"""HDF5 results (docs/design.md, "Contracts").

Every file carries the attributes ``geojax_version``, ``jax_version``, ``jaxlib_version``,
``source_revision`` (the git commit of the source, ``+dirty`` with uncommitted changes: read from git in a
checkout, recorded at build time in an installed copy), ``config_toml``, ``created_utc``, ``wall_s`` and ``device``, and every dataset its units and
axis names (``geojax.results``).  Files are written to a temporary
name in the same folder (``.NAME.tmp-PID``) and renamed, so a reader never sees
a half-written file; folders are removed by renaming them first
(``.NAME.trash-PID``), so a kill never leaves half a folder under its name.
What a killed process left under those names is removed by the next write
beside it (``remove_stale``).
"""

from __future__ import annotations

import datetime as _dt
import glob
import os
import shutil
from pathlib import Path

import h5py
import jax
import numpy as np

import geojax


def device_description() -> str:
    devices = jax.devices()
    return f"{len(devices)} x {devices[0].platform}:{devices[0].device_kind}"


def source_revision() -> str:
    """The git commit geojax runs from (``+dirty`` with uncommitted changes): the checkout's, else the one
    ``setup.py`` recorded when this copy was built (``geojax/_revision.txt``), else "unknown"."""
    from geojax._git import revision

    root = Path(geojax.__file__).resolve().parent.parent
    if not (root / ".git").exists():
        recorded = Path(geojax.__file__).resolve().parent / "_revision.txt"
        return recorded.read_text().strip() if recorded.is_file() else "unknown"
    return revision(root) or "unknown"


def write_h5(path: str | Path, groups: dict[str, dict[str, np.ndarray]], config_toml: str, wall_s: float, attrs=None,
             dims: dict[str, tuple[str, ...]] | None = None) -> Path:
    """Write ``{group: {name: array}}`` and the standard attributes to ``path`` atomically.

    ``dims`` names the axes (``geojax.results.label_datasets``: {"GROUP" or "GROUP/NAME": leading axes}).
    """
    import jaxlib

    from geojax.results import label_datasets

    path = Path(path)
    if path.parent and not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(path)
    tmp = temporary(path)
    try:
        with h5py.File(tmp, "w") as f:
            f.attrs["geojax_version"] = geojax.__version__
            f.attrs["jax_version"] = jax.__version__
            f.attrs["jaxlib_version"] = jaxlib.__version__
            f.attrs["source_revision"] = source_revision()
            f.attrs["config_toml"] = config_toml
            f.attrs["created_utc"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")
            f.attrs["wall_s"] = float(wall_s)
            f.attrs["device"] = device_description()
            for key, value in (attrs or {}).items():
                f.attrs[key] = value
            for group, datasets in groups.items():
                g = f.require_group(group)
                for name, value in datasets.items():
                    g.create_dataset(name, data=np.asarray(value))
            label_datasets(f, dims or {})
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def read_h5(path: str | Path) -> tuple[dict[str, dict[str, np.ndarray]], dict]:
    """Read every dataset (``{group: {name: array}}``) and the file attributes."""
    groups: dict[str, dict[str, np.ndarray]] = {}
    with h5py.File(path, "r") as f:
        attrs = dict(f.attrs)
        for group_name, group in f.items():
            if isinstance(group, h5py.Group):
                groups[group_name] = {name: ds[()] for name, ds in group.items()}
    return groups, attrs


def check_output_file(path: str | Path, name: str = "out", replace: bool = True) -> Path:
    """``ValueError`` unless ``path`` can be written as a results file: not a folder, and a file can be created
    in its folder (or in the nearest folder above it that exists, where the folders are made as it is written).
    ``replace=False``: also refused if ``path`` exists (the command line's policy without ``--force``).
    Checked before a run starts; the error names the setting ``name``."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{name}={str(path)!r}: is a folder; give a file name")
    if not replace and path.exists():
        raise ValueError(f"{name}={str(path)!r}: exists; pass force=True to replace it or choose another file")
    _check_writable(path.parent, path.name, f"{name}={str(path)!r}")
    return path


def check_output_folder(path: str | Path, name: str = "plots") -> Path:
    """``ValueError`` unless ``path`` is a folder, or can be made one, in which files can be created."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ValueError(f"{name}={str(path)!r}: exists and is not a folder")
    _check_writable(path, "probe", f"{name}={str(path)!r}")
    return path


def _check_writable(folder: Path, stem: str, what: str) -> None:
    """Create and remove a temporary file (``temporary``'s name, so a kill leaves nothing ``remove_stale`` keeps)
    in ``folder`` or the nearest folder above it that exists: permissions alone do not say (root may write
    anywhere but /proc, a read-only mount)."""
    folder = folder.absolute()
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        raise ValueError(f"{what}: {str(folder)!r} is not a folder")
    probe = temporary(folder / stem)
    try:
        probe.open("w").close()
    except OSError as err:
        raise ValueError(f"{what}: cannot create a file in {str(folder)!r} ({err.strerror or err})") from None
    probe.unlink(missing_ok=True)


def temporary(path: Path, tag: str = "tmp") -> Path:
    """This process's temporary name for ``path``: ``.NAME.TAG-PID`` in the same folder."""
    return path.with_name(f".{path.name}.{tag}-{os.getpid()}")


def atomic_write(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole or not at all (temporary file, fsync, rename)."""
    tmp = temporary(path)
    try:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def discard_folder(path: Path) -> None:
    """Remove a folder so that a kill at any moment leaves it whole or gone: rename, then delete."""
    trash = temporary(path, "trash")
    os.replace(path, trash)
    shutil.rmtree(trash)


def remove_stale(path: Path) -> None:
    """Remove the temporaries (``.NAME.tmp-PID``, ``.NAME.trash-PID``) that killed processes left beside
    ``path``; those of a live process other than this one are left alone."""
    _remove_stale(path.parent, glob.escape(f".{path.name}.") + "*-*")


def remove_stale_in(folder: Path) -> None:
    """``remove_stale`` for every name in ``folder``."""
    _remove_stale(folder, ".*-*")


def _remove_stale(folder: Path, pattern: str) -> None:
    for stale in folder.glob(pattern):
        tag, _, pid = stale.name.rpartition("-")
        if tag.rpartition(".")[2] in ("tmp", "trash") and pid.isdigit() and not _other_live_process(int(pid)):
            shutil.rmtree(stale, ignore_errors=True) if stale.is_dir() else stale.unlink(missing_ok=True)


def _other_live_process(pid: int) -> bool:
    if pid == os.getpid():
        return False  # ours, from an earlier run in this process that was interrupted
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def read_attrs(path: str | Path, what: str = "resume") -> dict:
    """The attributes of a geojax results file; ``ValueError`` with one line if ``path`` is not one."""
    try:
        with h5py.File(path, "r") as f:
            attrs = dict(f.attrs)
    except OSError:
        raise ValueError(f"{what}: {str(path)!r} is not an HDF5 file; choose another output file") from None
    if "config_toml" not in attrs:
        raise ValueError(f"{what}: {str(path)!r} is not a geojax results file; choose another output file")
    return attrs
