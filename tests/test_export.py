"""CCSDS OEM and burn-list export (``geojax.export``): written from a short QFFC run, read back by readers of
this file's own (KVN lines, ``xml.etree``) and by ``ccsds-ndm`` (the NDM/XML schemas' object model) where it
is installed; states against the run's, the frame against ERFA's IAU 1976 precession, burns against the
run's delivered Delta-V."""

from __future__ import annotations

import csv
import datetime as dt
from xml.etree import ElementTree

import jax.numpy as jnp
import numpy as np
import pytest

from geojax import cli, scenario
from geojax.control.predictor import boundary_elements
from geojax.export import trajectory
from geojax.export.oem import Covariance, Metadata, covariance_keys, write_oem
from geojax.runner import rollout
from geojax.physics.constants import JD_J2000, SECONDS_PER_DAY
from geojax.physics.elements import cartesian_to_mee
from geojax.physics.propagate import DYNAMICS
from geojax.physics.time import tt_seconds_from_utc

DAYS = 3


@pytest.fixture(scope="module")
def run():
    return rollout.simulate(scenario.load("li2022-qffc", {"duration.days": DAYS}), 0)


# --- readers of our own, written from the standard (502.0-B-2 sec. 5, 505.0-B-2) ---------------------------

def read_kvn(path):
    """(header+metadata {key: value}, [(epoch, [6 floats])], [(epoch, frame, 6x6)]) of a one-segment KVN OEM."""
    keys, states, covariances, block = {}, [], [], None
    for line in path.read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("COMMENT") or line in ("META_START", "META_STOP"):
            continue
        if line in ("COVARIANCE_START", "COVARIANCE_STOP"):
            block = "cov" if line == "COVARIANCE_START" else None
            continue
        if block == "cov":
            if line.startswith("EPOCH"):
                covariances.append([line.split("=")[1].strip(), None, []])
            elif line.startswith("COV_REF_FRAME"):
                covariances[-1][1] = line.split("=")[1].strip()
            else:
                covariances[-1][2].append([float(x) for x in line.split()])
        elif "=" in line:
            key, value = (part.strip() for part in line.split("=", 1))
            keys[key] = value
        else:
            epoch, *numbers = line.split()
            states.append((epoch, [float(x) for x in numbers]))
    full = [(epoch, frame, _symmetric(rows)) for epoch, frame, rows in covariances]
    return keys, states, full


def _symmetric(rows):
    matrix = np.zeros((6, 6))
    for i, row in enumerate(rows):
        assert len(row) == i + 1
        matrix[i, :i + 1] = row
    return matrix + np.tril(matrix, -1).T


HEADER = ["COMMENT*", "CREATION_DATE", "ORIGINATOR"]
METADATA = ["COMMENT*", "OBJECT_NAME", "OBJECT_ID", "CENTER_NAME", "REF_FRAME", "REF_FRAME_EPOCH?", "TIME_SYSTEM",
            "START_TIME", "USEABLE_START_TIME?", "USEABLE_STOP_TIME?", "STOP_TIME", "INTERPOLATION?",
            "INTERPOLATION_DEGREE?"]
STATE = ["EPOCH", "X", "Y", "Z", "X_DOT", "Y_DOT", "Z_DOT", "X_DDOT?", "Y_DDOT?", "Z_DDOT?"]
COVARIANCE = ["COMMENT*", "EPOCH", "COV_REF_FRAME?", *covariance_keys()]


def follows(tags, sequence) -> bool:
    """Whether ``tags`` fit the schema sequence ``sequence`` (a name, optional with '?', repeated with '*')."""
    i = 0
    for name in sequence:
        bare = name.rstrip("?*")
        if name.endswith("*"):
            while i < len(tags) and tags[i] == bare:
                i += 1
        elif i < len(tags) and tags[i] == bare:
            i += 1
        elif not name.endswith("?"):
            return False
    return i == len(tags)


