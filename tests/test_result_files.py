"""A result owns its file: ``<library call>(...).save(path)`` writes the datasets and attributes that ``geojax
<command> --out`` writes for the same inputs (values, dtypes, shapes, units, descriptions, axis labels; only the
times and the source revision may differ), for every kind of single run; the command line prints the result's
summary lines."""

import h5py
import numpy as np
import pytest

import geojax
from geojax import cli, transfer
from geojax.bound import bound
from geojax.runner.rollout import Result
from geojax.uncontrolled import propagate_scenario

# Measured, not computed: they differ from run to run.
TIMES = {"wall_s", "created_utc", "compile_s", "run_s", "source_revision"}
TIMED_DATASETS = {"metrics/cpu_s_per_orbit", "rounds/solve_s", "iterations/wall_s"}  # wall times: of a run, of
# each program solve, of a tuning at each iteration


def contents(path) -> dict:
    """Everything a results file holds that does not depend on when and how fast it was written."""
    out = {}
    with h5py.File(path) as f:
        out.update({f"@{k}": v for k, v in f.attrs.items() if k not in TIMES})

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                attrs = {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in obj.attrs.items()
                         if k not in ("DIMENSION_LIST", "REFERENCE_LIST", "CLASS")}  # not the scales' object references
                value = None if name in TIMED_DATASETS else obj[()]
                out[name] = (obj.dtype.str, obj.shape, value, attrs, tuple(d.label for d in obj.dims))

        f.visititems(visit)
    return out


def assert_same_file(a, b) -> None:
    x, y = contents(a), contents(b)
    assert sorted(x) == sorted(y)
    for key in x:
        if key.startswith("@"):
            assert np.array_equal(x[key], y[key]) if isinstance(x[key], np.ndarray) else x[key] == y[key], key
            continue
        (dtype, shape, value, attrs, dims), (dtype_b, shape_b, value_b, attrs_b, dims_b) = x[key], y[key]
        assert (dtype, shape, attrs, dims) == (dtype_b, shape_b, attrs_b, dims_b), key
        assert value is None and value_b is None or np.array_equal(value, value_b, equal_nan=dtype[1] == "f"), key


def printed_lines(capsys) -> list[str]:
    return capsys.readouterr().out.splitlines()


def test_propagate_save_is_the_command_s_file(tmp_path, capsys):
    command, library = tmp_path / "command.h5", tmp_path / "library.h5"
    assert cli.main(["propagate", "li2022", "--days", "3", "--step", "1800", "--out", str(command), "--plots",
                     str(tmp_path / "cli")]) == 0
    printed = printed_lines(capsys)
    assert printed[-1] == f"wrote {tmp_path / 'cli' / 'li2022-uncontrolled.png'}"
    sc = geojax.load_scenario("li2022", {"duration.days": 3, "integration.step_s": 1800})
    result = propagate_scenario(sc, progress=False)
    assert result.save(library) == library
    assert_same_file(command, library)
    assert result.summary()[1:] == printed[1:5]  # the first names the wall time
    assert (tmp_path / "cli" / "li2022-uncontrolled.png").stat().st_size > 10_000
    figure, = result.plot(tmp_path)
    assert figure == tmp_path / "li2022-uncontrolled.png" and figure.stat().st_size > 10_000


@pytest.mark.parametrize("name, seed", [("li2022-qffc", 0), ("katz2025-constant", 3)])
def test_simulate_save_is_the_command_s_file_for_a_planner_and_a_feedback_law(name, seed, tmp_path, capsys):
    """A planner's file holds its uncontrolled /reference and the /target, a feedback law's its /steps; the
    library's default keeps the steps of exactly the laws whose figures need them, as the command does."""
    command, library = tmp_path / "command.h5", tmp_path / "library.h5"
    assert cli.main(["simulate", name, "--days", "2", "--seed", str(seed), "--out", str(command)]) == 0
    printed = printed_lines(capsys)
    result = geojax.simulate(geojax.load_scenario(name, {"duration.days": 2}), seed)
    result.save(library)
    assert_same_file(command, library)
    with h5py.File(library) as f:
        assert ("steps" in f) == (name == "katz2025-constant") and ("reference" in f) == (name == "li2022-qffc")
        assert f.attrs["seed"] == seed
    table = [line for line in result.summary()[1:] if "cpu_s_per_orbit" not in line]
    assert table and all(line in printed for line in table)
    assert ("Li 2022" in table[0]) == (name == "li2022-qffc") and ("Katz 2025" in table[0]) == (name != "li2022-qffc")
    assert "Li 2022" not in result.summary(paper=False)[1] and "Katz 2025" not in result.summary(paper=False)[1]
    figures = result.plot(tmp_path / "figures")
    assert figures and all(f.stat().st_size > 10_000 for f in figures)


