"""The layout's rules (docs/architecture.md), checked on the source's import graph with ``ast``:

* layers, low to high: errors, spatial, shipped, compiled < description < kinematics < mechanics < geometry < dynamics
  < studies < output < workflows < cli; a module never imports a higher layer (a lower one, or its own, is fine);
* output/ only formats and writes: at run time it imports no module of the physics or the studies (kinematics,
  mechanics, geometry, dynamics, studies); types for annotations come in under ``if TYPE_CHECKING:``, and the few
  names it reads at run time are listed in ``OUTPUT_RUNTIME_NAMES`` with their reason (the workflows/ layer
  loads the inputs, runs the physics and hands the results to output/);
* the physics subpackages (kinematics, mechanics, geometry, dynamics) import neither matplotlib nor
  pressfit.output, and never open files for writing;
* no module-level mutable state in the library: no module-level dict/list/set that a function mutates
  (``global`` statements and module-level caches, ``functools.cache`` and ``lru_cache`` among them, are refused);
  the one exception is a resource, not results: mechanics/data_pool.py's pool of Pinocchio Data, whose lent Data
  give a fresh one's results bit for bit (tests/mechanics/test_data_pool.py);
* no import circle between modules, counting every import (module level, inside functions, under
  TYPE_CHECKING): the clearance law lives apart from the clearance solvers for this
  (mechanics/clearance_law.py; the circle was clearance -> statics -> preload -> clearance);
* results and records are built by keyword: a public dataclass with 3 or more ``__init__`` fields is
  ``kw_only`` (a positional call that reorders two fields would silently permute the physics);
* every exception is defined in errors.py.
"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "pressfit"
LAYERS = ["errors", "spatial", "shipped", "compiled", "description", "kinematics", "mechanics", "geometry", "dynamics",
          "studies", "output", "workflows", "cli"]
BASE = {"errors": 0, "spatial": 0, "shipped": 0, "compiled": 0}  # the lowest layer: these import each other
PHYSICS = {"kinematics", "mechanics", "geometry", "dynamics"}


def _rank(part: str) -> int:
    return BASE.get(part, LAYERS.index(part))


def _modules() -> list[tuple[str, Path]]:
    out = []
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).with_suffix("")
        if rel.parts[0] in ("__init__", "__main__"):
            continue
        out.append((rel.parts[0], path))
    return out


def _tree(path: Path) -> ast.Module:
    """The parsed source of ``path`` (each text parsed once per test run: every check walks the same files)."""
    return _parsed(path.read_text())


@functools.cache
def _parsed(text: str) -> ast.Module:
    return ast.parse(text)


def _imports(path: Path) -> list[str]:
    names = []
    for node in ast.walk(_tree(path)):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                raise AssertionError(f"{path}: relative import (use absolute pressfit.* imports)")
            names.append(node.module or "")
            names += [f"{node.module}.{a.name}" for a in node.names]
    return names


MODULES = _modules()


def test_every_module_is_in_a_layer():
    assert MODULES, "no source found: the test would pass vacuously"
    assert {layer for layer, _ in MODULES} <= set(LAYERS)


@pytest.mark.parametrize(("layer", "path"), MODULES, ids=[str(p.relative_to(SRC)) for _, p in MODULES])
def test_no_import_of_a_higher_layer(layer, path):
    for name in _imports(path):
        parts = name.split(".")
        if parts[0] == "pressfit" and len(parts) > 1 and parts[1] in LAYERS:
            assert _rank(parts[1]) <= _rank(layer), f"{path.name} ({layer}) imports {name}"


SOLVER_LAYERS = ("kinematics", "mechanics", "geometry", "dynamics", "studies")
# names output/ imports at run time from a solver layer, each with its reason; every other import of a solver layer
# is under ``if TYPE_CHECKING:`` (an annotation). Data: the schema of a result (column names, labels, units), defined
# once beside the code that fills it. Presentation helpers: pure functions of a finished result (no solve) that still
# live beside their study because the CLI prints them too; they move into output/ with their callers.
OUTPUT_RUNTIME_NAMES = {
    "pressfit.dynamics.series.section_columns": "data: the header of sections.csv (the flexible run's sections)",
    "pressfit.studies.insertion_study.COLUMNS": "data: the columns of the insertion study's table",
    "pressfit.studies.cycle_study.FACTOR_LABELS": "data: the throughput study's factors as labels",
    "pressfit.studies.design.METRICS": "data: the design study's metric columns",
    "pressfit.studies.montecarlo.OUTPUTS": "data: the Monte Carlo study's output columns",
    "pressfit.studies.montecarlo.QUANTILES": "data: the quantiles the Monte Carlo summary holds",
    "pressfit.studies.limit_check.LIMITS": "data: each envelope limit's label and unit",
    "pressfit.studies.workspace_envelope.LEG_QUANTITIES": "data: the load envelope's per-leg quantities and units",
    "pressfit.studies.workspace_envelope.PLATE_QUANTITIES": "data: the load envelope's plate quantities and units",
    "pressfit.studies.workspace_envelope.envelope_rows": "presentation: the envelope's table rows",
    "pressfit.studies.preload_study.format_answers": "presentation: the preload study's answers as text",
    "pressfit.studies.paper_tables.TableEntry": "data: one printed entry of Tables 5-6 (rebuilt from tables.json)",
    "pressfit.studies.paper_tables.TABLES": "data: the titles of Tables 5 and 6",
    "pressfit.studies.paper_tables.case_table": "presentation: one case's part of Table 5 or 6 as printed",
    "pressfit.studies.paper_tables.shown_value": "presentation: an entry as the paper prints it",
    "pressfit.geometry.interference.machine_shapes": "drawing: the bodies' shapes and placements (no distance query)",
    "pressfit.kinematics.closed_form.frames_along": "drawing: a drawn leg's frame from its direction (closed form)",
}


def _runtime_imports(path: Path) -> list[tuple[int, str, list[str]]]:
    """(line, module, imported names) of every import of ``path`` outside an ``if TYPE_CHECKING:`` block
    (``import a.b`` gives the names ``[]``)."""
    tree = _tree(path)
    hidden = {id(n) for node in ast.walk(tree) if isinstance(node, ast.If) and ast.unparse(node.test) in
              ("TYPE_CHECKING", "typing.TYPE_CHECKING") for stmt in node.body for n in ast.walk(stmt)}
    out = []
    for node in ast.walk(tree):
        if id(node) in hidden:
            continue
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name, []) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            out.append((node.lineno, node.module or "", [a.name for a in node.names]))
    return out


@pytest.mark.parametrize(("layer", "path"), [m for m in MODULES if m[0] == "output"],
                         ids=[str(p.relative_to(SRC)) for layer, p in MODULES if layer == "output"])
def test_output_imports_no_solver(layer, path):
    """output/ formats and writes: no import of the physics or the studies at run time, but for the names of
    ``OUTPUT_RUNTIME_NAMES`` (the workflows run the solvers and hand output/ their results)."""
    for line, module, names in _runtime_imports(path):
        parts = module.split(".")
        if parts[0] != "pressfit" or len(parts) < 2 or parts[1] not in SOLVER_LAYERS:
            continue
        bad = [f"{module}.{n}" for n in names if f"{module}.{n}" not in OUTPUT_RUNTIME_NAMES] or \
            ([] if names else [module])
        assert not bad, f"{path}:{line} imports {', '.join(bad)} at run time: output/ writes only (run the " \
                        "physics in a workflow, or import the type under `if TYPE_CHECKING:`)"


def test_the_output_allow_list_is_still_needed():
    """Every name of OUTPUT_RUNTIME_NAMES is still imported at run time by a module of output/ (a name no longer
    read there leaves the list)."""
    used = {f"{module}.{n}" for layer, path in MODULES if layer == "output"
            for _, module, names in _runtime_imports(path) for n in names}
    assert set(OUTPUT_RUNTIME_NAMES) - used == set(), "allowed but no longer imported: remove from the list"


@pytest.mark.parametrize(("layer", "path"), [m for m in MODULES if m[0] in PHYSICS],
                         ids=[str(p.relative_to(SRC)) for layer, p in MODULES if layer in PHYSICS])
def test_physics_neither_plots_nor_writes(layer, path):
    for name in _imports(path):
        assert not name.startswith(("matplotlib", "pressfit.output", "plotly")), f"{path} imports {name}"
    tree = _tree(path)
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            assert node.func.attr not in ("write_text", "write_bytes", "savefig", "mkdir", "to_csv"), \
                f"{path}:{node.lineno} writes ({node.func.attr})"
        if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", "")) == "open":
            mode = node.args[1] if len(node.args) > 1 else next((k.value for k in node.keywords if k.arg == "mode"),
                                                                 None)
            text = mode.value if isinstance(mode, ast.Constant) else "r"
            assert not set(text) & set("wax+"), f"{path}:{node.lineno} opens a file for writing"


@pytest.mark.slow
@pytest.mark.parametrize(("layer", "path"), MODULES, ids=[str(p.relative_to(SRC)) for _, p in MODULES])
def test_no_global_mutable_state(layer, path):
    tree = _tree(path)
    for node in ast.walk(tree):
        assert not isinstance(node, ast.Global), f"{path}:{node.lineno}: global statement"
        for decorator in getattr(node, "decorator_list", []):
            name = ast.unparse(decorator)
            assert not re.search(r"\b(lru_cache|cache)\b", name), f"{path}:{node.lineno}: a module-level cache ({name})"
    mutable = set()
    for node in tree.body:  # module level: names bound to a mutable container
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and isinstance(node.value, (ast.Dict, ast.List, ast.Set,
                                                                                      ast.DictComp, ast.ListComp)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            mutable |= {t.id for t in targets if isinstance(t, ast.Name)}
    for node in ast.walk(tree):  # ... and mutated anywhere in the module
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                and isinstance(node.func.value, ast.Name) and node.func.value.id in mutable \
                and node.func.attr in ("append", "update", "clear", "pop", "setdefault", "extend", "add", "insert"):
            raise AssertionError(f"{path}:{node.lineno}: module-level {node.func.value.id} is mutated")
        if isinstance(node, (ast.Assign, ast.AugAssign)):
            for t in node.targets if isinstance(node, ast.Assign) else [node.target]:
                if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name) and t.value.id in mutable:
                    raise AssertionError(f"{path}:{node.lineno}: module-level {t.value.id} is mutated")


@pytest.mark.parametrize(("layer", "path"), [m for m in MODULES if m[0] == "cli"],
                         ids=[str(p.relative_to(SRC)) for layer, p in MODULES if layer == "cli"])
def test_the_cli_holds_no_physics(layer, path):
    """The CLI parses, calls the library and prints: no numerical or physics engine of its own."""
    for name in _imports(path):
        assert name.split(".")[0] not in ("numpy", "scipy", "pinocchio", "coal", "matplotlib"), f"{path} imports {name}"


# modules (or module:Class) not yet converted to keyword-only results: the integrator shrinks this list
KW_ONLY_EXEMPT: set[str] = set()  # every module is converted (a new exemption needs its reason here)


def _is_dataclass(node: ast.ClassDef) -> ast.expr | None:
    """The ``@dataclass`` or ``@dataclass(...)`` decorator of a class, else None."""
    return next((d for d in node.decorator_list
                 if "dataclass" in (getattr(d, "id", None), getattr(getattr(d, "func", None), "id", None))), None)


def _init_fields(node: ast.ClassDef) -> list[str]:
    """The fields a dataclass's ``__init__`` takes (no ClassVar, no ``field(init=False)``)."""
    return [s.target.id for s in node.body if isinstance(s, ast.AnnAssign) and isinstance(s.target, ast.Name)
            and not ast.unparse(s.annotation).startswith("ClassVar")
            and not (isinstance(s.value, ast.Call) and getattr(s.value.func, "id", "") == "field"
                     and any(k.arg == "init" and getattr(k.value, "value", True) is False for k in s.value.keywords))]


