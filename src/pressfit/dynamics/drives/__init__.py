"""Actuator drives behind one interface (:mod:`pressfit.dynamics.drives.base`): the ideal force source, the
servo motor + ball screw and the servo-hydraulic cylinder, picked by ``[actuator] kind`` (:func:`of`)."""

from __future__ import annotations

from pressfit.description.machine import Machine
from pressfit.dynamics.drives.base import Drive
from pressfit.dynamics.drives.electric import ElectricDrive
from pressfit.dynamics.drives.force import ForceDrive
from pressfit.dynamics.drives.hydraulic import HydraulicDrive


def of(machine: Machine) -> Drive:
    """The machine's drive model, by ``machine.actuator.kind``."""
    kind = machine.actuator.kind
    if kind == "electric":
        return ElectricDrive(machine)
    if kind == "hydraulic":
        return HydraulicDrive(machine)
    return ForceDrive.of(machine)


__all__ = ["Drive", "ElectricDrive", "ForceDrive", "HydraulicDrive", "of"]
