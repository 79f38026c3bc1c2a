"""Several satellites in one slot (``[[satellites]]``, ``geojax.scenario_cluster``): their closed loops in one
compiled program and the distance between them (``loop.cluster``), run and reported (``collocation.run``)."""

from geojax.collocation.run import ClusterResult, simulate_cluster

__all__ = ["ClusterResult", "simulate_cluster"]
