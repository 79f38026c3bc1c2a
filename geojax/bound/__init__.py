"""The minimum-fuel bound of a scenario (Gazzino 2016, Problem 3, as a linear program): ``bound``."""

from geojax.bound.program import Infeasible
from geojax.bound.run import BoundResult, bound, replay

__all__ = ["BoundResult", "Infeasible", "bound", "replay"]
