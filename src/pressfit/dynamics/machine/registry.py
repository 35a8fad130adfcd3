"""The dynamics models' one registry: ``MODELS`` maps the name a case file gives (``[simulation] model``,
``[cycle] model``, ``--model``) to the model's scenario class (:class:`pressfit.dynamics.series.ScenarioStep`).
A new model is one module and one line here; everything else asks the class (:func:`model_kind`) for its
capabilities (``elastic``, ``integrator_error``), never the name.
"""

from __future__ import annotations

from pressfit.dynamics.machine.flexible_scenario import FlexibleScenario
from pressfit.dynamics.machine.rigid import RigidScenario
from pressfit.errors import PressfitError

MODELS = {
    "flexible": FlexibleScenario,
    "rigid": RigidScenario,
}


def model_kind(name: str) -> type[FlexibleScenario | RigidScenario]:
    """The scenario class of the model ``name`` (the one reader of a model's name)."""
    try:
        return MODELS[name]
    except KeyError:
        raise PressfitError(f"model must be {' or '.join(repr(m) for m in MODELS)}, got {name!r}") from None