@pytest.mark.parametrize(("layer", "path"), MODULES, ids=[str(p.relative_to(SRC)) for _, p in MODULES])
def test_results_are_built_by_keyword(layer, path):
    rel = str(path.relative_to(SRC)) if path.is_relative_to(SRC) else path.name
    if rel in KW_ONLY_EXEMPT:
        return
    for node in ast.walk(_tree(path)):
        if not isinstance(node, ast.ClassDef) or node.name.startswith("_") or f"{rel}:{node.name}" in KW_ONLY_EXEMPT:
            continue
        deco = _is_dataclass(node)
        if deco is None or len(_init_fields(node)) < 3:
            continue
        kw_only = isinstance(deco, ast.Call) and any(k.arg == "kw_only" and getattr(k.value, "value", False) is True
                                                     for k in deco.keywords)
        assert kw_only, f"{path}:{node.lineno}: dataclass {node.name} has {len(_init_fields(node))} fields: make it " \
                        "@dataclass(..., kw_only=True) and build it by keyword"


@pytest.mark.parametrize(("layer", "path"), MODULES, ids=[str(p.relative_to(SRC)) for _, p in MODULES])
def test_exceptions_live_in_errors_py(layer, path):
    """Every exception is defined in errors.py (one place to read what a failure carries)."""
    if layer == "errors":
        return
    bad = [n.name for n in ast.walk(_tree(path)) if isinstance(n, ast.ClassDef)
           and any(re.search(r"(Error|Exception)$", ast.unparse(b)) for b in n.bases)]
    assert not bad, f"{path}: exception {', '.join(bad)} is defined outside errors.py: move it there"


