"""The limit check's verdict as text and JUnit XML (one test case per envelope line)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from pressfit.studies.limit_check import CaseResult, CheckRun, FileError


def _vec(v: list[float], digits: int) -> str:
    return "(" + ", ".join(f"{c:.{digits}g}" for c in v) + ")"


def unreachable_summary(r: CaseResult) -> str:
    """One line for every unreachable pose of a case: how many, and the worst excess over a limit."""
    u = r.unreachable
    worst_l = max(u, key=lambda e: e["leg_length_excess_m"])  # type: ignore[arg-type, return-value]
    worst_a = max(u, key=lambda e: e["angle_excess_rad"])  # type: ignore[arg-type, return-value]
    parts = [f"{len(u)} of {r.n_poses} poses unreachable (all listed by --json/--junit)"]
    if worst_l["leg_length_excess_m"]:
        parts.append(f"worst leg-length excess {worst_l['leg_length_excess_m']:.4g} m at pose "
                     f"{_vec(worst_l['pose_m'], 4)} m ({worst_l['reason']})")  # type: ignore[arg-type]
    if worst_a["angle_excess_rad"]:
        parts.append(f"worst cardan-angle excess {worst_a['angle_excess_rad']:.4g} rad at pose "
                     f"{_vec(worst_a['pose_m'], 4)} m ({worst_a['reason']})")  # type: ignore[arg-type]
    return "; ".join(parts)


def _error_text(e: FileError) -> str:
    return e.message if e.message.startswith(e.path) else f"{e.path}: {e.message}"


def format_run(run: CheckRun) -> str:
    """The whole ``pressfit check`` report: skipped files, each case's table, files in error, the tally."""
    out = [f"skipped (no [envelope]): {', '.join(run.skipped)}"] if run.skipped else []
    out += [format_table(run.results)] if run.results else []
    out += [f"ERROR {_error_text(e)}" for e in run.errors]
    failed = sum(not r.passed for r in run.results)
    out.append(f"{len(run.results) - failed} passed, {failed} failed, {len(run.errors)} in error")
    return "\n".join(out)


def format_table(results: list[CaseResult]) -> str:
    """A plain-text report: one line per envelope limit, failures marked and explained."""
    out = []
    for r in results:
        out.append(f"{'PASS' if r.passed else 'FAIL'}  {r.case}  ({r.path}; {r.n_poses} poses x {r.n_loads} loads)")
        if r.unreachable:
            out.append(f"  FAIL reachability: {unreachable_summary(r)}")
        for x in r.limits:
            where = (f"leg {x.leg} " if x.leg else "") + f"at pose {_vec(x.pose_m, 4)} m"
            if x.load:
                where += f", load {_vec(x.load, 4)}"
            sense = x.sense
            op = ("<=" if sense == "max" else ">=") if x.passed else ("EXCEEDS" if sense == "max" else "BELOW")
            verdict = "ok  " if x.passed else "FAIL"
            out.append(f"  {verdict} {x.label}: worst {x.worst:.6g} {x.unit} {op} limit {x.limit:.6g} {x.unit}"
                       f"  [{x.key}; {where}; {x.method}]")
    return "\n".join(out)


def junit_xml(run: CheckRun) -> str:
    """JUnit XML: one test suite per case, one test case per envelope line and one for the reachability of
    every pose (its failure text lists each unreachable pose); a file in error is a suite with an error."""
    import xml.etree.ElementTree as ET

    root = ET.Element("testsuites", name="pressfit check")
    for e in run.errors:
        suite = ET.SubElement(root, "testsuite", name=e.path, tests="1", failures="0", errors="1", file=e.path)
        tc = ET.SubElement(ET.SubElement(suite, "testcase", classname=e.path, name="case file"), "error",
                           message=_error_text(e))
        tc.text = _error_text(e)
    for r in run.results:
        cases = [(f"{x.key}", None if x.passed else
                  f"{x.label}: worst {x.worst:.6g} {x.unit} violates limit {x.limit:.6g} {x.unit} "
                  f"(leg {x.leg}, pose {_vec(x.pose_m, 6)} m, load {_vec(x.load, 6)}; {x.method})") for x in r.limits]
        if r.unreachable:
            cases.append(("reachable poses", unreachable_summary(r) + "\n" + "\n".join(
                f"{_vec(u['pose_m'], 6)} m: {u['reason']}" for u in r.unreachable)))  # type: ignore[arg-type]
        suite = ET.SubElement(root, "testsuite", name=r.case, tests=str(len(cases)),
                              failures=str(sum(m is not None for _, m in cases)), file=r.path)
        for name, msg in cases:
            tc = ET.SubElement(suite, "testcase", classname=r.case, name=name)
            if msg is not None:
                ET.SubElement(tc, "failure", message=msg.split("\n")[0]).text = msg
    return ET.tostring(root, encoding="unicode", xml_declaration=True)
