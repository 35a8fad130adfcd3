"""Actuator drives behind one interface (:mod:`pressfit.dynamics.drives.base`): the ideal force source, the
servo motor + ball screw, the servo-hydraulic cylinder and the direct-drive linear motor, picked by the
machine's drive table (:data:`DRIVES`; the tables by kind name: :data:`pressfit.description.machine.DRIVE_TABLES`).
A new kind is one module and one line here (and its table's line there)."""

from __future__ import annotations

from pressfit.description import machine as schema
from pressfit.description.machine import Machine
from pressfit.dynamics.drives.base import Drive
from pressfit.dynamics.drives.electric import ElectricDrive
from pressfit.dynamics.drives.force import ForceDrive
from pressfit.dynamics.drives.hydraulic import HydraulicDrive
from pressfit.dynamics.drives.linear_motor import LinearMotorDrive
from pressfit.errors import PressfitError

# schema table -> drive (each with ``of(machine)``): the only place a drive kind is mapped to its dynamics
DRIVES: dict[type[schema.DriveTable], type] = {
    schema.ForceSource: ForceDrive,
    schema.ElectricDrive: ElectricDrive,
    schema.HydraulicDrive: HydraulicDrive,
    schema.LinearMotorDrive: LinearMotorDrive,
}


def drive_type(machine: Machine) -> type:
    """The drive class of the machine's drive table (:data:`DRIVES`), for its flags without building it."""
    table = type(machine.actuator.table)
    if table not in DRIVES:
        raise PressfitError(f"{machine.source or machine.name}: key 'actuator.kind': the drive table "
                            f"{table.__name__} has no drive in pressfit.dynamics.drives.DRIVES")
    return DRIVES[table]


def by_kind(kind: str) -> type:
    """The drive class whose ``kind`` is ``kind`` (:data:`DRIVES`; the name a run's summary records)."""
    for drive in DRIVES.values():
        if drive.kind == kind:
            return drive
    raise PressfitError(f"unknown drive kind {kind!r} (known: {', '.join(d.kind for d in DRIVES.values())})")


def of(machine: Machine) -> Drive:
    """The machine's drive model (:data:`DRIVES`)."""
    return drive_type(machine).of(machine)


__all__ = ["DRIVES", "Drive", "ElectricDrive", "ForceDrive", "HydraulicDrive", "LinearMotorDrive", "by_kind",
           "drive_type", "of"]
