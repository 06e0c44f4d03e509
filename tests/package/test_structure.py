"""The package's structure: one-way imports without circles, small modules and functions.

Read from the source with ``ast`` (nothing is imported): every ``pilegroup.*`` import is an edge
between modules. No circle, type-only imports (under ``if TYPE_CHECKING:``) included: a type two
modules need lives below both. The layering of data (model -> geometry -> solver -> studies)
holds for the imports at run time. Limits (docs/architecture.md): modules up to 500 lines and
functions up to 80 lines, unless the module docstring says why (a line starting ``Size:``).
The step protocol (:mod:`pilegroup.solver.step_protocol`) is the only way Newton, the stepper
and the constraints use a problem, and no module reads another object's private attributes.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FOLDERS = {"model": "pilegroup.model", "geometry": "pilegroup.geometry",
           "constitutive": "pilegroup.constitutive", "solver": "pilegroup.solver",
           "studies": "pilegroup.studies", "src/pilegroup": "pilegroup"}
#: Which layer may import which (data flows one way: model -> geometry -> solver -> studies;
#: inside studies: results -> report -> run -> batch, verification -> campaigns, lab -> bench
#: -> cli).
LAYER = {"pilegroup": 0, "pilegroup.constitutive": 1, "pilegroup.model": 1,
         "pilegroup.geometry": 2, "pilegroup.solver": 3, "pilegroup.studies": 4,
         "pilegroup.studies.results": 4.1, "pilegroup.studies.report": 4.2,
         "pilegroup.studies.run": 4.3, "pilegroup.studies.batch": 4.4,
         "pilegroup.studies.verification": 4.4, "pilegroup.studies.campaigns": 4.5,
         "pilegroup.studies.lab": 4.5,
         "pilegroup.studies.bench": 4.6, "pilegroup.studies.cli": 4.7,
         "pilegroup.__main__": 5}
MAX_MODULE, MAX_FUNCTION = 500, 80


def _modules() -> dict[str, Path]:
    out = {}
    for folder, pkg in FOLDERS.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            rel = path.relative_to(ROOT / folder).with_suffix("")
            parts = [p for p in rel.parts if p != "__init__"]
            out[".".join([pkg, *parts])] = path
    return out


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _imports(tree: ast.AST, known: set[str], type_only: bool = False) -> set[str]:
    found: set[str] = set()

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node) and not type_only:
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return {m for m in found if m in known}


def _layer(module: str) -> int:
    return max(v for k, v in LAYER.items() if module == k or module.startswith(k + "."))


GRAPH = {m: _imports(ast.parse(p.read_text()), set(_modules()))
         for m, p in _modules().items()}
#: Every import, type-only ones included.
ALL_IMPORTS = {m: _imports(ast.parse(p.read_text()), set(_modules()), type_only=True)
               for m, p in _modules().items()}


def test_no_import_circle():
    state: dict[str, int] = {}

    def walk(m: str, stack: list[str]) -> None:
        state[m] = 1
        for n in sorted(ALL_IMPORTS[m]):
            if n == m or n.startswith(m + "."):
                continue  # a package importing its own modules
            assert state.get(n) != 1, "import circle: " + " -> ".join([*stack, m, n])
            if n not in state:
                walk(n, [*stack, m])
        state[m] = 2

    for m in sorted(ALL_IMPORTS):
        if m not in state:
            walk(m, [])


def test_imports_flow_one_way():
    wrong = [(m, n) for m, ns in GRAPH.items() for n in ns if _layer(n) > _layer(m)]
    assert not wrong, wrong


@pytest.mark.parametrize("module", sorted(_modules()))
def test_module_and_function_sizes(module):
    path = _modules()[module]
    text = path.read_text()
    tree = ast.parse(text)
    doc = ast.get_docstring(tree) or ""
    if any(line.startswith("Size:") for line in doc.splitlines()):
        return
    assert text.count("\n") <= MAX_MODULE, f"{path}: {text.count(chr(10))} lines"
    long = [(n.name, n.end_lineno - n.lineno + 1) for n in ast.walk(tree)
            if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)
            and n.end_lineno - n.lineno + 1 > MAX_FUNCTION]
    assert not long, f"{path}: {long}"


def test_module_names_are_unique():
    """One name per concept: no two modules share a file name (``__init__``/``__main__`` aside)."""
    seen: dict[str, list[str]] = {}
    for m, p in _modules().items():
        if p.stem not in ("__init__", "__main__"):
            seen.setdefault(p.stem, []).append(m)
    assert not {k: v for k, v in seen.items() if len(v) > 1}


def test_class_names_are_unique():
    """One name per concept: a class name is defined in one module of the package only."""
    seen: dict[str, list[str]] = {}
    for m, p in _modules().items():
        for node in ast.parse(p.read_text()).body:
            if isinstance(node, ast.ClassDef):
                seen.setdefault(node.name, []).append(m)
    assert not {k: v for k, v in seen.items() if len(v) > 1}


def _private_reads(tree: ast.AST) -> list[str]:
    """``obj._name`` where ``obj`` is not ``self``/``cls`` (dunder names allowed)."""
    out = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and node.attr.startswith("_")
                and not node.attr.startswith("__")):
            owner = node.value
            if not (isinstance(owner, ast.Name) and owner.id in ("self", "cls")):
                out.append(f"line {node.lineno}: {ast.unparse(node)}")
    return out


@pytest.mark.parametrize("module", sorted(_modules()))
def test_no_private_attribute_of_another_object(module):
    assert not _private_reads(ast.parse(_modules()[module].read_text())), module


def _protocol_members() -> set[str]:
    tree = ast.parse((ROOT / "solver" / "step_protocol.py").read_text())
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "StepProblem")
    return {n.name for n in cls.body if isinstance(n, ast.FunctionDef)}


def _problem_uses(tree: ast.AST) -> set[str]:
    """Attributes read on ``pb``, ``problem`` or ``self.problem``."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            v = node.value
            if (isinstance(v, ast.Name) and v.id in ("pb", "problem")) or (
                    isinstance(v, ast.Attribute) and v.attr == "problem"
                    and isinstance(v.value, ast.Name) and v.value.id == "self"):
                out.add(node.attr)
    return out


@pytest.mark.parametrize("name", ["newton", "stepping", "constraints"])
def test_solver_drivers_use_the_step_protocol_only(name):
    members = _protocol_members()
    assert {"solve_step", "set_step", "residual_state"} <= members
    used = _problem_uses(ast.parse((ROOT / "solver" / f"{name}.py").read_text()))
    assert used, name  # the check reads the driver's uses of the problem
    assert used <= members, sorted(used - members)


def test_every_module_is_in_the_architecture_document():
    """docs/architecture.md names every module (in backticks) with what it owns."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    missing = sorted(str(p.relative_to(ROOT)) for p in _modules().values()
                     if p.stem != "__init__" and f"`{p.stem}`" not in text)
    subpackages = sorted(str(p.parent.relative_to(ROOT)) for p in _modules().values()
                         if p.stem == "__init__" and f"`{p.parent.name}`" not in text)
    assert not missing and not subpackages, (missing, subpackages)