def test_the_exempt_modules_still_need_their_exemption():
    """Every entry of KW_ONLY_EXEMPT names an existing module (and class) that would fail without it: a
    converted module leaves the list."""
    for entry in KW_ONLY_EXEMPT:
        rel, _, cls = entry.partition(":")
        tree = _tree(SRC / rel)
        late = [n for n in ast.walk(tree) if isinstance(n, ast.ClassDef) and not n.name.startswith("_")
                and (not cls or n.name == cls) and (d := _is_dataclass(n)) is not None and len(_init_fields(n)) >= 3
                and not any(k.arg == "kw_only" for k in getattr(d, "keywords", []))]
        assert late, f"{entry} is exempt from keyword-only results but needs no exemption: remove it"


def test_the_rules_catch_a_violation(tmp_path):
    """The checks are not vacuous: a physics module that plots, keeps a cache and defines its own exception is
    refused, and so is a positional result (a 3-field dataclass that is not kw_only)."""
    bad = tmp_path / "bad.py"
    bad.write_text("import matplotlib\nfrom pressfit.output import files\n_CACHE = {}\n"
                   "def f(k):\n    _CACHE[k] = 1\n    open('x', 'w')\n"
                   "class SolverError(errors.PressfitError):\n    pass\n")
    cached = tmp_path / "cached.py"
    cached.write_text("import functools\n@functools.lru_cache(maxsize=8)\ndef table(x):\n    return x\n")
    with pytest.raises(AssertionError, match=r"a module-level cache \(functools.lru_cache\(maxsize=8\)\)"):
        test_no_global_mutable_state("mechanics", cached)
    with pytest.raises(AssertionError, match="exception SolverError is defined outside errors.py"):
        test_exceptions_live_in_errors_py("mechanics", bad)
    with pytest.raises(AssertionError, match="imports matplotlib"):
        test_physics_neither_plots_nor_writes("mechanics", bad)
    with pytest.raises(AssertionError, match="module-level _CACHE is mutated"):
        test_no_global_mutable_state("mechanics", bad)
    with pytest.raises(AssertionError, match="imports matplotlib"):
        test_the_cli_holds_no_physics("cli", bad)
    with pytest.raises(AssertionError, match=r"\(kinematics\) imports pressfit.output"):
        test_no_import_of_a_higher_layer("kinematics", bad)
    writer = tmp_path / "writer.py"  # an output module that solves: refused; the same import for a type is fine
    writer.write_text("from typing import TYPE_CHECKING\nfrom pressfit.mechanics.statics import solve_equilibrium\n"
                      "if TYPE_CHECKING:\n    from pressfit.mechanics.statics import Equilibrium\n")
    with pytest.raises(AssertionError, match="imports pressfit.mechanics.statics.solve_equilibrium at run time"):
        test_output_imports_no_solver("output", writer)
    writer.write_text("import pressfit.studies.compare\n")
    with pytest.raises(AssertionError, match="imports pressfit.studies.compare at run time"):
        test_output_imports_no_solver("output", writer)
    writer.write_text("from typing import TYPE_CHECKING\nfrom pressfit.studies.limit_check import LIMITS\n"
                      "if TYPE_CHECKING:\n    from pressfit.mechanics.statics import Equilibrium\n")
    test_output_imports_no_solver("output", writer)  # an allowed name, a type for annotations
    writer.write_text("from pressfit.workflows.report import write_report\n")
    with pytest.raises(AssertionError, match=r"\(output\) imports pressfit.workflows.report"):
        test_no_import_of_a_higher_layer("output", writer)
    positional = tmp_path / "positional.py"
    positional.write_text("from dataclasses import dataclass, field\n@dataclass(frozen=True)\nclass Result:\n"
                          "    force_n: float\n    moment_nm: float\n    residual: float\n"
                          "@dataclass\nclass Pair:\n    a: float\n    b: float\n    c: float = field(init=False)\n"
                          "@dataclass(frozen=True, kw_only=True)\nclass Fine:\n    a: float\n    b: float\n"
                          "    c: float\n")
    with pytest.raises(AssertionError, match="dataclass Result has 3 fields"):
        test_results_are_built_by_keyword("studies", positional)
    positional.write_text(positional.read_text().replace("(frozen=True)", "(frozen=True, kw_only=True)", 1))
    test_results_are_built_by_keyword("studies", positional)  # Pair has 2 __init__ fields, Fine is kw_only


