"""README examples are tests (scikit-fem style): the documented case file validates, and the two
commands at the top are the ones .ci/run and users run."""

import re
from pathlib import Path

from pressfit.description.cases import load_case

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def test_readme_starts_with_the_two_commands():
    commands = re.findall(r"<!-- (main|test)-command -->\n```sh\n(.+)\n```", README)
    assert [c[0] for c in commands] == ["main", "test"]
    assert "pressfit report" in commands[0][1] and "pytest" in commands[1][1]
    assert README.index("<!-- test-command -->") < README.index("---")


def test_ci_runs_the_readme_commands_in_order():
    """.ci/run runs the main command, then the test command, each verbatim (on a clean clone: a plain install
    followed by the editable one is what a newcomer does, and what numba's cache once broke)."""
    main, test = (re.search(rf"<!-- {k}-command -->\n```sh\n(.+)\n```", README).group(1) for k in ("main", "test"))
    ci = (ROOT / ".ci/run").read_text()
    assert main in ci and test in ci and ci.index(main) < ci.index(test)


def test_readme_case_file_example_is_valid(tmp_path):
    (block,) = [b for b in re.findall(r"```toml\n(.*?)```", README, re.S) if "[envelope]" in b]
    model = (ROOT / "models/pressfit_4upu.toml").as_posix()
    path = tmp_path / "example.toml"
    path.write_text(re.sub(r'^model = ".*?"', f'model = "{model}"', block, flags=re.M))
    case = load_case(path)
    machine = case.machine()
    assert machine.actuator.axial_stiffness_n_per_m == 8.0e7  # the override took effect
    assert case.poses.array().shape == (1 + 11 * 6 * 11, 3) and case.loads.wrenches().shape == (9, 6)
    assert case.clearance is not None and len(case.envelope.model_dump(exclude_none=True)) == 12
