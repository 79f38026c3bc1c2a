"""``studies/compare/table.py``'s window search: the window it scales with the box and the rule that picks the best
setting, each against an independent check."""

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from geojax.physics.constants import MU_EARTH_M3_S2
from geojax.physics.elements import mee_to_cartesian

STUDY = Path(__file__).resolve().parents[1] / "studies" / "compare" / "table.py"


def load():
    spec = importlib.util.spec_from_file_location("compare_table", STUDY)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("box_deg", [0.02, 0.05, 0.1])
def test_the_box_radius_in_h_k_reaches_the_box_latitude(box_deg):
    # Independent: an orbit of MEE (h, k) = (box_hk, 0), propagated to the top of its path (true longitude 90 deg
    # from the node, which is at 0 for k = 0) by the Cartesian conversion, has its sub-satellite latitude at
    # asin(z / r): that must be the box half-width, so a window of a fraction f of box_hk keeps i below f x box.
    table = load()
    mee = np.array([42164.0e3, 0.0, 0.0, table.box_hk(box_deg), 0.0, math.pi / 2])
    r, _ = mee_to_cartesian(mee, MU_EARTH_M3_S2)
    r = np.asarray(r)
    assert math.degrees(math.asin(r[2] / np.linalg.norm(r))) == pytest.approx(box_deg, rel=1e-12)
    station = {"ex": 0.0, "ey": 1e-4}
    for candidate in table.mpc_window(box_deg, station) + table.fompc_window(box_deg, station):
        assert candidate["controller.di_max"] < table.box_hk(box_deg)
    # The MPC's default window at 0.05 deg (e_max 2e-4, margin 0.005 deg) is what the scaling gives there.
    at_default = table.mpc_window(0.05, station)[0]
    assert at_default["controller.e_max"] == pytest.approx(2e-4, rel=0.01)
    assert at_default["controller.lon_margin_deg"] == pytest.approx(0.005, rel=1e-12)


def test_the_best_setting_is_the_cheapest_that_holds_the_box():
    table = load()
    runs = [{"status": 0, "dv_steady_per_year_mps": 55.0}, {"status": 2, "dv_steady_per_year_mps": 50.0},
            {"status": 0, "dv_steady_per_year_mps": 53.0}, {"status": 1, "dv_steady_per_year_mps": 52.0}]
    assert table.best_index(runs) == 2  # the cheaper ones left the box (2) or left cycles unsolved (1)
    assert table.best_index([{"status": 3, "dv_steady_per_year_mps": 40.0}]) is None
