"""The git commit of a checkout (standard library only: ``setup.py`` loads this file at build time, before
geojax's dependencies exist)."""

from __future__ import annotations

import subprocess
from pathlib import Path


def revision(root: Path) -> str | None:
    """``git rev-parse HEAD`` of ``root`` (``+dirty`` with uncommitted changes), or None outside a checkout."""
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return (head + ("+dirty" if dirty else "")) if head else None
