"""The null controller: no thrust.  Uncontrolled propagation and the predictor's reference run."""

from __future__ import annotations

from geojax.control.base import Controller, Spec, coast, no_plan, stateless_init

FIELDS: dict = {}
SPEC = Spec(FIELDS)
CONTROLLER = Controller(stateless_init, no_plan, coast)


def make(tables: list[dict]) -> Controller:
    return CONTROLLER
