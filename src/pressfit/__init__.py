"""pressfit: structural load and compliance analysis of the 4-UPU press-fit manipulator."""

from pressfit.description.machine import DEFAULT_MODEL, Machine, load_machine
from pressfit.errors import PressfitError

__all__ = ["DEFAULT_MODEL", "Machine", "PressfitError", "load_machine"]
__version__ = "0.1.0"
