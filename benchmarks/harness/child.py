"""A measurement in a fresh Python process: its own compilation, its own peak memory, its own devices."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from harness import devices as _devices


def run_json(args: list[str], devices: _devices.Devices = _devices.Devices(), cwd: Path | None = None,
             pythonpath: Path | None = None):
    """Run ``python ARGS`` on ``devices`` (its ``XLA_FLAGS``, platform and cores) and return the JSON of the
    last line it prints.  ``pythonpath``: the tree whose ``geojax`` it imports (default: as inherited)."""
    env = _devices.environment(devices)
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    cores = devices.cores
    out = subprocess.run([sys.executable, *args], check=True, stdout=subprocess.PIPE, text=True, env=env, cwd=cwd,
                         preexec_fn=(lambda: _devices.pin(cores)) if cores is not None else None).stdout
    return json.loads(out.strip().splitlines()[-1])
