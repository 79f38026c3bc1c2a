"""Progress on stderr: a bar on a terminal, sparse lines off one, and a phase (set-up,
compiling) shown before the rate starts; what a command's progress says is true: the cycles it counts
are the run's, and a program the compilation cache served is said to be loaded, not compiled."""

import io
import threading

from geojax import progress


class Terminal(io.StringIO):
    def isatty(self):
        return True


class Clock:
    def __init__(self):
        self.now = 1000.0

    def __call__(self):
        return self.now


def test_a_terminal_gets_a_bar_with_the_phase_then_the_rate(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    stream = Terminal()
    with progress.Progress(100, "samples", stream=stream) as bar:
        bar.phase("qffc: compiling")
        clock.now += 12.0
        bar.update(0)
        assert stream.getvalue().endswith("0/100 samples  qffc: compiling (12 s) ")
        bar.restart()
        clock.now += 10.0
        bar.update(20)  # 20 samples in 10 s after the compilation: 2 per second, 40 s to go
        assert stream.getvalue().endswith("] 20/100 samples  2.0 samples/s  ETA 40 s ")
        assert stream.getvalue().count("\r") == 4  # redrawn in place
    assert stream.getvalue().endswith("\n")


def test_before_the_first_unit_finishes_it_says_running_not_a_rate_of_zero(monkeypatch):
    """A sweep's first chunk runs for minutes before a sample is counted: no "0.0 samples/s" meanwhile."""
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    stream = Terminal()
    with progress.Progress(100, "samples", stream=stream) as bar:
        bar.restart()
        clock.now += 500.0
        bar.update(0)
        assert stream.getvalue().endswith("0/100 samples  running 500 s (the rate once the first samples finish) ")
        bar.update(50)
        assert stream.getvalue().endswith("50/100 samples  0.1 samples/s  ETA 500 s ")


def test_between_counts_the_ticker_redraws_the_rate_and_the_eta_counting_down(monkeypatch):
    """A sweep's compiled batch runs for minutes between counts: each tick redraws the bar with the rate of the
    samples finished (not one falling as the wait goes on) and the ETA less the time since the count; off a
    terminal a tick writes a line only after 5 line intervals without one."""
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    stream = Terminal()
    with progress.Progress(100, "samples", stream=stream) as bar:
        bar.restart()
        clock.now += 30.0
        bar.tick()
        assert stream.getvalue().endswith("0/100 samples  running 30 s (the rate once the first samples finish) ")
        bar.update(25)  # 25 samples in 30 s: 100 s to go
        assert stream.getvalue().endswith("25/100 samples  0.8 samples/s  ETA 90 s ")
        clock.now += 40.0
        bar.tick()
        assert stream.getvalue().endswith("25/100 samples  0.8 samples/s  ETA 50 s ")
        clock.now += 80.0  # later than the rate said: 0 s left, not a negative time
        bar.tick()
        assert stream.getvalue().endswith("25/100 samples  0.8 samples/s  ETA 0 s ")
        bar.update(25)  # 50 in 150 s
        assert stream.getvalue().endswith("50/100 samples  0.3 samples/s  ETA 150 s ")
    lines = io.StringIO()
    with progress.Progress(100, "samples", stream=lines, interval_s=30.0) as bar:
        bar.restart()
        clock.now += 149.0
        bar.tick()
        assert lines.getvalue() == ""
        clock.now += 1.0
        bar.tick()
        assert lines.getvalue() == "[150 s] 0/100 samples  running 150 s (the rate once the first samples finish)\n"


def test_the_ticker_thread_redraws_while_the_bar_is_open_and_stops_with_it():
    """``tick_s``: a thread of its own redraws the bar (more frames than the counts drew) until it is closed."""
    stream = Terminal()
    with progress.Progress(10, "samples", stream=stream, tick_s=0.001) as bar:
        bar.update(1)
        for _ in range(10000):  # until a tick has drawn (no time asserted: polled, a millisecond at a time)
            if stream.getvalue().count("\r") > 2:
                break
            threading.Event().wait(0.001)
        assert stream.getvalue().count("\r") > 2 and bar._ticker.is_alive()
    assert not bar._ticker.is_alive()
    frames = stream.getvalue()
    threading.Event().wait(0.01)
    assert stream.getvalue() == frames  # nothing drawn after the close


def test_a_file_gets_a_line_per_phase_then_every_10_percent_or_30_s_whichever_is_later(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    stream = io.StringIO()  # not a terminal: stderr redirected to a file
    with progress.Progress(100, "samples", stream=stream) as bar:
        bar.phase("qffc: set-up")
        clock.now += 40.0
        bar.phase("qffc: compiling")  # each phase is said when it starts
        clock.now += 100.0
        bar.restart()
        assert stream.getvalue().splitlines() == ["[0 s] 0/100 samples  qffc: set-up (0 s)",
                                                  "[40 s] 0/100 samples  qffc: compiling (0 s)"]
        for _ in range(50):  # 1 sample each second: 10 % takes 10 s, so the 30 s decide
            clock.now += 1.0
            bar.update(1)
        clock.now += 1.0
        bar.update(48)  # 10 % more within 1 s: too soon for a line
    lines = stream.getvalue().splitlines()[2:]
    assert lines == ["[150 s] 10/100 samples  1.0 samples/s  ETA 90 s",  # 30 s after the last line
                     "[180 s] 40/100 samples  1.0 samples/s  ETA 60 s",
                     "[191 s] 98/100 samples  1.9 samples/s  ETA 1 s"]  # the last count, at the end
    assert "\r" not in stream.getvalue()


def test_lines_wait_for_10_percent_when_30_s_pass_sooner(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    stream = io.StringIO()
    with progress.Progress(1000, "cycles", stream=stream) as bar:
        for _ in range(150):  # 1 cycle a minute: 10 % takes 100 min
            clock.now += 60.0
            bar.update(1)
    times = [line.split("]")[0] for line in stream.getvalue().splitlines()]
    assert times == ["[6000 s", "[9000 s"]  # 100 cycles, then the final count (150)


def test_a_short_run_off_a_terminal_and_a_quiet_run_print_nothing():
    stream = io.StringIO()
    with progress.Progress(10, "cycles", stream=stream) as bar:
        bar.update(10)
    assert stream.getvalue() == ""
    with progress.Progress(10, "cycles", stream=stream, enabled=False) as bar:
        bar.phase("compiling")
        bar.update(10)
    assert stream.getvalue() == ""


def test_propagate_counts_the_runs_cycles_and_says_what_the_cache_served(tmp_path):
    """A propagation integrates two cycles beyond the run's (to interpolate its end) but counts the run's, as its
    file and summary do (3 days: 3 cycles, 5 integrated); a second process with the same cache folder loads the
    program (JAX's cache-hit event, through ``compilation.Compilations``) and says so."""
    import os
    import subprocess
    import sys

    env = {**{k: v for k, v in os.environ.items() if k != "JAX_COMPILATION_CACHE_DIR"},
           "GEOJAX_CACHE_DIR": str(tmp_path / "cache")}
    argv = [sys.executable, "-m", "geojax", "propagate", "li2022", "--days", "3"]
    first, second = (subprocess.run(argv, env=env, capture_output=True, text=True, check=True).stderr
                     for _ in range(2))
    assert "3/3 cycles" in first and "5/5" not in first
    assert "compiled and ran the first 1 cycle in" in first
    assert "loaded from the cache and ran the first 1 cycle in" in second
