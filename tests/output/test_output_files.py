"""Output and input files (issue 10, "Bad input, files and signals"): atomic writes honour the umask and
write through symlinks; nothing partial is left after an error, Ctrl-C or SIGTERM; colliding map names
are refused; input files must be regular and small (a FIFO or /dev/zero is refused at once)."""

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from pressfit.cli import _Group, main
from pressfit.description.machine import read_toml
from pressfit.errors import ModelFileError, OutputError, OutputExistsError
from pressfit.output.files import write_directory, write_text


@pytest.mark.parametrize("mask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_new_files_honour_the_umask(tmp_path, mask, mode):
    old = os.umask(mask)
    try:
        path = write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(old)
    assert path.stat().st_mode & 0o777 == mode


def test_writes_go_through_a_symlink_to_its_target(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    with pytest.raises(Exception, match="exists"):
        write_text(link, "new")
    write_text(link, "new", overwrite=True)
    assert link.is_symlink() and target.read_text() == "new"


def leftovers(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def test_an_interrupted_multi_file_output_leaves_nothing(tmp_path):
    def write(tmp):
        write_text(tmp / "first.csv", "1")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_directory(tmp_path / "out", False, write)
    assert leftovers(tmp_path) == []


def test_sigterm_during_output_leaves_no_partial_or_temporary_file(tmp_path):
    """The CLI turns SIGTERM into an unwinding exit (143), so the staged directory is removed."""
    group = _Group()

    @group.command()
    def boom() -> None:
        write_directory(tmp_path / "out", False,
                        lambda tmp: [write_text(tmp / "a.csv", "1"), os.kill(os.getpid(), signal.SIGTERM)])

    res = CliRunner().invoke(group, ["boom"])
    assert res.exit_code == 128 + signal.SIGTERM
    assert leftovers(tmp_path) == []


def test_output_directory_checks(tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(OutputError, match="not a directory") as refused:
        write_directory(tmp_path / "afile", True, lambda tmp: [])
    assert refused.value.path == str(tmp_path / "afile")  # the refused output, as data
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "keep.txt").write_text("x")
    with pytest.raises(OutputExistsError, match="not empty") as refused:
        write_directory(tmp_path / "full", False, lambda tmp: [])
    assert refused.value.path == str(tmp_path / "full")


def test_workspace_refuses_heights_that_share_a_file_name(tmp_path):
    res = CliRunner().invoke(main, ["workspace", "--y", "0.6", "--y", "0.6004", "--out", str(tmp_path / "ws"),
                                    "--no-progress"])
    assert res.exit_code == 2 and "same files" in res.stderr
    assert leftovers(tmp_path) == []


def test_special_and_oversized_input_files_are_refused(tmp_path):
    fifo = tmp_path / "case.toml"
    os.mkfifo(fifo)
    with pytest.raises(ModelFileError, match="regular file"):
        read_toml(fifo)
    big = tmp_path / "big.toml"
    with big.open("wb") as f:
        f.truncate(20_000_000)  # sparse: no disk used
    with pytest.raises(ModelFileError, match="at most"):
        read_toml(big)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["fifo", "/dev/zero"])
def test_check_of_a_fifo_or_device_returns_at_once(tmp_path, name):
    """In a subprocess with a timeout: reading a FIFO blocks and /dev/zero never ends without the stat check."""
    path = tmp_path / "c.toml" if name == "fifo" else Path(name)
    if name == "fifo":
        os.mkfifo(path)
    res = subprocess.run([sys.executable, "-m", "pressfit", "check", str(path)], capture_output=True, text=True,
                         timeout=60)
    assert res.returncode == 2 and "regular file" in res.stderr and len(res.stderr.splitlines()) == 1


def test_json_writes_a_non_finite_figure_as_null():
    """An unbounded figure (the settling time of a force that never settled, reported as infinite beside its failed
    verdict; a pin never touched) is JSON null, not an internal error (json's allow_nan=False raised ValueError)."""
    import json

    import numpy as np

    from pressfit.output.files import to_json

    data = {"settling_time_s": float("inf"), "alignment_m": np.float64("nan"), "rms_n": np.array([1.0, np.inf]),
            "rows": [{"peak_n": -np.inf, "passed": False}], "count": 3}
    assert json.loads(to_json(data)) == {"settling_time_s": None, "alignment_m": None, "rms_n": [1.0, None],
                                         "rows": [{"peak_n": None, "passed": False}], "count": 3}