@pytest.mark.slow
def test_bound_save_is_the_command_s_file(tmp_path, capsys):
    command, library = tmp_path / "command.h5", tmp_path / "library.h5"
    assert cli.main(["bound", "li2022-qffc", "--days", "1", "--slot-steps", "8", "--free-end", "--out",
                     str(command), "--plots", str(tmp_path / "cli")]) == 0
    printed = printed_lines(capsys)
    assert printed[-1] == f"wrote {tmp_path / 'cli' / 'li2022-qffc-bound.png'}"
    result = bound(geojax.load_scenario("li2022-qffc", {"duration.days": 1}), slot_steps=8, free_end=True)
    result.save(library)
    assert_same_file(command, library)
    with h5py.File(library) as f:
        assert f["metrics/free_end"][()] == 1 and f["slots/dlon_deg"].dims[1].label == "step"
    assert all(line in printed for line in result.summary())
    figure, = result.plot(tmp_path)
    assert figure == tmp_path / "li2022-qffc-bound.png" and figure.stat().st_size > 10_000
    assert cli.main(["plot", str(command), "--out", str(tmp_path / "again")]) == 0  # the same figure from the file
    assert (tmp_path / "again" / "command.png").stat().st_size > 10_000


def test_transfer_save_is_the_command_s_file(tmp_path, capsys):
    command, library = tmp_path / "command.h5", tmp_path / "library.h5"
    assert cli.main(["transfer", "ma2023-quadrilateral", "--days", "0.5", "--out", str(command), "--plots",
                     str(tmp_path / "cli")]) == 0
    printed = printed_lines(capsys)
    assert printed[-1] == f"wrote {tmp_path / 'cli' / 'ma2023-quadrilateral.png'}"
    result = transfer.run(transfer.load("ma2023-quadrilateral"), days=0.5)
    result.save(library)
    assert_same_file(command, library)
    assert result.summary() == printed[:len(result.summary())]
    figure, = result.plot(tmp_path)
    assert figure == tmp_path / "ma2023-quadrilateral.png" and figure.stat().st_size > 10_000
    assert cli.main(["plot", str(command), "--out", str(tmp_path / "again")]) == 0
    assert (tmp_path / "again" / "command.png").stat().st_size > 10_000
    assert "(Ma 2023: 0.95)" in "\n".join(result.summary()) and "(Ma 2023:" not in "\n".join(result.summary(paper=False))


def test_a_batch_or_a_hand_made_result_is_refused_in_one_line(tmp_path):
    batch = Result({}, np.zeros(2, np.int8), None, None, None, 900.0, 1.0)
    with pytest.raises(ValueError, match="a batch of 2 rollouts"):
        batch.save(tmp_path / "x.h5")
    with pytest.raises(ValueError, match="scenario: this Result does not carry its scenario"):
        batch._replace(status=np.int8(0)).summary()
    assert not (tmp_path / "x.h5").exists()


def test_a_spec_key_of_the_library_is_named_by_its_flag_on_the_command_line(capsys):
    with pytest.raises(ValueError, match="bound.slot_steps: must divide"):
        bound(geojax.load_scenario("li2022-qffc", {"duration.days": 1}), slot_steps=5)
    assert cli.main(["bound", "li2022-qffc", "--days", "1", "--slot-steps", "5"]) == 2
    err = capsys.readouterr().err
    assert "--slot-steps: must divide" in err and "bound.slot_steps" not in err and err.count("\n") == 1
