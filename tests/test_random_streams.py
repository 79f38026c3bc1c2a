"""Each part of the loop draws from its own named stream: adding or removing a part changes no other part's
draws (common random numbers for paired comparisons: wheels on and off, the filter on and off).

Independent check: the same seed run with and without a part; the other part's draws before the parts can
interact (the filter's error at the first cycle start, drawn from its initial covariance) are equal bit for
bit, and a part's id does not depend on the tuple's order.
"""

import numpy as np
import pytest

from geojax import scenario
from geojax.runner.rollout import simulate
from geojax.states import momentum
from geojax.states.base import RESERVED_STREAMS, StateModel, check_streams, stream_id


def test_the_filters_first_error_is_the_same_with_and_without_the_wheels():
    base = {"duration.days": 2}
    alone = simulate(scenario.load("li2022-qffc-ranging", base), seed=5)
    wheels = simulate(scenario.load("li2022-qffc-ranging", {**base, "attitude.wheels": True}), seed=5)
    first = [r.records.cycles.states["navigation"].error_rsw[0] for r in (alone, wheels)]
    assert np.array_equal(*first), first
    assert np.all(np.abs(first[0]) > 0)  # a drawn error, not a zero that would match trivially
    assert "wheels" in wheels.records.cycles.states and "wheels" not in alone.records.cycles.states


def test_a_parts_stream_is_its_names_not_its_place():
    other = momentum.MODEL._replace(name="other")
    assert stream_id(momentum.MODEL) != stream_id(other)
    assert stream_id(momentum.MODEL) not in RESERVED_STREAMS
    check_streams((momentum.MODEL, other))
    check_streams((other, momentum.MODEL))
    with pytest.raises(ValueError, match="also state 'wheels'"):
        check_streams((momentum.MODEL, other._replace(stream=stream_id(momentum.MODEL))))
    with pytest.raises(ValueError, match="reserved"):
        check_streams((other._replace(stream=1),))
    assert isinstance(momentum.MODEL, StateModel)
