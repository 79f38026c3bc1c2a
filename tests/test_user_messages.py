"""What a user reads when a long run is resumed, interrupted or rounded."""

import io
import time

import pytest

from geojax import cli, sweep
from geojax.parallel import _concurrently
from geojax.progress import Progress


def test_a_resumed_run_s_saved_work_is_not_in_the_rate():
    """Before: the first frame of a resumed sweep showed 17,467,248 samples/s (the saved samples over a few
    microseconds).  The rate counts only this run's samples: 10 samples in >= 0.05 s is at most 200/s."""
    stream = io.StringIO()  # not a terminal: lines, here one per update
    with Progress(1000, "samples", stream=stream, enabled=True, interval_s=0.0, fraction=0.0) as bar:
        bar.skip(900)
        time.sleep(0.05)
        bar.update(10)
    last = stream.getvalue().strip().splitlines()[-1]
    assert "910/1000 samples" in last
    rate = float(last.split("samples  ")[1].split(" ")[0])
    assert 0 < rate <= 200


def test_ctrl_c_in_a_sweep_names_resume(tmp_path, capsys, monkeypatch):
    path = tmp_path / "s.toml"
    path.write_text('scenario = "li2022-qffc"\n[grid]\n"thrusters.beta_max_deg" = [60.0]\n')

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(sweep, "run_sweep", interrupted)
    assert cli.main(["sweep", str(path), "--out", str(tmp_path / "o.h5"), "-q"]) == 130
    err = capsys.readouterr().err
    assert "interrupted" in err and f"geojax sweep {path} --out {tmp_path / 'o.h5'} --resume" in err


def test_compilations_run_at_once_and_errors_reach_the_caller():
    import threading

    # Every task waits until all four have started: one after another, the first would wait for ever (the barrier's
    # timeout only keeps such a failure from hanging the suite; no time is measured).
    together = threading.Barrier(4, timeout=60)

    def task(i):
        together.wait()
        return i * i

    assert _concurrently([lambda i=i: task(i) for i in range(4)]) == [0, 1, 4, 9]

    def fails():
        raise ValueError("bad shape")

    with pytest.raises(ValueError, match="bad shape"):
        _concurrently([lambda: 1, fails])


@pytest.mark.parametrize("days, expected", [
    (20.0, "20 days"),  # 20 cycles = 19.945 days: within 2 %
    (0.3, "0.3 days, flown as 1 sidereal-day cycle (0.997 days)"),  # one cycle: 86164.0905 s / 86400 s
    (2.6, "2.6 days, flown as 3 sidereal-day cycles (2.992 days)"),  # round(2.607) = 3 cycles
])
def test_durations_say_how_they_are_flown(days, expected):
    assert cli.flown_days(days) == expected
