"""The ``pressfit kinematics`` command (issue 2's acceptance check against the paper's Table 4)."""

import json

import numpy as np
from click.testing import CliRunner

from pressfit.cli import main


def test_kinematics_json_matches_table_4():
    """v_p at (0.1, 0.6, 0) as printed in Table 4, to its rounding (5e-4)."""
    res = CliRunner().invoke(main, ["kinematics", "0.1", "0.6", "0", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    np.testing.assert_allclose(out["preload_vector"], [-0.5, 0.463, -0.5, 0.535], rtol=0, atol=5e-4)
    assert out["reachable"] is True


def test_kinematics_unreachable_exits_2_naming_the_leg():
    """Leg 2 is shorter than l_min at (0.25, 0.45, 0): exit code 2, one-line message, no traceback."""
    res = CliRunner().invoke(main, ["kinematics", "0.25", "0.45", "0"])
    assert res.exit_code == 2
    assert "leg 2: leg length l [m]" in res.output and "minimum 0.5" in res.output
    assert "Traceback" not in res.output
