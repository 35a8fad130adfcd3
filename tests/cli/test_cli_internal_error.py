"""An unexpected exception (a bug, not bad input) exits 70 (EX_SOFTWARE of sysexits.h) with one line naming
it, never 1, which CI reads as "a limit is exceeded" (issue 18); PRESSFIT_TRACEBACK=1 adds the traceback."""

import subprocess
import sys

import pytest
from click.testing import CliRunner

import pressfit.kinematics
from pressfit.cli import main


@pytest.mark.parametrize("exc", [RuntimeError("solver state lost"), ZeroDivisionError("float division by zero"),
                                 MemoryError("cannot allocate 28 GiB")])
def test_an_unexpected_exception_exits_70_with_one_line(monkeypatch, exc):
    def boom(*args, **kwargs):
        raise exc

    monkeypatch.setattr(pressfit.kinematics, "pose_report", boom)
    monkeypatch.delenv("PRESSFIT_TRACEBACK", raising=False)
    res = CliRunner().invoke(main, ["kinematics", "0", "0.72", "0"])
    assert res.exit_code == 70, (res.output, res.exception)
    lines = [x for x in res.stderr.splitlines() if x.strip()]
    assert lines == [f"internal error: {type(exc).__name__}: {exc} (please report; run with PRESSFIT_TRACEBACK=1 "
                     "for the traceback)"], res.stderr
    assert "Traceback" not in res.output


SCRIPT = """
import sys
import pressfit.kinematics
from pressfit.cli import main
def boom(*a, **k):
    raise RuntimeError("boom")
pressfit.kinematics.pose_report = boom
main(["kinematics", "0", "0.72", "0"])
"""


@pytest.mark.parametrize("flag", ["", "1"])
def test_the_traceback_is_printed_only_when_asked(flag):
    env = {"PATH": "", "PRESSFIT_TRACEBACK": flag}
    res = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, timeout=120)
    assert res.returncode == 70, res.stderr
    assert res.stderr.strip().splitlines()[-1].startswith("internal error: RuntimeError: boom (please report")
    assert ("Traceback (most recent call last)" in res.stderr) == (flag == "1")
    if not flag:
        assert len(res.stderr.strip().splitlines()) == 1, res.stderr


def test_bad_input_still_exits_2_not_70():
    res = CliRunner().invoke(main, ["kinematics", "0", "5", "0"])  # unreachable: a PressfitError
    assert res.exit_code == 2 and res.stderr.startswith("error: "), res.output