# --- cited documents exist ------------------------------------------------------------------------------------
ROOT = SRC.parents[1]
MD_REF = re.compile(r"(?<![\w./-])((?:[\w.-]+/)*[\w.-]+\.md)\b")


def _written_markdown_names() -> set[str]:
    """The Markdown files the package writes (string constants in src that are a bare Markdown file name):
    outputs, not documents."""
    return {node.value for path in SRC.rglob("*.py") for node in ast.walk(_tree(path))
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and MD_REF.fullmatch(node.value)}


def missing_documents(text: str, outputs: set[str]) -> list[str]:
    """The ``*.md`` references in ``text`` that name no file of the repository (at the top level or under docs/)
    and no output the package writes."""
    return [ref for ref in MD_REF.findall(text) if Path(ref).name not in outputs
            and not (ROOT / ref).is_file() and not (ROOT / "docs" / ref).is_file()]


@pytest.mark.slow
def test_cited_documents_exist():
    """A test or source file that gives a document as its source must name one that is in the repository."""
    outputs = _written_markdown_names()
    assert outputs == {"report.md", "tables.md", "cad_fit.md", "calibration.md"}
    files = [*SRC.rglob("*.py"), *(ROOT / "tests").rglob("*.py"), *(ROOT / "benchmarks").rglob("*.py")]
    bad = [f"{f.relative_to(ROOT)}: {ref}" for f in files for ref in missing_documents(f.read_text(), outputs)]
    assert not bad, "cites a document that is not in the repository: " + "; ".join(bad)


