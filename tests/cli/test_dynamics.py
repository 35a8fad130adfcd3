"""``pressfit simulate``'s warnings (pressfit.cli.dynamics): the comparison run's are labelled as such."""

from __future__ import annotations

from pressfit.cli.dynamics import run_warnings


def test_a_warning_of_the_comparison_run_says_it_is_about_the_comparison_run():
    """issue 28 item 8: the main run (limiter on) warns A; the comparison run without the limiter warns A and B.
    A is printed once, as the run's; B says it is about the comparison run without the limiter."""
    summary = {"limiter": True, "warnings": ["A: the plays open"],
               "comparison": {"limiter": False, "warnings": ["A: the plays open", "B: the drives saturate"]}}
    assert run_warnings(summary) == [
        "A: the plays open",
        "the comparison run (limiter off, not the main run): B: the drives saturate"]
    assert run_warnings({"warnings": ["A", "A"]}) == ["A"]  # no comparison: the run's, once
