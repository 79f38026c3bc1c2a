"""Progress of long runs on stderr: a bar redrawn in place on a terminal, and plain lines, sparingly, when
stderr is a file or a pipe (a run whose output is redirected still says how far it is)."""

from __future__ import annotations

import sys
import time

# Lines off a terminal: one when a phase starts (set-up, compiling), then one each time both LINE_INTERVAL_S
# and LINE_FRACTION of the work have passed since the last (every 10 % or 30 s, whichever comes later), and
# the final count if any line was written.
LINE_INTERVAL_S = 30.0
LINE_FRACTION = 0.1


class Progress:
    """``with Progress(total, "cycles") as bar: bar.update(n)``.

    ``enabled``: False draws nothing; None or True draws a bar if ``stream`` (default stderr) is a terminal,
    else lines.  ``bar.phase("compiling")`` names what runs before the first unit is done (set-up,
    compilation), shown with its elapsed time instead of a rate until ``restart``.
    """

    def __init__(self, total: int, unit: str, stream=None, enabled: bool | None = None,
                 interval_s: float = LINE_INTERVAL_S, fraction: float = LINE_FRACTION):
        self.total, self.unit = total, unit
        self.stream = stream or sys.stderr
        self.enabled = enabled is not False
        self.bars = self.enabled and _is_terminal(self.stream)
        self.interval_s, self.fraction = interval_s, fraction
        self.done = 0
        self.note = ""  # shown after the ETA (a cluster's workers alive)
        self.current_phase = ""  # what runs before the rate starts ("compiling qffc"); "" once it has
        self._resumed = 0  # done before the last restart: counted, not in the rate
        self.began = self.start = self._phase_start = time.perf_counter()
        self._line_at, self._line_done = None, 0  # when the last line was written, and the count then

    def skip(self, n: int) -> None:
        """Count ``n`` done earlier (a resumed run's saved work): shown, never in the rate."""
        self.done = min(self.total, self.done + n)
        self.restart()

    def phase(self, name: str) -> None:
        """Name what runs now, before the rate can start (``"set-up"``, ``"compiling qffc"``)."""
        self.current_phase, self._phase_start = name, time.perf_counter()
        self._draw(phase_changed=True)

    def restart(self, note: str = "") -> None:
        """Start the rate and ETA afresh from here (after a compilation, which says nothing of the rate)."""
        self._resumed, self.start = self.done, time.perf_counter()
        self.note = note or self.note
        self.current_phase = ""
        self.update(0)

    def __enter__(self):
        return self

    def update(self, n: int) -> None:
        self.done = min(self.total, self.done + n)
        self._draw()

    def text(self) -> str:
        """The counts, and the phase with its elapsed time or the rate and ETA."""
        now = time.perf_counter()
        head = f"{self.done}/{self.total} {self.unit}"
        if self.current_phase:
            body = f"  {self.current_phase} ({now - self._phase_start:.0f} s)"
        elif self.done == self._resumed and self.done < self.total:  # a rate of 0.0 would say it had stalled
            body = f"  running (the rate once the first {self.unit} finish)"
        else:
            elapsed = now - self.start
            rate = (self.done - self._resumed) / elapsed if elapsed > 0 else 0.0
            eta = f"{(self.total - self.done) / rate:.0f} s" if rate > 0 else "--"
            body = f"  {rate:.1f} {self.unit}/s  ETA {eta}"
        return head + body + (f"  {self.note}" if self.note else "")

    def _draw(self, phase_changed: bool = False, final: bool = False) -> None:
        if not self.enabled:
            return
        if self.bars:
            width = 30
            filled = int(width * self.done / max(self.total, 1))
            self.stream.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {self.text()} ")
            self.stream.flush()
            return
        now = time.perf_counter()
        if not self._line_due(now, phase_changed, final):
            return
        self._line_at, self._line_done = now, self.done
        self.stream.write(f"[{now - self.began:.0f} s] {self.text()}\n")
        self.stream.flush()

    def _line_due(self, now: float, phase_changed: bool, final: bool) -> bool:
        if final:  # the last count, where any line was written
            return self._line_at is not None and self._line_done != self.done
        if phase_changed:
            return True
        return (now - (self._line_at or self.began) >= self.interval_s
                and self.done - self._line_done >= self.fraction * self.total)

    def __exit__(self, *exc):
        if self.bars:
            self.stream.write("\n")
            self.stream.flush()
        else:
            self._draw(final=True)
        return False


def _is_terminal(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):  # a closed or file-like stream without isatty
        return False
