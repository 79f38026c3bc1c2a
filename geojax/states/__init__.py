"""Further states of the spacecraft that the closed loop carries (DESIGN.md layer 5), one module each on the
protocol of ``states.base``: the wheels' momentum (``states.momentum``) and the orbit-determination filter (``states.navigation``).  ``REGISTRY`` maps a model's name (its key
in the loop's records) to it; ``of_config`` picks those a scenario asks for (none by default: no state, no cost)."""

from geojax.states import momentum, navigation
from geojax.states.base import StateModel

REGISTRY: dict[str, StateModel] = {momentum.NAME: momentum.MODEL, navigation.NAME: navigation.MODEL}


def of_config(config: dict) -> tuple[StateModel, ...]:
    """The models a validated scenario table asks for, in a fixed order (static: they shape the compiled loop)."""
    wheels = (momentum.MODEL,) if config["attitude"]["wheels"] else ()
    nav = config["navigation"]
    # the wheels first: the filter's plan is the thrust after the dumping tilt (commanded, so known)
    return wheels + ((navigation.model(navigation.layout_of(nav)),) if nav["model"] == "ekf" else ())
