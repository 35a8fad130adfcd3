"""Tables 5-6 as printed (pressfit.studies.paper_tables): per case, components by leg, the paper beside pressfit,
round-off printed 0 (issue 28 item 9)."""

from __future__ import annotations

import math

from pressfit.studies.paper_tables import QUANTITIES, TableEntry, case_table, shown_value, to_markdown


def entries_of(case, paper, linear):
    """Entries of one case: paper[q][leg] and linear[q][leg] for the 7 quantities, CAD legs 1-4 = kinematic
    legs (1, 3, 4, 2); relative errors of the compared ones computed here."""
    out = []
    for q in QUANTITIES:
        for cad, kin in zip(range(1, 5), (1, 3, 4, 2), strict=True):
            p, a = paper[q][cad - 1], linear[q][cad - 1]
            compared = q in ("F_z", "M_bend", "M_z")
            err = (a - p) / abs(p) if compared and max(abs(p), abs(a)) >= 1e-3 else math.nan
            out.append(TableEntry(case=case, quantity=q, cad_leg=cad, kinematic_leg=kin, paper=p, linear=a,
                                  nonlinear=a, relative_error=err, compared=compared))
    return out


def test_round_off_is_printed_0_and_never_minus_0():
    """Scale 195.7 N: 1.899e-15 and -2e-13 are round-off (below 1e-9 x 195.7 = 2e-7), -0.0 and -1e-300 are 0;
    3.6e-6 is a value (the paper prints such); a value that would print -0 at 4 digits is 0."""
    assert [shown_value(x, 195.7) for x in (1.899e-15, -2e-13, -0.0, -1e-300)] == ["0"] * 4
    assert shown_value(-3.6e-6, 195.7) == "-3.6e-06" and shown_value(-195.66, 195.7) == "-195.7"
    assert shown_value(-0.0, 0.0) == "0"


def test_tables_are_per_case_with_components_by_leg_and_the_paper_beside_pressfit():
    """Two cases: each gets its own Table 5 and Table 6 part, a row per CAD leg with its kinematic leg, per
    component the paper's value then pressfit's, the compared components' relative error after them; pressfit's
    round-off (1.899e-15, -0.0) shows as 0, the paper's 3.6e-6 as printed."""
    zero = {q: [0.0] * 4 for q in QUANTITIES}
    paper = zero | {"F_x": [-3.6e-6, 0.0, 0.0, 0.0], "F_z": [-195.8, -195.8, -195.6, -195.6],
                    "M_z": [1.0, 1.0, 1.0, 1.0]}
    linear = zero | {"F_x": [1.899e-15, -0.0, 0.0, 0.0], "F_z": [-195.7] * 4, "M_z": [1.1, 1.1, 1.1, 1.1]}
    entries = entries_of("A", paper, linear) + entries_of("B", zero, zero)
    header, rows = case_table(entries, "A", "Table 5")
    assert header == ["CAD leg (kin.)", "F_x paper", "F_x pressfit", "F_y paper", "F_y pressfit", "F_z paper",
                      "F_z pressfit", "F_z rel. error"]
    assert [r[0] for r in rows] == ["1 (1)", "2 (3)", "3 (4)", "4 (2)"]
    assert rows[0][1:3] == ["-3.6e-06", "0"] and rows[1][1:3] == ["0", "0"]
    assert rows[0][5:] == ["-195.8", "-195.7", "+0.1%"]
    header6, rows6 = case_table(entries, "A", "Table 6")
    assert header6[-3:] == ["M_z paper", "M_z pressfit", "M_z rel. error"] and rows6[0][-3:] == ["1", "1.1", "+10.0%"]
    text = to_markdown(entries)
    assert text.count("**A**") == 2 and text.count("**B**") == 2  # each case in Table 5 and in Table 6
    assert "e-15" not in text and "-0 " not in text and "| -0 |" not in text
    assert text.index("### Table 5") < text.index("**A**") < text.index("**B**") < text.index("### Table 6")
