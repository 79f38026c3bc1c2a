"""A minimal progress bar for long runs: drawn on stderr only when it is a terminal."""

from __future__ import annotations

import sys
import time


class Progress:
    """``with Progress(total, "cycles") as bar: bar.update(n)``."""

    def __init__(self, total: int, unit: str, stream=None, enabled: bool | None = None):
        self.total, self.unit = total, unit
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.done = 0
        self.start = time.perf_counter()

    def __enter__(self):
        return self

    def update(self, n: int) -> None:
        self.done = min(self.total, self.done + n)
        if not self.enabled:
            return
        elapsed = time.perf_counter() - self.start
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("nan")
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        self.stream.write(
            f"\r[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} {self.unit}"
            f"  {rate:.1f} {self.unit}/s  ETA {eta:.0f} s "
        )
        self.stream.flush()

    def __exit__(self, *exc):
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()
        return False
