"""The dynamics models' one registry: ``MODELS`` maps the name a case file gives (``[simulation] model``,
``[cycle] model``, ``--model``) to the model's scenario class (:class:`pressfit.dynamics.series.ScenarioStep`), as
``module:class`` (imported when asked for: the command line lists the names without loading the physics).
A new model is one module and one line here; the schema, the command line and the plans take the names from
here (:func:`model_names`, :func:`require_model`) and everything else asks the class (:func:`model_kind`) for
its capabilities (``elastic``, ``integrator_error``), never the name.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING

from pressfit.errors import ModelFileError, PressfitError

if TYPE_CHECKING:
    from pressfit.dynamics.machine.flexible_scenario import FlexibleScenario
    from pressfit.dynamics.machine.rigid import RigidScenario

MODELS = {
    "flexible": "pressfit.dynamics.machine.flexible_scenario:FlexibleScenario",
    "rigid": "pressfit.dynamics.machine.rigid:RigidScenario",
}


def model_names() -> tuple[str, ...]:
    """The registered models' names, in the registry's order."""
    return tuple(MODELS)


def model_kind(name: str) -> type[FlexibleScenario | RigidScenario]:
    """The scenario class of the model ``name`` (the one reader of a model's name)."""
    try:
        module, cls = MODELS[name].split(":")
    except KeyError:
        raise PressfitError(f"model must be {_choices()}, got {name!r}") from None
    return getattr(import_module(module), cls)


def require_model(path: object, key: str, name: str) -> None:
    """Refuse (ModelFileError naming the file ``path`` and the ``key``) a model name that is not registered: a plan
    checks its model before computing anything."""
    if name not in MODELS:
        raise ModelFileError(path, key, f"a dynamics model, {_choices()}, got {name!r}")


def _choices() -> str:
    return " or ".join(repr(m) for m in MODELS)
