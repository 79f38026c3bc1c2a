"""CCSDS files for operations from a run with the navigation filter (``li2022-qffc-ranging``, 3 days): the OEM at
every integration step with its interpolation metadata and the filter's covariance blocks, the estimated ephemeris,
and the manoeuvres as an OPM.  The independent reader is ``ccsds-ndm`` (classes generated from the NDM/XML
schemas, its own KVN parser); the checks are the run's own records written by other code (the filter's per-cycle
error and 1-sigma in RSW, ``burns_total``), ERFA's IAU 1976 precession for the frame, and a second method for the
interpolation (Lagrange through every other state against the state the loop integrated between them)."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from geojax import cli, scenario
from geojax.runner import rollout
from geojax.physics.constants import JD_J2000, SECONDS_PER_DAY
from geojax.physics.frames import rsw_basis
from geojax.physics.time import tt_seconds_from_utc

ndm_io = pytest.importorskip("ccsds_ndm.ndm_io")
DAYS = 3
STATE_KEYS = ("x", "y", "z", "x_dot", "y_dot", "z_dot")


@pytest.fixture(scope="module")
def runs():
    """(the run as always, the same run with its ephemeris recorded)."""
    sc = scenario.load("li2022-qffc-ranging", {"duration.days": DAYS})
    return rollout.simulate(sc, 0), rollout.simulate(sc, 0, ephemeris=True)


@pytest.fixture(scope="module")
def run(runs):
    return runs[1]


def read(path):
    return ndm_io.NdmIo().from_path(path)


def oem_arrays(path):
    """(segment, TT seconds [n], states km [n, 6], covariance epochs' TT seconds [m], covariances km [m, 6, 6])."""
    segment = read(path).body.segment[0]
    t = np.array([utc_seconds(s.epoch) for s in segment.data.state_vector])
    states = np.array([[float(getattr(s, k).value) for k in STATE_KEYS] for s in segment.data.state_vector])
    names = [f"c{STATE_KEYS[i]}_{STATE_KEYS[j]}" for i in range(6) for j in range(i + 1)]
    t_cov, covs = [], []
    for block in segment.data.covariance_matrix:
        values = iter(float(getattr(block, name).value) for name in names)
        lower = np.zeros((6, 6))
        for i in range(6):
            for j in range(i + 1):
                lower[i, j] = next(values)
        covs.append(lower + np.tril(lower, -1).T)
        t_cov.append(utc_seconds(block.epoch))
    return segment, t, states, np.array(t_cov), np.array(covs)


def utc_seconds(text: str) -> float:
    return tt_seconds_from_utc(dt.datetime.fromisoformat(text))


def to_epoch_frame(run, states_km):
    """EME2000 states [n, 6] km -> geojax ECI m by ERFA's precession matrix (r_epoch = P r_J2000)."""
    p = __import__("erfa").pmat76(JD_J2000, run.scenario.epoch_tt_s / SECONDS_PER_DAY)
    return np.hstack([states_km[:, :3] @ p.T, states_km[:, 3:] @ p.T]) * 1e3, p


def test_recording_the_ephemeris_leaves_the_run_as_it_was(runs):
    """The same seed with and without the ephemeris: the same records and metrics (the recording is a different
    compiled program: XLA's fusion moves last bits, and the closed loop with its filter carries them on: measured
    over three days, the metrics up to 8e-10 relative (the filter's RMS errors; 1e-14 before the filter read the
    burns' truth back from the planned and flown directions), the final elements 1e-14 absolute) and a run without it
    carries none."""
    plain, recorded = runs
    assert plain.ephemeris is None and recorded.ephemeris.truth.shape == (DAYS, 96, 6)
    assert set(plain.metrics) == set(recorded.metrics) and plain.metrics["burns_total"] > 0
    for name, value in plain.metrics.items():
        np.testing.assert_allclose(recorded.metrics[name], value, rtol=1e-8, atol=1e-18, err_msg=name)
    np.testing.assert_allclose(recorded.final.orbit, plain.final.orbit, rtol=1e-13, atol=1e-13)  # MEE f, g, h, k ~1e-4
    assert recorded.status == plain.status == 0


def test_oem_holds_every_step_and_the_filter_covariance(run, tmp_path):
    """``ccsds-ndm`` reads a state every integration step (897.5 s, under 900) and the end, LAGRANGE metadata, and
    a covariance block at every state but the end; each block, turned back into geojax's frame (ERFA) and into
    RSW about the written state, gives at the cycle starts the 1-sigma the filter recorded (``nav_sigma_*``)."""
    path = run.save_oem(tmp_path / "x.oem", burns_csv=False)[0]
    segment, t, states, t_cov, covs = oem_arrays(path)
    assert (segment.metadata.interpolation, int(segment.metadata.interpolation_degree)) == ("LAGRANGE", 8)
    assert len(t) == DAYS * 96 + 1 and np.max(np.diff(t)) <= 900.0
    assert len(covs) == len(t) - 1 and np.allclose(t_cov, t[:-1], atol=1e-6)
    assert np.all(np.linalg.eigvalsh(covs) > -1e-7 * np.max(np.abs(covs), axis=(1, 2))[:, None])
    rv, p = to_epoch_frame(run, states)
    six = np.kron(np.eye(2), p)
    columns = run.cycles()
    for k in range(DAYS):
        i = 96 * k
        basis = np.asarray(rsw_basis(rv[i, :3], rv[i, 3:]))
        rot = np.kron(np.eye(2), basis)
        sigma = np.sqrt(np.diag(rot @ six @ covs[i] @ six.T @ rot.T) * 1e6)
        recorded = [columns[f"nav_sigma_{axis}_{unit}"][k] for unit in ("m", "mps")
                    for axis in ("radial", "along", "cross")]
        np.testing.assert_allclose(sigma, recorded, rtol=1e-6)  # 8 printed digits of a variance


def test_estimated_ephemeris_is_the_filter_estimate(run, tmp_path):
    """``of="estimate"``: the filter's estimate at the same steps (no end state); estimate - truth, both read back
    by ``ccsds-ndm``, in RSW at the cycle starts is the error the filter recorded there (``nav_error_*``)."""
    truth = oem_arrays(run.save_oem(tmp_path / "t.oem", burns_csv=False)[0])
    estimate = oem_arrays(run.save_oem(tmp_path / "e.oem", of="estimate", burns_csv=False)[0])
    assert len(estimate[1]) == len(truth[1]) - 1 and np.allclose(estimate[1], truth[1][:-1], atol=1e-6)
    assert len(estimate[4]) == len(estimate[1])
    rv_true, _ = to_epoch_frame(run, truth[2])
    rv_est, _ = to_epoch_frame(run, estimate[2])
    columns = run.cycles()
    for k in range(DAYS):
        i = 96 * k
        rot = np.kron(np.eye(2), np.asarray(rsw_basis(rv_true[i, :3], rv_true[i, 3:])))
        error = rot @ (rv_est[i] - rv_true[i])
        recorded = [columns[f"nav_error_{axis}_{unit}"][k] for unit in ("m", "mps")
                    for axis in ("radial", "along", "cross")]
        np.testing.assert_allclose(error[:3], recorded[:3], rtol=0, atol=2e-6)  # 1 um printed, twice
        np.testing.assert_allclose(error[3:], recorded[3:], rtol=0, atol=2e-9)


def test_lagrange_interpolation_of_the_written_states(run, tmp_path):
    """The interpolation the metadata names: degree-8 Lagrange through the states of an OEM every other step
    (``oem_step_s``: 1795 s) gives the states between them, which the every-step OEM holds, to a few mm where its
    nine nodes span no burn's start or end (measured 2.2 mm); across one (the thrust's jump) by metres, as the
    OEM's comment says (measured 7.0 m)."""
    from scipy.interpolate import BarycentricInterpolator

    from geojax.export import trajectory

    _, t, every, _, _ = oem_arrays(run.save_oem(tmp_path / "a.oem", burns_csv=False)[0])
    sparse_path = run.save_oem(tmp_path / "b.oem", oem_step_s=2 * run.step_s + 1, burns_csv=False)[0]
    _, t2, states2 = oem_arrays(sparse_path)[:3]
    assert "across a burn's start or end" in sparse_path.read_text()
    assert np.allclose(np.diff(t2)[:-1], 2 * run.step_s, atol=1e-5)
    burns = trajectory.run_burns(run)
    switches = np.concatenate([burns.start_tt_s, burns.start_tt_s + burns.duration_s])
    worst = {True: 0.0, False: 0.0}
    for i in range(9, len(t) - 10, 2):  # each skipped state, nine written states around it
        nodes = np.searchsorted(t2, t[i]) + np.arange(-4, 5)
        got = BarycentricInterpolator(t2[nodes] - t[i], states2[nodes, :3])(0.0)
        spans = bool(np.any((switches > t2[nodes[0]]) & (switches < t2[nodes[-1]])))
        worst[spans] = max(worst[spans], np.max(np.abs(got - every[i, :3])) * 1e3)
    assert worst[False] < 5e-3 and 0.1 < worst[True] < 20.0, worst  # m


def test_opm_has_one_maneuver_block_per_burn_flown(run, tmp_path):
    """``ccsds-ndm`` reads the OPM: one maneuver block per burn, as many as ``burns_total``, RTN, propellant
    negative, in time order; their Delta-V is the commanded one, within the filter's execution errors (1-sigma
    ``errors.sigma3_dv_pct`` / 3, pointing ``errors.sigma3_att_deg`` / 3) of the Delta-V the loop delivered."""
    opm = read(run.save_maneuvers(tmp_path / "m.opm"))
    blocks = opm.body.segment.data.maneuver_parameters
    assert len(blocks) == run.metrics["burns_total"] > 0
    assert all(b.man_ref_frame == "RTN" and float(b.man_delta_mass.value) < 0 for b in blocks)
    assert all(b.comment and b.comment[0].startswith("flown burn") for b in blocks)
    ignition = [utc_seconds(b.man_epoch_ignition) for b in blocks]
    assert np.all(np.diff(ignition) > 0)
    dv = np.array([[float(getattr(b, f"man_dv_{i}").value) for i in (1, 2, 3)] for b in blocks]) * 1e3
    delivered = float(run.final.dv_mps - run.params.initial.dv_mps)
    errors = run.scenario.config["errors"]
    sigma = np.hypot(errors["sigma3_dv_pct"] / 300, np.radians(errors["sigma3_att_deg"] / 3))
    assert abs(np.linalg.norm(dv, axis=1).sum() - delivered) < 4 * sigma * delivered


def test_simulate_writes_step_oem_and_opm(run, tmp_path, monkeypatch, capsys):
    """``geojax simulate li2022-qffc-ranging --days 3 --oem x.oem --maneuvers m.opm --out r.h5`` asks the run for
    its ephemeris and writes a state at least every 900 s with covariance blocks, and one maneuver block per
    burn flown as the results file's ``burns_total`` counts."""
    import h5py

    asked = {}

    def simulate(*args, **kwargs):
        asked.update(kwargs)
        return run

    monkeypatch.setattr(rollout, "simulate", simulate)
    oem, opm, out = tmp_path / "x.oem", tmp_path / "m.opm", tmp_path / "r.h5"
    argv = ["simulate", "li2022-qffc-ranging", "--days", str(DAYS), "--oem", str(oem), "--maneuvers", str(opm),
            "--out", str(out), "-q"]
    assert cli.main(argv) == 0 and asked["ephemeris"] is True
    assert f"wrote {opm}" in capsys.readouterr().out
    _, t, _, _, covs = oem_arrays(oem)
    assert np.max(np.diff(t)) <= 900.0 and len(covs) == len(t) - 1
    with h5py.File(out) as f:
        burns_total = float(f["metrics/burns_total"][()])
    assert len(read(opm).body.segment.data.maneuver_parameters) == burns_total > 0
    assert cli.main([*argv[:-1], "--oem-step", "1800", "--oem-of", "estimate", "--force"]) == 0
    _, t, _, _, _ = oem_arrays(oem)
    np.testing.assert_allclose(np.diff(t), 2 * run.step_s, atol=1e-5)  # 1795 s: two steps within 1800


@pytest.mark.parametrize("extra, message", [
    (["--oem", "x.oem", "--oem-step", "100"], "--oem-step: must be at least the integration step, 897.543 s"),
    (["--oem-of", "estimate"], "--oem-of: needs --oem FILE"),
    (["--oem-step", "1800"], "--oem-step: needs --oem FILE")])
def test_bad_oem_options_are_refused_before_the_run(extra, message, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(rollout, "simulate", lambda *a, **k: pytest.fail("ran before checking the options"))
    monkeypatch.chdir(tmp_path)
    assert cli.main(["simulate", "li2022-qffc-ranging", *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_a_step_oem_needs_a_recorded_ephemeris(runs, tmp_path):
    plain, _ = runs
    with pytest.raises(ValueError, match=r"ephemeris=True"):
        plain.save_oem(tmp_path / "x.oem", oem_step_s=3600.0)
    with pytest.raises(ValueError, match=r"ephemeris=True"):
        plain.save_oem(tmp_path / "x.oem", of="estimate")