def read_xml(path):
    """Like ``read_kvn``, checking every element against the OEM schema's sequences on the way."""
    root = ElementTree.parse(path).getroot()
    assert root.tag == "oem" and root.get("id") == "CCSDS_OEM_VERS" and root.get("version") == "2.0"
    assert [e.tag for e in root] == ["header", "body"]
    header = root.find("header")
    assert follows([e.tag for e in header], HEADER)
    segments = root.find("body").findall("segment")
    assert len(segments) == 1 and [e.tag for e in segments[0]] == ["metadata", "data"]
    meta, data = segments[0]
    assert follows([e.tag for e in meta], METADATA)
    tags = [e.tag for e in data]
    n_comments = tags.count("COMMENT")
    n_states = tags.count("stateVector")
    assert tags == ["COMMENT"] * n_comments + ["stateVector"] * n_states + ["covarianceMatrix"] * (
        len(tags) - n_comments - n_states)
    keys = {e.tag: e.text for e in [*header, *meta] if e.tag != "COMMENT"}
    states = []
    for vector in data.findall("stateVector"):
        assert follows([e.tag for e in vector], STATE)
        states.append((vector.findtext("EPOCH"), [float(vector.findtext(k)) for k in STATE[1:7]]))
    covariances = []
    for cov in data.findall("covarianceMatrix"):
        assert follows([e.tag for e in cov], COVARIANCE)
        values = iter(float(cov.findtext(k)) for k in covariance_keys())
        rows = [[next(values) for _ in range(i + 1)] for i in range(6)]
        covariances.append((cov.findtext("EPOCH"), cov.findtext("COV_REF_FRAME"), _symmetric(rows)))
    return keys, states, covariances


def utc_seconds(text: str) -> float:
    return tt_seconds_from_utc(dt.datetime.fromisoformat(text))


# --- the states --------------------------------------------------------------------------------------------

def test_boundary_records_invert_exactly():
    """``mee_of_boundary`` undoes ``predictor.boundary_elements`` (the loop's record) to rounding, e up to 0.1."""
    rng = np.random.default_rng(3)
    n = 200
    e, w = rng.uniform(0, 0.1, n), rng.uniform(0, 2 * np.pi, n)
    mee = np.stack([rng.uniform(4.0e7, 4.4e7, n), e * np.cos(w), e * np.sin(w), rng.uniform(-0.1, 0.1, n),
                    rng.uniform(-0.1, 0.1, n), rng.uniform(-np.pi, np.pi, n)], -1)
    angle = rng.uniform(0, 2 * np.pi, n)
    records = np.asarray(jnp.stack([boundary_elements(jnp.asarray(m), a) for m, a in zip(mee, angle)]))
    back = trajectory.mee_of_boundary(records, angle)
    np.testing.assert_allclose(back[:, 0], mee[:, 0], rtol=1e-14)
    np.testing.assert_allclose(back[:, 1:5], mee[:, 1:5], atol=1e-16)
    np.testing.assert_allclose(np.mod(back[:, 5] - mee[:, 5] + np.pi, 2 * np.pi) - np.pi, 0.0, atol=1e-13)


def test_first_state_is_the_initial_state_and_last_the_final(run):
    """The state rebuilt from cycle 0's boundary record is the scenario's initial state (a second route: its
    orbit as given, to Cartesian), to the float64 rounding of a GEO radius."""
    t, r, v = trajectory.cycle_states(run)
    mu = float(run.params.forces.mu_m3_s2)
    to_rv = DYNAMICS[run.scenario.dynamics].to_cartesian
    initial, final = (np.asarray(to_rv(np.asarray(o), mu)) for o in (run.params.initial.orbit, run.final.orbit))
    assert len(t) == DAYS + 1 and t[0] == run.scenario.epoch_tt_s
    np.testing.assert_allclose(r[0], initial[:3], rtol=0, atol=1e-7)
    np.testing.assert_allclose(v[0], initial[3:], rtol=0, atol=1e-11)
    np.testing.assert_array_equal(np.hstack([r[-1], v[-1]]), final)
    np.testing.assert_allclose(np.diff(t), 86164.0905, atol=1e-6)  # one sidereal day apart
    assert np.all(np.abs(np.linalg.norm(r, axis=1) - 42164.17e3) < 20e3)  # at GEO radius


