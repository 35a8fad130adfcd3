"""The limit check's verdict as text and JUnit XML (one test case per envelope line)."""

from __future__ import annotations

import numpy as np

from pressfit.studies.limit_check import LIMITS, CaseResult


def format_table(results: list[CaseResult]) -> str:
    """A plain-text report: one line per envelope limit, failures marked and explained."""
    out = []
    for r in results:
        out.append(f"{'PASS' if r.passed else 'FAIL'}  {r.case}  ({r.path}; {r.n_poses} poses x {r.n_loads} loads)")
        for u in r.unreachable:
            out.append(f"  FAIL unreachable pose {u['pose_m']} m: {u['reason']}")
        for x in r.limits:
            where = (f"leg {x.leg} " if x.leg else "") + f"at pose {np.round(x.pose_m, 4).tolist()} m"
            if x.load:
                where += f", load {np.round(x.load, 3).tolist()}"
            sense = LIMITS[x.key].sense
            op = ("<=" if sense == "max" else ">=") if x.passed else ("EXCEEDS" if sense == "max" else "BELOW")
            verdict = "ok  " if x.passed else "FAIL"
            out.append(f"  {verdict} {x.label}: worst {x.worst:.6g} {x.unit} {op} limit {x.limit:.6g} {x.unit}"
                       f"  [{x.key}; {where}; {x.method}]")
    return "\n".join(out)


def junit_xml(results: list[CaseResult]) -> str:
    """JUnit XML: one test suite per case, one test case per envelope line (and per unreachable pose)."""
    import xml.etree.ElementTree as ET

    root = ET.Element("testsuites", name="pressfit check")
    for r in results:
        cases = [(f"{x.key}", None if x.passed else
                  f"{x.label}: worst {x.worst:.6g} {x.unit} violates limit {x.limit:.6g} {x.unit} "
                  f"(leg {x.leg}, pose {x.pose_m} m, load {x.load})") for x in r.limits]
        cases += [(f"reachable {u['pose_m']}", str(u["reason"])) for u in r.unreachable]
        suite = ET.SubElement(root, "testsuite", name=r.case, tests=str(len(cases)),
                              failures=str(sum(m is not None for _, m in cases)), file=r.path)
        for name, msg in cases:
            tc = ET.SubElement(suite, "testcase", classname=r.case, name=name)
            if msg is not None:
                ET.SubElement(tc, "failure", message=msg).text = msg
    return ET.tostring(root, encoding="unicode", xml_declaration=True)