@pytest.mark.slow
def test_missing_document_check_catches_a_phantom_source():
    outputs = _written_markdown_names()
    phantom, nested = "DESIGN" + ".md", "notes/derivation" + ".md"  # split so that this file cites neither
    assert missing_documents(f"# closed form ({phantom}) and (see {nested})", outputs) == [phantom, nested]
    assert missing_documents("docs/conventions.md, README.md, conventions.md, DIR/report.md", outputs) == []


def _module_name(path: Path, root: Path) -> str:
    rel = path.relative_to(root.parent).with_suffix("")
    return ".".join(rel.parts).removesuffix(".__init__")


def _import_cycles(paths: list[Path], root: Path = SRC) -> list[list[str]]:
    """The strongly connected components (more than one module) of the import graph of ``paths`` (modules of
    the package at ``root``)."""
    names = {_module_name(p, root): p for p in paths}
    graph = {m: {t for t in _imports(p) if t in names and t != m} for m, p in names.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(v: str) -> None:  # Tarjan
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return cycles


@pytest.mark.slow
def test_no_import_circle():
    assert _import_cycles(sorted(SRC.rglob("*.py"))) == []


def test_the_circle_check_finds_a_circle(tmp_path):
    """Not vacuous: three modules importing each other in a ring (one inside a function) are one circle."""
    pkg = tmp_path / "pressfit" / "mechanics"
    pkg.mkdir(parents=True)
    (pkg / "a.py").write_text("from pressfit.mechanics.b import f\n")
    (pkg / "b.py").write_text("def f():\n    from pressfit.mechanics import c\n")
    (pkg / "c.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                              "    from pressfit.mechanics.a import x\n")
    ring = ["pressfit.mechanics.a", "pressfit.mechanics.b", "pressfit.mechanics.c"]
    assert _import_cycles(sorted(pkg.glob("*.py")), tmp_path / "pressfit") == [ring]


def test_the_architecture_document_names_every_module():
    """docs/architecture.md's module table holds every module of src/pressfit (and nothing that is gone)."""
    doc = (SRC.parents[1] / "docs" / "architecture.md").read_text().split("## Rules")[0]
    named = set(re.findall(r"^\| `([\w/]+\.py)` \|", doc, flags=re.MULTILINE))
    packages_with_code = ("shipped", "cli", "drives", "contact_laws")  # an __init__.py that is more than a docstring
    present = {str(p.relative_to(SRC)) for p in SRC.rglob("*.py")
               if p.name != "__main__.py" and (p.name != "__init__.py" or p.parent.name in packages_with_code)}
    assert present - named == set(), f"modules missing from docs/architecture.md: {sorted(present - named)}"
    assert named - present == set(), f"docs/architecture.md names modules that do not exist: {sorted(named - present)}"


def test_test_modules_have_unique_names():
    """pytest's default import mode imports a test module by its basename: two ``test_x.py`` in different folders
    make the second fail to collect ("import file mismatch") on a clean clone, so every basename is unique."""
    names = [p.name for p in (SRC.parents[1] / "tests").rglob("test_*.py")]
    assert sorted({n for n in names if names.count(n) > 1}) == []



MAX_FUNCTION_LINES = 80


def long_functions(paths: list[Path], root: Path = SRC) -> list[str]:
    """Every function (and method) of ``paths`` longer than ``MAX_FUNCTION_LINES`` lines, its decorators and
    docstring included, as ``path:line name (n lines)`` (path relative to ``root``)."""
    out = []
    for path in paths:
        for node in ast.walk(_tree(path)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - min([node.lineno, *(d.lineno for d in node.decorator_list)]) + 1
                if lines > MAX_FUNCTION_LINES:
                    out.append(f"{path.relative_to(root)}:{node.lineno} {node.name} ({lines} lines)")
    return out


@pytest.mark.slow
def test_no_function_is_longer_than_80_lines():
    """A function over ``MAX_FUNCTION_LINES`` lines is several steps that want names of their own."""
    assert long_functions(sorted(SRC.rglob("*.py"))) == []


def test_the_length_check_catches_a_long_function(tmp_path):
    body = "    x = 1\n" * (MAX_FUNCTION_LINES - 1)
    (tmp_path / "m.py").write_text(f"def fits():\n{body}\n\ndef over():\n{body}    x = 2\n")
    assert long_functions([tmp_path / "m.py"], tmp_path) == ["m.py:83 over (81 lines)"]


def model_name_reads(paths: list[Path], names: tuple[str, ...], root: Path = SRC) -> list[str]:
    """Where ``paths`` read a dynamics model's name: a comparison with one of ``names`` (``==``, ``!=``, ``in``) or a
    literal list, tuple or set of them (a hand-kept list of the models, as ``click.Choice([...])`` was), as
    ``path:line``. The registry (:mod:`pressfit.dynamics.machine.registry`) is the one reader."""
    out = []
    for path in paths:
        for node in ast.walk(_tree(path)):
            if isinstance(node, ast.Compare):
                operands = [node.left, *node.comparators]
            elif isinstance(node, ast.List | ast.Tuple | ast.Set):
                operands = list(node.elts)
            else:
                continue
            if any(isinstance(o, ast.Constant) and o.value in names for o in operands):
                out.append(f"{path.relative_to(root)}:{node.lineno}")
    return out


def test_only_the_registry_reads_a_model_name():
    """A new dynamics model is one module and one registry line: no other module branches on a model's name or
    keeps its own list of the names (defaults, docs and messages may spell one)."""
    from pressfit.dynamics.machine.registry import model_names

    registry = SRC / "dynamics" / "machine" / "registry.py"
    assert model_name_reads(sorted(p for p in SRC.rglob("*.py") if p != registry), model_names()) == []


def test_the_model_name_check_catches_a_branch_and_a_list(tmp_path):
    (tmp_path / "m.py").write_text('def f(m):\n    if m == "rigid":\n        return ["flexible", "rigid"]\n'
                                   '    return m\n\n\nDEFAULT = "rigid"\n')
    assert model_name_reads([tmp_path / "m.py"], ("flexible", "rigid"), tmp_path) == ["m.py:2", "m.py:3"]