@pytest.mark.parametrize("suffix, frame, time_system", [(".oem", "EME2000", "UTC"), (".xml", "MOD", "TT")])
def test_oem_read_back_equals_the_run(run, tmp_path, suffix, frame, time_system):
    """Both encodings, read by this file's readers: metadata as the standard names it, epochs and states equal
    to the run's to the printed digits; EME2000 against ERFA's IAU 1976 precession matrix (``erfa.pmat76``)."""
    written = run.save_oem(tmp_path / f"run{suffix}", frame=frame, time_system=time_system)
    assert [p.name for p in written] == [f"run{suffix}", "run-burns.csv"]
    keys, states, covariances = (read_xml if suffix == ".xml" else read_kvn)(written[0])
    if suffix == ".oem":
        assert keys["CCSDS_OEM_VERS"] == "2.0"
    assert (keys["CENTER_NAME"], keys["REF_FRAME"], keys["TIME_SYSTEM"]) == ("EARTH", frame, time_system)
    assert keys["OBJECT_NAME"] == "li2022-qffc" and not covariances
    assert (keys["START_TIME"], keys["STOP_TIME"]) == (states[0][0], states[-1][0])
    t, r, v = trajectory.cycle_states(run)
    if time_system == "UTC":
        assert states[0][0].startswith(run.scenario.config["epoch"]["utc"])  # 2020-01-01T12:00:00
        seconds = np.array([utc_seconds(epoch) for epoch, _ in states])
    else:
        assert keys["REF_FRAME_EPOCH"] == states[0][0]
        seconds = np.array([(dt.datetime.fromisoformat(e) - dt.datetime(2000, 1, 1, 12)).total_seconds()
                            for e, _ in states])
    np.testing.assert_allclose(seconds, t, rtol=0, atol=1e-6)
    if frame == "EME2000":
        precession = __import__("erfa").pmat76(JD_J2000, run.scenario.epoch_tt_s / SECONDS_PER_DAY)
        r, v = r @ precession, v @ precession  # r_J2000 = P^T r_epoch, on rows
    got = np.array([numbers for _, numbers in states])
    np.testing.assert_allclose(got[:, :3], r / 1e3, rtol=0, atol=0.5e-9 + 1e-10)  # 9 decimals of km
    np.testing.assert_allclose(got[:, 3:], v / 1e3, rtol=0, atol=0.5e-12 + 1e-13)  # 12 decimals of km/s


def test_covariance_blocks_read_back(tmp_path):
    """Covariance blocks (a navigation filter's: tests/test_ccsds.py): the KVN lower triangle and the XML CX_X ... CZ_DOT_Z_DOT
    elements give back the symmetric matrix to the printed 8 digits."""
    rng = np.random.default_rng(0)
    a = rng.normal(size=(6, 6))
    cov = a @ a.T * 1e-6
    meta = Metadata("SAT", "2020-001A", "EME2000", "UTC", "2020-01-01T00:00:00", "2020-01-01T00:01:00")
    epochs = ["2020-01-01T00:00:00", "2020-01-01T00:01:00"]
    for name, read in (("c.oem", read_kvn), ("c.xml", read_xml)):
        path = write_oem(tmp_path / name, meta, epochs, np.ones((2, 6)),
                         covariances=(Covariance(epochs[0], cov, "RTN"), Covariance(epochs[1], 2 * cov)))
        _, states, covariances = read(path)
        assert len(states) == 2 and [(c[0], c[1]) for c in covariances] == [(epochs[0], "RTN"), (epochs[1], None)]
        np.testing.assert_allclose(covariances[0][2], cov, rtol=1e-7)
        np.testing.assert_allclose(covariances[1][2], 2 * cov, rtol=1e-7)


def test_ccsds_ndm_reads_both_encodings(run, tmp_path):
    """``ccsds-ndm`` (classes generated from the NDM/XML 2.0 schemas) reads the KVN and the XML file, with the
    states as written, and writes the XML back with the same element sequence as ours (its serialiser follows
    the schema's order)."""
    ndm = pytest.importorskip("ccsds_ndm.ndm_io")
    io = ndm.NdmIo()
    kvn, xml = (run.save_oem(tmp_path / f"run.{s}", burns_csv=False)[0] for s in ("oem", "xml"))
    _, ours, _ = read_kvn(kvn)
    for path in (kvn, xml):
        message = io.from_path(path)
        segment = message.body.segment[0]
        frame = segment.metadata.ref_frame
        assert getattr(frame, "value", frame) == "EME2000"
        vectors = segment.data.state_vector
        got = [[float(getattr(s, k).value) for k in ("x", "y", "z", "x_dot", "y_dot", "z_dot")] for s in vectors]
        np.testing.assert_array_equal(got, [numbers for _, numbers in ours])
        again = io.to_string(message, ndm.NDMFileFormats.XML)
        theirs = [e.tag.split("}")[-1] for e in ElementTree.fromstring(again.encode()).iter()]
        assert theirs == [e.tag for e in ElementTree.parse(xml).getroot().iter()]


