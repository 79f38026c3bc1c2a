"""A measurement in a fresh Python process: its own compilation, its own peak memory, its own devices."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from harness import devices as _devices


def run_json(args: list[str], devices: _devices.Devices = _devices.Devices(), cwd: Path | None = None,
             pythonpath: Path | None = None, env: dict | None = None):
    """Run ``python ARGS`` on ``devices`` (its ``XLA_FLAGS``, platform and cores) and return the JSON of the
    last line it prints.  ``pythonpath``: the tree whose ``geojax`` it imports (default: as inherited).
    ``env``: the child's environment before ``devices`` is applied (default: this process's)."""
    env = _devices.environment(devices, env)
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    cores = devices.cores
    # A child inherits its parent's cores: pin it apart only where they differ (a function run between fork
    # and exec, which a parent running JAX's threads warns about).
    repin = cores is not None and tuple(sorted(cores)) != _devices.usable_cores()
    out = subprocess.run([sys.executable, *args], check=True, stdout=subprocess.PIPE, text=True, env=env, cwd=cwd,
                         preexec_fn=(lambda: _devices.pin(cores)) if repin else None).stdout
    return json.loads(out.strip().splitlines()[-1])
