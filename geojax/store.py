"""HDF5 results (DESIGN.md, "Contracts").

Every file carries the attributes ``geojax_version``, ``config_toml``,
``created_utc``, ``wall_s`` and ``device``.  Files are written to a temporary
name in the same folder and renamed, so a reader never sees a half-written file.
"""

from __future__ import annotations

import datetime as _dt
import os
from pathlib import Path

import h5py
import jax
import numpy as np

import geojax


def device_description() -> str:
    devices = jax.devices()
    return f"{len(devices)} x {devices[0].platform}:{devices[0].device_kind}"


def write_h5(path: str | Path, groups: dict[str, dict[str, np.ndarray]], config_toml: str, wall_s: float, attrs=None) -> Path:
    """Write ``{group: {name: array}}`` and the standard attributes to ``path`` atomically."""
    path = Path(path)
    if path.parent and not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        with h5py.File(tmp, "w") as f:
            f.attrs["geojax_version"] = geojax.__version__
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


def check_output_file(path: str | Path) -> Path:
    """``ValueError`` unless ``path`` can be written as a results file: not a folder, its parent a folder or
    creatable.  Checked before a run starts."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"--out {str(path)!r}: is a folder; give a file name")
    parent = path.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise ValueError(f"--out {str(path)!r}: {str(parent)!r} is not a folder")
    if not os.access(parent, os.W_OK):
        raise ValueError(f"--out {str(path)!r}: {str(parent)!r} is not writable")
    return path
