"""An uncontrolled run gets every file a controlled one gets, from ``geojax simulate`` or ``geojax propagate``
alike, and every burn flown goes to the manoeuvre file, the recovery law's included (``geo``: controller none with
``controller.recovery``).  The independent reader is ``ccsds-ndm``; the checks are the loop's own integration of
the Delta-V and the mass (``dv_recovery_mps``, ``mass_used_kg``), against burns rebuilt from the thrust of every
step by other code (``export.trajectory.step_burns``), and the same null-controller loop reached by both commands."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from geojax import cli

ndm_io = pytest.importorskip("ccsds_ndm.ndm_io")
STATE_KEYS = ("x", "y", "z", "x_dot", "y_dot", "z_dot")


def maneuvers(path) -> list:
    return ndm_io.NdmIo().from_path(path).body.segment.data.maneuver_parameters


def oem_states(path) -> np.ndarray:
    segment = ndm_io.NdmIo().from_path(path).body.segment[0]
    return np.array([[float(getattr(s, k).value) for k in STATE_KEYS] for s in segment.data.state_vector])


def test_the_recovery_law_s_burns_go_to_the_manoeuvre_file(tmp_path, capsys):
    """geo drifts out of its box on day 3 and the recovery law flies it back: the OPM holds its burns, whose Delta-V
    and propellant are what the loop integrated (every Delta-V of this run is the recovery's), and the burn list
    beside the OEM holds the same burns."""
    out, opm, oem = tmp_path / "geo.h5", tmp_path / "geo.opm", tmp_path / "geo.oem"
    assert cli.main(["simulate", "geo", "--days", "8", "--out", str(out), "--maneuvers", str(opm),
                     "--oem", str(oem)]) == 0
    assert f"wrote {opm}" in capsys.readouterr().out
    with h5py.File(out) as f:
        m = {k: f[f"metrics/{k}"][()] for k in f["metrics"]}
    assert m["recovery_cycles"] >= 3 and m["dv_recovery_mps"] > 0.5
    blocks = maneuvers(opm)
    dv = np.array([[float(getattr(b, f"man_dv_{i}").value) for i in (1, 2, 3)] for b in blocks]) * 1e3
    assert len(blocks) > 3 and all(b.man_ref_frame == "RTN" for b in blocks)
    assert abs(np.linalg.norm(dv, axis=1).sum() - m["dv_recovery_mps"]) < 1e-8 * len(blocks)
    assert abs(-sum(float(b.man_delta_mass.value) for b in blocks) - m["mass_used_kg"]) < 1e-9 * len(blocks)
    assert np.all(np.abs(dv[:, 0]) < 1e-12) and np.any(np.abs(dv[:, 1]) > 0) and np.any(np.abs(dv[:, 2]) > 0.01)
    csv = np.genfromtxt(tmp_path / "geo-burns.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    np.testing.assert_allclose(np.stack([csv["dv_r_mps"], csv["dv_t_mps"], csv["dv_n_mps"]], 1), dv, atol=1e-9)


def test_propagate_and_simulate_write_the_same_uncontrolled_files(tmp_path, capsys):
    """li2022 (no controller): ``propagate --oem --maneuvers`` and ``simulate --oem --maneuvers --out`` write the
    same free drift, a state at every step and no maneuver block; simulate's file holds its metrics."""
    files = {}
    for command in ("propagate", "simulate"):
        oem, opm, out = (tmp_path / f"{command}.{ext}" for ext in ("oem", "opm", "h5"))
        assert cli.main([command, "li2022", "--days", "3", "--oem", str(oem), "--maneuvers", str(opm),
                         "--out", str(out)]) == 0
        assert maneuvers(opm) in ([], None)
        files[command] = oem_states(oem)
    assert capsys.readouterr().out.count("wrote") == 6  # each: the file, the OEM and its burn list, the OPM
    assert files["simulate"].shape == (3 * 96 + 1, 6)
    np.testing.assert_array_equal(files["propagate"], files["simulate"])
    with h5py.File(tmp_path / "simulate.h5") as f:
        assert f["metrics/status"][()] == 0 and f["metrics/mass_used_kg"][()] == 0.0
        assert f["metrics/max_abs_dlon_deg"][()] > 0


def test_propagate_refuses_a_bad_oem_step_before_the_run(capsys):
    assert cli.main(["propagate", "li2022", "--days", "3", "--oem-step", "10", "--oem", "/tmp/never.oem"]) == 2
    err = capsys.readouterr().err
    assert "--oem-step: must be at least the integration step" in err and err.count("\n") == 1
