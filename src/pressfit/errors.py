"""The package's exceptions: every failure a user can cause derives from :class:`PressfitError`."""

from __future__ import annotations


class PressfitError(Exception):
    """Base class of every error pressfit raises on purpose (the CLI turns it into exit code 2)."""


class ModelFileError(PressfitError):
    """A machine or case file is malformed: names the file, the key and what was expected."""

    def __init__(self, path: object, key: str, expected: str) -> None:
        self.path, self.key, self.expected = str(path), key, expected
        super().__init__(f"{self.path}: key '{key}': {expected}")


class UnreachablePoseError(PressfitError):
    """A plate pose breaks a joint limit; ``violations`` lists (leg, quantity, value, limit)."""

    def __init__(self, pose_m: object, violations: list[tuple[int, str, float, str]]) -> None:
        self.pose_m, self.violations = pose_m, violations
        lines = [(f"leg {leg}: " if leg else "") + f"{what} = {value:.6g} breaks {limit}"
                 for leg, what, value, limit in violations]
        pose = tuple(float(c) for c in pose_m)  # type: ignore[union-attr]
        super().__init__(f"pose {pose} m is not reachable: " + "; ".join(lines))


class SingularPoseError(PressfitError):
    """The static matrix or the stiffness is singular at this pose."""


class ConvergenceError(PressfitError):
    """An iterative solver stopped before meeting its tolerance; carries the residual reached."""

    def __init__(self, what: str, residual: float, tolerance: float, iterations: int) -> None:
        self.residual, self.tolerance, self.iterations = residual, tolerance, iterations
        super().__init__(
            f"{what} did not converge: residual {residual:.3e} > tolerance {tolerance:.1e} "
            f"after {iterations} iterations"
        )


class OutputExistsError(PressfitError):
    """An output file exists and overwriting was not requested."""


class OutputError(PressfitError):
    """An output file cannot be written (its directory is a file, or not writable)."""


class UnstableEquilibriumError(PressfitError):
    """The solution found is not a physical, stable state (a leg beyond buckling, a huge displacement)."""
