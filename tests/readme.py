"""README numbers are tests (scikit-fem's "examples are tests"): a test that computes a number the README states
first checks that the README still says it (:func:`readme_fragment`), then that the computed value rounds to
the printed digits (:func:`assert_printed`), so the README and the code cannot drift apart."""

from __future__ import annotations

from pathlib import Path

README = " ".join((Path(__file__).resolve().parents[1] / "README.md").read_text().split())


def readme_fragment(text: str) -> str:
    """Assert that README.md contains ``text`` (runs of white space, line breaks included, compare equal) and
    return it."""
    assert " ".join(text.split()) in README, f"README.md no longer says: {text!r}"
    return text


def half_unit(printed: str) -> float:
    """Half a unit of the last printed digit of a decimal number as printed: "30.5" -> 0.05, "2.4e-6" -> 5e-8."""
    mantissa, _, exponent = printed.lower().partition("e")
    return 0.5 * 10.0 ** (int(exponent or 0) - len(mantissa.partition(".")[2]))


def assert_printed(value: float, printed: str) -> None:
    """``value`` rounds to ``printed``: |value - printed| <= half a unit of its last digit (1e-9 relative slack
    for a value that falls exactly on the boundary)."""
    tolerance = half_unit(printed) * (1 + 1e-9)
    assert abs(value - float(printed)) <= tolerance, f"{value!r} does not round to the README's {printed}"
