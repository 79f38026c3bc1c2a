"""Output paths on the command line: every file a command would write is checked before anything runs (one line
naming the path, exit 2, nothing computed), and one overwrite policy for every command: a results file that
exists is refused without ``--force`` (a sweep's ``--resume`` continues it instead)."""

from pathlib import Path

import pytest

import geojax
from geojax import cli, store

SWEEP = """
name = "paths"
scenario = "li2022-qffc"
repetitions = 2
[set]
"duration.days" = 2
[grid]
"thrusters.beta_max_deg" = [70.0]
"""
TUNE = Path(geojax.__file__).parent.parent / "studies" / "katz2025" / "tune-discrete-sigma.toml"
UNWRITABLE = Path("/proc/geojax-out.h5")  # a folder no one can create a file in, root included


@pytest.fixture
def nothing_runs(monkeypatch):
    """Every run the commands call fails the test if called: a refusal must come before it."""
    from geojax import bound, transfer, tune, uncontrolled
    from geojax.runner import rollout
    from geojax.sweep import run

    def ran(*args, **kwargs):
        raise AssertionError("a run started before its outputs were checked")

    for module, name in ((rollout, "simulate"), (uncontrolled, "propagate_scenario"), (bound, "bound"),
                         (transfer, "run"), (run, "_run_chunks"), (tune, "tune")):
        monkeypatch.setattr(module, name, ran)


def commands(tmp_path: Path, out: str, flag: str = "--out") -> list[list[str]]:
    (tmp_path / "s.toml").write_text(SWEEP)
    return [["simulate", "li2022-qffc", "--days", "2", flag, out],
            ["propagate", "li2022", "--days", "2", flag, out],
            ["bound", "li2022-qffc", "--days", "2", flag, out],
            ["transfer", "ma2023-boom", flag, out],
            ["sweep", str(tmp_path / "s.toml"), flag, out],
            ["tune", str(TUNE), flag, out]]


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs /proc (Linux)")
@pytest.mark.parametrize("index", range(6))
def test_an_unwritable_out_is_refused_before_the_run(index, tmp_path, capsys, nothing_runs):
    # os.access says /proc is writable to root; only creating a file there tells.
    argv = commands(tmp_path, str(UNWRITABLE))[index]
    assert cli.main(argv) == 2
    assert f"--out '{UNWRITABLE}': cannot create a file in '/proc'" in one_line_error(capsys)


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs /proc (Linux)")
@pytest.mark.parametrize("flag", ["--oem", "--plots"])
def test_an_unwritable_oem_or_figure_folder_is_refused_before_the_run(flag, tmp_path, capsys, nothing_runs):
    assert cli.main(["simulate", "li2022-qffc", "--days", "2", flag, "/proc/geojax-x"]) == 2
    assert f"{flag} '/proc/geojax-x': cannot create a file in '/proc'" in one_line_error(capsys)


def test_a_file_where_a_folder_is_needed_is_refused(tmp_path, capsys, nothing_runs):
    (tmp_path / "f").write_text("")
    assert cli.main(["propagate", "li2022", "--days", "2", "--out", str(tmp_path / "f" / "x.h5")]) == 2
    assert "is not a folder" in one_line_error(capsys)
    assert cli.main(["propagate", "li2022", "--days", "2", "--plots", str(tmp_path / "f")]) == 2
    assert "exists and is not a folder" in one_line_error(capsys)


@pytest.mark.parametrize("index", range(6))
def test_every_command_refuses_an_existing_file_without_force(index, tmp_path, capsys, nothing_runs):
    there = tmp_path / "there.h5"
    there.write_bytes(b"not ours")
    assert cli.main(commands(tmp_path, str(there))[index]) == 2
    assert f"--out '{there}'" in (err := one_line_error(capsys)) and "exists; pass" in err and "--force" in err
    assert there.read_bytes() == b"not ours"


def test_an_existing_oem_and_tuned_scenario_are_refused_too(tmp_path, capsys, nothing_runs):
    (tmp_path / "x.oem").write_text("")
    assert cli.main(["simulate", "li2022-qffc", "--days", "2", "--oem", str(tmp_path / "x.oem")]) == 2
    assert "--oem" in (err := one_line_error(capsys)) and "exists; pass --force" in err
    (tmp_path / "t-tuned.toml").write_text("")
    assert cli.main(["tune", str(TUNE), "--out", str(tmp_path / "t.h5")]) == 2
    assert "t-tuned.toml': exists; pass --force" in one_line_error(capsys)


def test_force_replaces_and_figures_are_redrawn_in_place(tmp_path, capsys):
    out, figures = tmp_path / "run.h5", tmp_path / "fig"
    out.write_bytes(b"old")
    figures.mkdir()
    argv = ["propagate", "li2022", "--days", "2", "--out", str(out), "--plots", str(figures)]
    assert cli.main(argv + ["--force"]) == 0
    assert store.read_attrs(out)["config_toml"]
    capsys.readouterr()
    assert cli.main(argv) == 2 and "exists; pass --force" in one_line_error(capsys)
    before = (figures / "li2022-uncontrolled.png").stat().st_mtime_ns
    assert cli.main(argv[:4] + ["--out", str(tmp_path / "new.h5"), "--plots", str(figures)]) == 0
    assert (figures / "li2022-uncontrolled.png").stat().st_mtime_ns > before  # the same figure, redrawn


@pytest.mark.slow
def test_a_sweep_with_force_starts_afresh_and_force_with_resume_is_refused(tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text(SWEEP)
    out = tmp_path / "s.h5"
    parts = tmp_path / "s.h5.parts"
    parts.mkdir()  # an unfinished sweep of another file: refused, then discarded with --force
    (parts / "chunk").write_text("1")
    assert cli.main(["sweep", str(spec), "--out", str(out), "-q"]) == 2
    assert "exists; pass --resume to continue it, --force to replace it" in one_line_error(capsys)
    assert cli.main(["sweep", str(spec), "--out", str(out), "--force", "--resume"]) == 2
    assert "--force: not with --resume" in one_line_error(capsys)
    assert cli.main(["sweep", str(spec), "--out", str(out), "--force", "-q"]) == 0
    assert not parts.exists() and store.read_attrs(out)["config_toml"] == SWEEP
