"""Every shipped scenario family keeps its numbers bit for bit: short runs of the padded one-sample loop and of
the sweeps' plain scan (no part, the wheels, the navigation filter; the QFFC, FOMPC, zone NSSK and Katz's law)
against the stored numbers of ``tests/reference/numbers.npz``: bit for bit on the platform they were written on,
to 1e-6 relative on another (``write_numbers.platform``: XLA compiles for the host's CPU).

Independent check: numbers written by an earlier build (``tests/reference/write_numbers.py``, regenerated only
deliberately, when a change is meant to move numbers), so the comparison needs no git history.
"""

import importlib.util
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent / "reference"


def _writer():
    spec = importlib.util.spec_from_file_location("write_numbers", HERE / "write_numbers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_short_runs_of_every_family_give_the_stored_numbers_bit_for_bit():
    writer = _writer()
    with np.load(HERE / "numbers.npz") as data:
        stored = {k: data[k] for k in data.files}
    written_on = str(stored.pop("platform"))
    ours = writer.numbers()
    assert sorted(ours) == sorted(stored), set(ours) ^ set(stored)
    if writer.platform() == written_on:
        differ = [k for k in stored if not np.array_equal(ours[k], stored[k], equal_nan=True)]
    else:  # another CPU or jaxlib: the last bits move (the module's docstring), nothing beyond them; a number
        # that is rounding itself (the wheels' gravity-gradient impulse without gravity gradient, 4e-16 N m s)
        # moves by its own size, hence the floor of 1e-12 in its unit
        differ = [k for k in stored if not np.allclose(
            ours[k], stored[k], rtol=1e-6, equal_nan=True,
            atol=max(1e-9 * float(np.nanmax(np.abs(stored[k]), initial=0.0)), 1e-12))]
    assert not differ, (differ, f"stored on {written_on}, run on {writer.platform()}")
    assert any(k.startswith("ranging.records.cycles.states.navigation") for k in ours)
    assert any(k.startswith("momentum.records.cycles.states.wheels") for k in ours)
