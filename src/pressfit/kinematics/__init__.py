"""Kinematics of the n-UPU machine: closed form (paper equations 1-10) and workspace maps."""

from pressfit.kinematics.closed_form import (
    Indices,
    LegKinematics,
    actuator_forces_min_norm,
    concurrency_point,
    dexterity,
    force_indices,
    indices,
    inverse_kinematics,
    is_reachable,
    jacobian,
    leg_frames,
    leg_vectors,
    limit_margins,
    pose_report,
    preload_basis,
    preload_vector,
    pseudo_inverse,
    reference_pose_m,
    require_all_reachable,
    require_reachable,
    static_matrix,
    unreachable_reason,
    violations,
)

__all__ = ["Indices", "LegKinematics", "actuator_forces_min_norm", "concurrency_point", "dexterity",
           "force_indices", "indices", "inverse_kinematics", "is_reachable", "jacobian", "leg_frames",
           "leg_vectors", "limit_margins", "pose_report", "preload_basis", "preload_vector", "pseudo_inverse",
           "reference_pose_m", "require_all_reachable", "require_reachable", "static_matrix", "unreachable_reason",
           "violations"]
