"""The file contract of every command (issue 18): outputs are checked before computing and written through a
temporary directory moved in at the end (simulate, modes as every other command); of two runs writing one
directory the loser is refused at the move; an output that is another output or an input is refused up
front; modes and export-mjcf validate their coordinates and time step; a stem as wide as the cylinder bore is
refused by the machine schema."""

import threading
from pathlib import Path

import pytest
import tomli_w
from click.testing import CliRunner

import pressfit.output.modal
import pressfit.output.simulation
import pressfit.workflows.insertion_simulation
import pressfit.workflows.natural_modes
import pressfit.workflows.report
from pressfit.cli import main
from pressfit.description.machine import DEFAULT_MODEL, load_machine, read_toml
from pressfit.errors import ModelFileError, OutputExistsError, PressfitError
from pressfit.output.files import LOCK_NAME, write_directory, write_text

ROOT = Path(__file__).resolve().parents[2]
INSERTION = ROOT / "cases/paper/insertion.toml"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def one_error_line(res, *words):
    assert res.exit_code == 2, (res.output, res.exception)
    lines = [x for x in res.stderr.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


def tree(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


# --- item 2: simulate --out and modes --out ----------------------------------------------------------------
@pytest.mark.parametrize("command", [["simulate", INSERTION, "--no-progress"], ["modes", "0", "0.72", "0"]])
def test_a_non_empty_directory_is_refused_before_computing(tmp_path, monkeypatch, command):
    def never(*a, **k):
        raise AssertionError("computed before checking the output directory")

    monkeypatch.setattr(pressfit.workflows.insertion_simulation, "simulate_insertion", never)
    monkeypatch.setattr(pressfit.workflows.natural_modes, "natural_modes", never)
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.txt").write_text("keep")
    one_error_line(run(*command, "--out", out), str(out), "--overwrite")
    assert tree(tmp_path) == ["out", "out/mine.txt"] and (out / "mine.txt").read_text() == "keep"


@pytest.mark.slow
def test_modes_out_leaves_nothing_when_a_file_fails(tmp_path, monkeypatch):
    """modes.json and modes.csv are written before the figure: a failing figure must leave neither."""
    def failing_figure(modes):
        raise PressfitError("figure refused")

    monkeypatch.setattr(pressfit.output.modal, "modes_figure", failing_figure)
    one_error_line(run("modes", "0", "0.72", "0", "--out", tmp_path / "m"), "figure refused")
    assert tree(tmp_path) == []
    monkeypatch.undo()
    res = run("modes", "0", "0.72", "0", "--out", tmp_path / "m")
    assert res.exit_code == 0, res.output
    assert tree(tmp_path) == ["m", "m/modes.csv", "m/modes.json", "m/modes.png"]


@pytest.mark.slow
def test_simulate_out_leaves_nothing_when_a_file_fails(tmp_path, monkeypatch):
    def failing_figure(result, comparison=None):
        raise PressfitError("figure refused")

    monkeypatch.setattr(pressfit.output.simulation, "simulation_figure", failing_figure)
    one_error_line(run("simulate", INSERTION, "--no-limiter", "--no-progress", "--out", tmp_path / "s"),
                   "figure refused")
    assert tree(tmp_path) == []


# --- item 4: two runs writing one directory -------------------------------------------------------------
def other_run(out: Path) -> None:
    """A complete second run of the same contract into ``out``."""
    write_directory(out, False, lambda tmp: [write_text(tmp / "report.md", "the other run")])


@pytest.mark.parametrize("existing", [False, True])
def test_report_loses_to_a_run_that_filled_the_directory_meanwhile(tmp_path, monkeypatch, existing):
    """The race simulated: while this report computes, another run writes the same directory; this one must
    exit 2 naming the directory and leave the other's files as they are (today both exit 0 and the second
    replaces the first)."""
    out = tmp_path / "rep"
    if existing:
        out.mkdir()

    def fake_report(machine, tmp, **options):
        write_text(tmp / "tables.md", "mine")
        path = write_text(tmp / "report.md", "mine")
        other_run(out)
        return path

    monkeypatch.setattr(pressfit.workflows.report, "write_report", fake_report)
    one_error_line(run("report", "--out", out, "--quick"), str(out), "another run")
    assert tree(tmp_path) == ["rep", "rep/report.md"] and (out / "report.md").read_text() == "the other run"


def test_a_run_holding_the_directory_makes_the_other_fail(tmp_path):
    out = tmp_path / "d"
    out.mkdir()

    def write(tmp):
        (out / LOCK_NAME).mkdir()  # another run is moving its files in now
        return [write_text(tmp / "a.csv", "1")]

    with pytest.raises(OutputExistsError, match="being written by another pressfit run"):
        write_directory(out, True, write)
    (out / LOCK_NAME).rmdir()
    assert tree(tmp_path) == ["d"]


@pytest.mark.parametrize("existing", [False, True])
def test_two_concurrent_runs_one_wins(tmp_path, existing):
    """Two threads compute at once, both past the up-front check, then move: exactly one succeeds."""
    out = tmp_path / "d"
    if existing:
        out.mkdir()
    barrier = threading.Barrier(2)
    outcome: dict[str, object] = {}

    def job(name):
        def write(tmp):
            barrier.wait(timeout=30)
            return [write_text(tmp / "report.md", name), write_text(tmp / f"{name}.csv", name)]

        try:
            write_directory(out, False, write)
            outcome[name] = "ok"
        except OutputExistsError as exc:
            outcome[name] = exc

    threads = [threading.Thread(target=job, args=(n,)) for n in ("a", "b")]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    winners = [n for n, v in outcome.items() if v == "ok"]
    assert len(winners) == 1 and len(outcome) == 2, outcome
    assert tree(tmp_path) == sorted(["d", "d/report.md", f"d/{winners[0]}.csv"])
    assert (out / "report.md").read_text() == winners[0]


def test_overwrite_still_replaces_files_of_the_same_names(tmp_path):
    out = tmp_path / "d"
    out.mkdir(mode=0o750)
    (out / "keep.txt").write_text("k")
    (out / "a.csv").write_text("old")
    write_directory(out, True, lambda tmp: [write_text(tmp / "a.csv", "new")])
    assert tree(tmp_path) == ["d", "d/a.csv", "d/keep.txt"] and (out / "a.csv").read_text() == "new"
    assert out.stat().st_mode & 0o777 == 0o750


def test_an_existing_empty_directory_keeps_its_mode(tmp_path):
    out = tmp_path / "d"
    out.mkdir(mode=0o750)
    write_directory(out, False, lambda tmp: [write_text(tmp / "a.csv", "1")])
    assert out.stat().st_mode & 0o777 == 0o750 and tree(tmp_path) == ["d", "d/a.csv"]


# --- item 3: an output that is another output or an input -------------------------------------------------
def check_case(tmp_path: Path) -> Path:
    case = tmp_path / "c.toml"
    case.write_text(tomli_w.dumps({"name": "c", "poses": {"points_m": [[0.0, 0.72, 0.0]]},
                                   "loads": {"press_force_n": 700.0}, "envelope": {"max_tension_n": 1e6}}))
    return case


def test_check_refuses_one_file_for_json_and_junit(tmp_path):
    case = check_case(tmp_path)
    one_error_line(run("check", case, "--json", tmp_path / "r", "--junit", tmp_path / "r", "--no-progress"),
                   "--junit", "--json", "same file")
    assert tree(tmp_path) == ["c.toml"]
    (tmp_path / "link").symlink_to(tmp_path / "r")  # the same file through a symlink
    one_error_line(run("check", case, "--json", tmp_path / "link", "--junit", tmp_path / "r", "--no-progress"),
                   "same file")


@pytest.mark.parametrize("option", ["--json", "--junit"])
def test_check_refuses_to_write_over_its_input(tmp_path, option):
    case = check_case(tmp_path)
    before = case.read_text()
    one_error_line(run("check", case, option, case, "--overwrite", "--no-progress"), option, "input file")
    (tmp_path / "alias").hardlink_to(case)  # one file under two names
    one_error_line(run("check", case, option, tmp_path / "alias", "--overwrite", "--no-progress"), "input file")
    one_error_line(run("check", tmp_path, option, case, "--overwrite", "--no-progress"), "input file")  # in a dir
    assert case.read_text() == before


def test_check_refuses_to_write_over_the_machine_file_a_case_names(tmp_path):
    machine = tmp_path / "m.toml"
    machine.write_text(Path(DEFAULT_MODEL).read_text())
    case = check_case(tmp_path)
    case.write_text('model = "m.toml"\n' + case.read_text())
    one_error_line(run("check", case, "--json", machine, "--overwrite", "--no-progress"), "input file", "m.toml")


def test_export_mjcf_refuses_to_write_over_its_machine_file(tmp_path):
    machine = tmp_path / "m.toml"
    machine.write_text(Path(DEFAULT_MODEL).read_text())
    before = machine.read_text()
    one_error_line(run("export-mjcf", "0", "0.72", "0", "--model", machine, "--out", machine, "--overwrite"),
                   "--out", "input file")
    assert machine.read_text() == before


# --- item 6: coordinates, time step, stem and bore ---------------------------------------------------------
@pytest.mark.parametrize("bad", ["nan", "inf", "-inf", "1e300"])
@pytest.mark.parametrize("command", ["modes", "export-mjcf"])
@pytest.mark.parametrize("slot", range(3))
def test_modes_and_export_validate_coordinates_like_solve(command, slot, bad):
    pose = ["0", "0.72", "0"]
    pose[slot] = bad
    res = run(command, *pose)
    one_error_line(res, "XYZ"[slot])
    assert "Warning" not in res.stderr


@pytest.mark.parametrize("step, ok", [("1e-300", False), ("9.99e-7", False), ("1e-6", True), ("0.01", True),
                                      ("0.0101", False)])
def test_export_mjcf_time_step_bounds(step, ok):
    res = run("export-mjcf", "0", "0.72", "0", "--timestep", step)
    if ok:
        assert res.exit_code == 0 and "<mujoco" in res.output, res.output
    else:
        one_error_line(res, "--timestep")


def write_machine(tmp_path: Path, stem_diameter_m: float) -> Path:
    data = read_toml(DEFAULT_MODEL)
    data["stem"]["diameter_m"] = stem_diameter_m
    path = tmp_path / "m.toml"
    path.write_text(tomli_w.dumps(data))
    return path


def test_a_stem_as_wide_as_the_cylinder_bore_is_refused(tmp_path):
    data = read_toml(DEFAULT_MODEL)
    bore = data["cylinder"]["outer_diameter_m"] - 2 * data["cylinder"]["wall_thickness_m"]  # 0.05 m
    with pytest.raises(ModelFileError) as err:
        load_machine(write_machine(tmp_path, bore))
    assert err.value.key == "stem" and "stem.diameter_m" in str(err.value) and "bore" in str(err.value)
    load_machine(write_machine(tmp_path, bore * (1 - 1e-9)))  # just narrower: accepted
    one_error_line(run("modes", "0", "0.72", "0", "--model", write_machine(tmp_path, 1.2 * bore)), "stem.diameter_m")


@pytest.mark.slow
def test_a_directory_output_never_replaces_an_input_file(tmp_path):
    """modes --out D --overwrite with the machine file read from D/modes.json: refused before any file is
    moved in (D keeps exactly its input)."""
    out = tmp_path / "d"
    out.mkdir()
    machine = out / "modes.json"
    machine.write_text(Path(DEFAULT_MODEL).read_text())
    before = machine.read_text()
    one_error_line(run("modes", "0", "0.72", "0", "--model", machine, "--out", out, "--overwrite"), "input file",
                   "modes.json")
    assert tree(tmp_path) == ["d", "d/modes.json"] and machine.read_text() == before


@pytest.mark.parametrize(("summary", "fragment"), [
    ('{"samples": 1, "front": [{"sample": 0, "speed_scale": 1.0}]}', "front[0].acceleration_scale"),  # older study
    ('[1, 2]', "no front"),
    ("{not json", "summary.json"),
])
def test_report_refuses_a_study_summary_it_cannot_show_before_computing(tmp_path, monkeypatch, summary, fragment):
    """``report --cycle-study DIR`` with a summary.json lacking a key the front table shows (a study written before
    the gains and the preload were in the grid, a list, broken JSON): exit 2 naming the file and the key, and
    nothing computed (the sections are never called) or written."""
    study = tmp_path / "study"
    study.mkdir()
    (study / "summary.json").write_text(summary)
    monkeypatch.setattr(pressfit.workflows.report, "_tables_section", lambda *a: pytest.fail("computed"))
    one_error_line(run("report", "--out", tmp_path / "rep", "--quick", "--cycle-study", study), "summary.json",
                   fragment)
    assert not (tmp_path / "rep").exists()
