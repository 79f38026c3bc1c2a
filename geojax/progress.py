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
        self.note = ""  # shown after the ETA (a cluster's workers alive)
        self._resumed = 0  # done before the last restart: counted, not in the rate
        self.start = time.perf_counter()

    def skip(self, n: int) -> None:
        """Count ``n`` done earlier (a resumed run's saved work): shown, never in the rate."""
        self.done = min(self.total, self.done + n)
        self.restart()

    def restart(self, note: str = "") -> None:
        """Start the rate and ETA afresh from here (after a compilation, which says nothing of the rate)."""
        self._resumed, self.start = self.done, time.perf_counter()
        self.note = note or self.note
        self.update(0)

    def __enter__(self):
        return self

    def update(self, n: int) -> None:
        self.done = min(self.total, self.done + n)
        if not self.enabled:
            return
        elapsed = time.perf_counter() - self.start
        rate = (self.done - self._resumed) / elapsed if elapsed > 0 else 0.0
        eta = f"{(self.total - self.done) / rate:.0f} s" if rate > 0 else "--"
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        self.stream.write(
            f"\r[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} {self.unit}"
            f"  {rate:.1f} {self.unit}/s  ETA {eta}" + (f"  {self.note} " if self.note else " ")
        )
        self.stream.flush()

    def __exit__(self, *exc):
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()
        return False
