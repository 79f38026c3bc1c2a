"""Progress of long runs on stderr: a bar redrawn in place on a terminal, and plain lines, sparingly, when
stderr is a file or a pipe (a run whose output is redirected still says how far it is)."""

from __future__ import annotations

import sys
import threading
import time

# Lines off a terminal: one when a phase starts (set-up, compiling), then one each time both LINE_INTERVAL_S
# and LINE_FRACTION of the work have passed since the last (every 10 % or 30 s, whichever comes later), and
# the final count if any line was written.
LINE_INTERVAL_S = 30.0
LINE_FRACTION = 0.1
# While a unit of work runs (a sweep's compiled batch, minutes on a CPU), a ticker redraws the bar every TICK_S
# (the elapsed time, the ETA counting down) and, off a terminal, writes a line once STALL_INTERVALS line intervals
# pass without one.
TICK_S = 1.0
STALL_INTERVALS = 5


class Progress:
    """``with Progress(total, "cycles") as bar: bar.update(n)``.

    ``enabled``: False draws nothing; None or True draws a bar if ``stream`` (default stderr) is a terminal,
    else lines.  ``bar.phase("compiling")`` names what runs before the first unit is done (set-up,
    compilation), shown with its elapsed time instead of a rate until ``restart``.

    The rate is that of the units finished since ``restart`` (at the last count); between counts the ETA counts
    down from the one then.  ``tick_s`` (e.g. ``TICK_S``; None: none) starts a ticker thread while the bar is
    open that redraws it (``tick``) every ``tick_s`` seconds, so that a run whose units finish minutes apart
    still shows its time passing.
    """

    def __init__(self, total: int, unit: str, stream=None, enabled: bool | None = None,
                 interval_s: float = LINE_INTERVAL_S, fraction: float = LINE_FRACTION, tick_s: float | None = None):
        self.total, self.unit = total, unit
        self.stream = stream or sys.stderr
        self.enabled = enabled is not False
        self.bars = self.enabled and _is_terminal(self.stream)
        self.interval_s, self.fraction = interval_s, fraction
        self.done = 0
        self.note = ""  # shown after the ETA (a cluster's workers alive)
        self.current_phase = ""  # what runs before the rate starts ("compiling qffc"); "" once it has
        self._resumed = 0  # done before the last restart: counted, not in the rate
        self.began = self.start = self._phase_start = self._counted_at = time.perf_counter()
        self._line_at, self._line_done = None, 0  # when the last line was written, and the count then
        self.tick_s = tick_s
        self._lock = threading.Lock()  # the ticker and the caller draw in turn
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

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
        self._counted_at = self.start
        self.note = note or self.note
        self.current_phase = ""
        self.update(0)

    def __enter__(self):
        if self.enabled and self.tick_s:
            self._ticker = threading.Thread(target=self._tick_until_closed, name="progress", daemon=True)
            self._ticker.start()
        return self

    def update(self, n: int) -> None:
        if n > 0:
            self._counted_at = time.perf_counter()
        self.done = min(self.total, self.done + n)
        self._draw()

    def tick(self) -> None:
        """Redraw with the time now (what the ticker calls): on a terminal the bar; off one a line where
        ``STALL_INTERVALS`` line intervals passed since the last."""
        self._draw(tick=True)

    def _tick_until_closed(self) -> None:
        while not self._stop.wait(self.tick_s):
            self.tick()

    def text(self) -> str:
        """The counts, and the phase with its elapsed time or the rate and ETA."""
        now = time.perf_counter()
        head = f"{self.done}/{self.total} {self.unit}"
        if self.current_phase:
            body = f"  {self.current_phase} ({now - self._phase_start:.0f} s)"
        elif self.done == self._resumed and self.done < self.total:  # a rate of 0.0 would say it had stalled
            body = f"  running {now - self.start:.0f} s (the rate once the first {self.unit} finish)"
        else:
            elapsed = self._counted_at - self.start  # to the last count: the rate of the units finished
            rate = (self.done - self._resumed) / elapsed if elapsed > 0 else 0.0
            left = max(0.0, (self.total - self.done) / rate - (now - self._counted_at)) if rate > 0 else None
            body = f"  {rate:.1f} {self.unit}/s  ETA {'--' if left is None else f'{left:.0f} s'}"
        return head + body + (f"  {self.note}" if self.note else "")

    def _draw(self, phase_changed: bool = False, final: bool = False, tick: bool = False) -> None:
        if not self.enabled:
            return
        with self._lock:
            self._draw_now(phase_changed, final, tick)

    def _draw_now(self, phase_changed: bool, final: bool, tick: bool) -> None:
        if self.bars:
            width = 30
            filled = int(width * self.done / max(self.total, 1))
            self.stream.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {self.text()} ")
            self.stream.flush()
            return
        now = time.perf_counter()
        if not self._line_due(now, phase_changed, final, tick):
            return
        self._line_at, self._line_done = now, self.done
        self.stream.write(f"[{now - self.began:.0f} s] {self.text()}\n")
        self.stream.flush()

    def _line_due(self, now: float, phase_changed: bool, final: bool, tick: bool) -> bool:
        if final:  # the last count, where any line was written
            return self._line_at is not None and self._line_done != self.done
        if phase_changed:
            return True
        if tick:  # a long wait between counts (or in a phase) still says how far it is
            return self.interval_s > 0 and now - (self._line_at or self.began) >= STALL_INTERVALS * self.interval_s
        return (now - (self._line_at or self.began) >= self.interval_s
                and self.done - self._line_done >= self.fraction * self.total)

    def __exit__(self, *exc):
        if self._ticker is not None:
            self._stop.set()
            self._ticker.join()
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