def test_estimate_without_a_filter_is_the_gaussian_fix(tmp_path):
    """``of="estimate"`` without a filter (li2022-qffc with H_rv = 1): the fix at each cycle start, its diagonal
    covariance Li 2022's 1-sigma (eq. 48: 3-sigma 0.3 m and 5e-5 m/s per component, times H_rv), its error within
    5 sigma of the truth and not zero."""
    run = rollout.simulate(scenario.load("li2022-qffc", {"duration.days": DAYS, "errors.h_rv": 1.0}), 0)
    keys, states, covariances = read_kvn(run.save_oem(tmp_path / "e.oem", of="estimate", burns_csv=False)[0])
    _, truth, _ = read_kvn(run.save_oem(tmp_path / "t.oem", burns_csv=False)[0])
    assert len(states) == DAYS and [e for e, _ in states] == [e for e, _ in truth[:-1]]
    assert "INTERPOLATION" not in keys and len(covariances) == DAYS
    h_rv = run.scenario.config["errors"]["h_rv"]
    sigma_km = h_rv * np.repeat([0.3 / 3, 5e-5 / 3], 3) / 1e3
    np.testing.assert_allclose(covariances[0][2], np.diag(sigma_km**2), rtol=1e-7, atol=1e-20)  # rotated: 1e-27
    error = np.array([s for _, s in states]) - np.array([s for _, s in truth[:-1]])
    assert np.all(np.abs(error) < 5 * sigma_km) and np.any(np.abs(error) > 0.1 * sigma_km)


def test_opm_maneuvers_equal_the_run(run, tmp_path):
    """``ccsds-ndm`` reads the OPM: one maneuver block per burn (``burns_total``), their ΔV sums to the Delta-V the
    loop integrated and their propellant to ``mass_used_kg`` (no execution errors in li2022-qffc), and the sums of
    |MAN_DV_1|, |MAN_DV_2|, |MAN_DV_3| (RTN) to ``dv_radial_per_year_mps``, ``dv_ew_per_year_mps`` and
    ``dv_ns_per_year_mps`` over the run: the budget per axis is the file's, burn by burn through the rocket
    equation against the loop's per-cycle Delta-V split by firing time."""
    ndm = pytest.importorskip("ccsds_ndm.ndm_io")
    blocks = ndm.NdmIo().from_path(run.save_maneuvers(tmp_path / "m.opm")).body.segment.data.maneuver_parameters
    assert len(blocks) == run.metrics["burns_total"] > 0
    dv = np.array([[float(getattr(b, f"man_dv_{i}").value) for i in (1, 2, 3)] for b in blocks]) * 1e3
    delivered = float(run.final.dv_mps - run.params.initial.dv_mps)
    assert abs(np.linalg.norm(dv, axis=1).sum() - delivered) < 1e-8 * len(blocks) + 1e-9 * delivered
    used = -sum(float(b.man_delta_mass.value) for b in blocks)
    assert abs(used - run.metrics["mass_used_kg"]) < 1e-9 * len(blocks)  # 9 decimals of kg printed per burn
    run_s = DAYS * 86164.0905
    per_axis = np.abs(dv).sum(axis=0) * 365.25 * SECONDS_PER_DAY / run_s
    names = ("dv_radial_per_year_mps", "dv_ew_per_year_mps", "dv_ns_per_year_mps")
    np.testing.assert_allclose(per_axis, [run.metrics[name] for name in names], rtol=1e-6)
    assert np.all(per_axis > 0.01 * run.metrics["dv_per_year_mps"])  # every axis flown, so each sum is checked
    assert np.linalg.norm(dv, axis=1).sum() < np.abs(dv).sum()  # components: the burns are not along one axis



def test_summary_says_what_each_delta_v_component_is(run):
    """The printed budget names each component's axis, the radial one as the arms' cosine loss, and says the three
    are components, not a partition; a run of 3 days says its yearly rates are extrapolated."""
    lines = run.summary()
    row = {line.split()[0]: line for line in lines if line.startswith("  dv_")}
    assert "radial (RTN R)" in row["dv_radial_per_year_mps"] and "cosine loss" in row["dv_radial_per_year_mps"]
    assert "along-track (RTN T)" in row["dv_ew_per_year_mps"]
    assert "cross-track (RTN N)" in row["dv_ns_per_year_mps"]
    assert all("extrapolated from" in row[name] for name in row if name.endswith("_per_year_mps"))
    assert any("not a partition" in line for line in lines)

# --- the burns ---------------------------------------------------------------------------------------------

