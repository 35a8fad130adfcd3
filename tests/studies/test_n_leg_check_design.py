"""`pressfit check` (studies/limit_check.py) and the design study (studies/design.py) with n legs (issue 21 item 1,
phase 3), on Tsai's 3-UPU: statically determinate, its actuator forces are A^-1 W whatever the stiffnesses (the
reference of both tests, computed independently by pressfit.kinematics)."""

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pressfit import kinematics
from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.errors import PreloadError
from pressfit.kinematics.workspace import workspace_box
from pressfit.studies import design, limit_check

ROOT = Path(__file__).resolve().parents[2]
TSAI = ROOT / "models" / "tsai_3upu.toml"
POSES = [[0.0, 0.62, 0.0], [0.1, 0.55, -0.1], [-0.2, 0.7, 0.2]]
LOAD = [0.0, -700.0, 0.0]


def _check_case(tmp_path, preload: str = "") -> Path:
    path = tmp_path / "check.toml"
    path.write_text(f'name = "tsai-check"\nmodel = "{TSAI}"\n{preload}\n[poses]\npoints_m = {POSES}\n'
                    f"[loads]\nforce_n = {LOAD}\n[solver]\nlinear = true\nrefine_worst = 3\n"
                    "[envelope]\nmax_compression_n = 300.0\nmax_actuator_force_n = 600.0\n")
    return path


def test_tsai_check_finds_the_determinate_worst_actuator_force(tmp_path):
    """The limit check on the 3-UPU (linear solves at every pose): its worst actuator force and leg are those of
    A^-1 W over the poses (to 1e-9, the linear solve's residual), the leg one of 1..3; the CLI exits 1 on the
    compression limit it exceeds (the worst 595 N against 300 N)."""
    path = _check_case(tmp_path)
    lines = {line.key: line for line in limit_check.evaluate_envelope(load_case(path)).limits}
    forces = np.array([kinematics.actuator_forces_min_norm(load_case(path).machine(), np.array(p), -np.array(LOAD))
                       for p in POSES])
    worst = np.unravel_index(np.argmax(np.abs(forces)), forces.shape)
    line = lines["max_actuator_force_n"]
    assert line.worst == pytest.approx(np.abs(forces).max(), rel=1e-9)
    assert line.leg == worst[1] + 1 and line.pose_m == POSES[worst[0]] and line.passed
    assert not lines["max_compression_n"].passed
    assert CliRunner().invoke(main, ["check", str(path)]).exit_code == 1


def test_tsai_check_refuses_a_preload(tmp_path):
    """A 3-leg machine has no preload space: the check refuses a case's a4_n (PreloadError), it never ignores it."""
    with pytest.raises(PreloadError, match="no redundant actuation"):
        limit_check.evaluate_envelope(load_case(_check_case(tmp_path, "[preload]\na4_n = 40.0\n")))


def test_tsai_design_peak_axial_force_is_the_determinate_one(tmp_path):
    """One design of the design study on the 3-UPU (its own p and r, a stiffer actuator): the peak axial force
    is the largest |A^-1 W| over the reachable grid and the cone's wrenches (1e-6: the condensed model's legs
    carry the actuator force, no shear at linear order), and the study's other metrics are finite."""
    text = (ROOT / "cases" / "studies" / "design_sections.toml").read_text()
    path = tmp_path / "design.toml"
    path.write_text(f'model = "{TSAI}"\n' + text)
    plan = design.plan_from_case(load_case(path))
    params = {"base_half_side_m": 0.442, "plate_half_side_m": 0.082, "cylinder_outer_diameter_m": 0.06,
              "stem_diameter_m": 0.03, "actuator_axial_stiffness_n_per_m": 5e7}
    metrics = design.evaluate_design(plan, params)
    machine = design.design_machine(plan, params)
    d = plan.design
    poses = workspace_box(machine, np.linspace(*d.heights_m, d.height_levels), d.grid_xz).reshape(-1, 3)
    poses = poses[kinematics.is_reachable(machine, poses)]
    peak = max(np.abs(kinematics.actuator_forces_min_norm(machine, poses, w[:3])).max() for w in plan.wrenches)
    assert metrics["peak_axial_force_n"] == pytest.approx(peak, rel=1e-6)
    assert all(np.isfinite(v) for v in metrics.values())