def test_burn_list_sums_to_the_delivered_delta_v(run, tmp_path):
    """The CSV's Delta-V (thrust x firing time through the rocket equation) sums to the Delta-V the loop
    integrated, per cycle and in all; each burn's mid-time is where the plan's clock (the true longitude of the
    cycle's start state, advancing 2 pi per cycle) reaches the longitude the QFFC centred it on (l_1, l_2)."""
    path = run.save_oem(tmp_path / "run.oem")[1]
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    assert list(rows[0]) == list(trajectory.BURN_COLUMNS)
    cycle = np.array([int(r["cycle"]) for r in rows])
    dv = np.array([float(r["dv_mps"]) for r in rows])
    rtn = np.array([[float(r[k]) for k in ("dv_r_mps", "dv_t_mps", "dv_n_mps")] for r in rows])
    np.testing.assert_allclose(np.linalg.norm(rtn, axis=1), dv, atol=2e-9)
    delivered = float(run.final.dv_mps - run.params.initial.dv_mps)
    assert delivered > 0.1 and abs(dv.sum() - delivered) < 1e-8 * len(rows) + 1e-9 * delivered
    per_cycle = np.bincount(cycle, weights=dv, minlength=DAYS)
    np.testing.assert_allclose(per_cycle, run.records.cycles.dv_mps, rtol=1e-9, atol=1e-8)
    start_tt = np.array([float(r["start_tt_s"]) for r in rows])
    np.testing.assert_allclose([utc_seconds(r["start_utc"]) for r in rows], start_tt, atol=1e-6)
    duration = np.array([float(r["duration_s"]) for r in rows])
    thruster = np.array([int(r["thruster"]) for r in rows])
    t_cycle, r, v = trajectory.cycle_states(run)
    cycle_s = np.diff(t_cycle)[0]
    mid = (start_tt + duration / 2 - t_cycle[cycle]) / cycle_s  # fraction of the cycle
    assert np.all((mid > 0) & (mid < 1)) and np.all(np.diff(start_tt) > 0)
    true_lon = np.asarray(cartesian_to_mee(r, v, float(run.params.forces.mu_m3_s2)))[:, 5]  # L at cycle starts
    planned = np.asarray(run.records.cycles.controller["burns"].l_rad)[cycle, thruster - 1]
    reached = true_lon[cycle] + 2 * np.pi * mid  # the plan's clock: L advances 2 pi per cycle
    inside = (start_tt > t_cycle[cycle] + 1) & (start_tt + duration < t_cycle[cycle + 1] - 1)  # not clipped
    assert inside.sum() >= len(rows) - 2
    miss = np.mod(reached - planned + np.pi, 2 * np.pi) - np.pi
    assert np.all(np.abs(miss[inside]) < 1e-4), miss  # 1.4 s of the cycle (no shadow in January)


def test_simulate_oem_flag_writes_the_files(run, tmp_path, monkeypatch, capsys):
    """``geojax simulate --oem FILE`` writes the OEM and the burn list and names them; a folder is refused in
    one line naming --oem, before any run."""
    monkeypatch.setattr(rollout, "simulate", lambda *a, **k: run)
    path = tmp_path / "out" / "run.xml"
    assert cli.main(["simulate", "li2022-qffc", "--days", str(DAYS), "--oem", str(path), "-q"]) == 0
    assert path.exists() and (tmp_path / "out" / "run-burns.csv").exists()
    assert f"wrote {path} and {tmp_path / 'out' / 'run-burns.csv'}" in capsys.readouterr().out
    monkeypatch.setattr(rollout, "simulate", lambda *a, **k: pytest.fail("ran before checking --oem"))
    assert cli.main(["simulate", "li2022-qffc", "--oem", str(tmp_path)]) == 2
    assert f"--oem '{tmp_path}': is a folder" in capsys.readouterr().err


def test_save_oem_refuses_unknown_frames_and_time_systems(run, tmp_path):
    with pytest.raises(ValueError, match="frame: must be one of EME2000, MOD"):
        run.save_oem(tmp_path / "a.oem", frame="GCRF")
    with pytest.raises(ValueError, match="time_system: must be one of UTC, TT"):
        run.save_oem(tmp_path / "a.oem", time_system="GPS")


def test_a_burn_planned_in_the_shadow_starts_when_the_shadow_ends():
    """``burns.firing_start_s`` against a sunlit clock written by hand: 10 s steps, the third and fourth in
    shadow (the clock stands at 20 s), the fifth half sunlit."""
    from geojax.control.burns import firing_start_s

    clock = jnp.array([0.0, 10.0, 20.0, 20.0, 20.0, 25.0, 35.0])
    starts = firing_start_s(clock, jnp.array([15.0, 20.0, 22.5, 0.0]), 10.0)
    np.testing.assert_allclose(starts, [15.0, 40.0, 45.0, 0.0])
