"""The architecture page matches the package tree, and the rules of the house hold.

Reads ``docs/architecture.md`` and every module's imports with :mod:`ast`; nothing is imported.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "gimwatch"
PAGE = ROOT / "docs" / "architecture.md"

#: One row of the module map: | `gimwatch/x/y.py` | its one job |
ROW = re.compile(r"^\| `(gimwatch/[^`]+\.py)` \| (.*) \|\s*$")
#: One row of the page's layer table: | 3 | `denoc`, `stability` (a remark) |
LAYER_ROW = re.compile(r"^\| (\d+) \| (.*) \|\s*$")


def _layers() -> dict[str, int]:
    """The import layers of the page's table, top (1) to bottom: package or module -> layer.

    The names are those in backticks outside parentheses (a remark may quote a name).
    """
    layers = {}
    for line in PAGE.read_text(encoding="utf-8").splitlines():
        match = LAYER_ROW.match(line)
        if match:
            names = re.sub(r"\([^)]*\)", "", match.group(2))
            for name in re.findall(r"`([^`]+)`", names):
                layers[name] = int(match.group(1))
    return layers


#: The import layers of the page; a module imports from its layer or the layers above it.
LAYERS = _layers()


def _modules() -> list[Path]:
    return sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def _rows() -> dict[str, str]:
    rows = {}
    for line in PAGE.read_text(encoding="utf-8").splitlines():
        match = ROW.match(line)
        if match:
            rows[match.group(1)] = match.group(2).strip()
    return rows


def _first_docstring_line(path: Path) -> str:
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    return doc.splitlines()[0] if doc else "<its one job, in one line>"


def _gimwatch_imports(path: Path) -> list[tuple[int, str, list[str]]]:
    """(line, imported module, imported names) of every gimwatch import in ``path``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level:
            raise AssertionError(f"{path}:{node.lineno}: relative import; write gimwatch.x")
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("gimwatch"):
            found.append((node.lineno, node.module, [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("gimwatch"):
                    found.append((node.lineno, alias.name, []))
    return found


def test_every_module_is_on_the_architecture_page():
    rows = _rows()
    assert rows, f"{PAGE} has no module table rows of the form | `gimwatch/x.py` | job |"
    missing = [p for p in _modules() if p.relative_to(ROOT).as_posix() not in rows]
    lines = [
        f"  under '### `{p.parent.relative_to(ROOT).as_posix()}/`' add:  "
        f"| `{p.relative_to(ROOT).as_posix()}` | {_first_docstring_line(p)} |"
        for p in missing
    ]
    assert not missing, (
        f"docs/architecture.md does not list {len(missing)} module(s); add one line each "
        "(the job in one line, here the docstring's first line):\n" + "\n".join(lines)
    )


def test_every_module_on_the_architecture_page_exists():
    gone = [name for name in _rows() if not (ROOT / name).is_file()]
    assert not gone, "docs/architecture.md lists modules that are not in the tree; delete:\n" + (
        "\n".join(f"  the line | `{name}` | ... |" for name in gone)
    )


def test_every_listed_module_states_its_job():
    empty = [name for name, job in _rows().items() if not job]
    assert not empty, f"docs/architecture.md: give these modules a one-line job: {empty}"


def test_the_architecture_page_is_in_the_docs_nav():
    # mkdocs.yml is part of the repository: its absence is a failure, not a reason to skip
    assert "architecture.md" in (ROOT / "mkdocs.yml").read_text(encoding="utf-8")


@pytest.mark.parametrize("path", _modules(), ids=lambda p: p.relative_to(PACKAGE).as_posix())
def test_no_cross_module_private_imports(path):
    """A name starting with ``_`` is used only in the module that defines it."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    offences = []
    modules = set()  # local names bound to gimwatch modules
    for line, module, names in _gimwatch_imports(path):
        for name in names:
            if name.startswith("_") and not name.startswith("__") and name != "_version":
                offences.append(f"line {line}: from {module} import {name}")
            modules.add(name)
        if not names:
            modules.add(module.split(".")[0])
    for node in ast.walk(tree):
        if isinstance(node, ast.alias) and node.asname and node.name in modules:
            modules.add(node.asname)
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Attribute)
            and node.attr.startswith("_")
            and not node.attr.startswith("__")
            and isinstance(node.value, ast.Name | ast.Attribute)
            and ast.unparse(node.value).split(".")[0] in modules
        ):
            offences.append(f"line {node.lineno}: {ast.unparse(node)}")
    assert not offences, (
        f"{path.relative_to(ROOT)} uses another module's private names (make the name public "
        "where it is a shared concept, or move it):\n  " + "\n  ".join(offences)
    )


@pytest.mark.parametrize("path", _modules(), ids=lambda p: p.relative_to(PACKAGE).as_posix())
def test_imports_point_down_the_layers(path):
    """A module imports only from its own layer or the layers above it (docs/architecture.md)."""
    parts = path.relative_to(PACKAGE).with_suffix("").parts
    source = parts[0]
    assert source in LAYERS, (
        f"{path.relative_to(ROOT)}: '{source}' has no layer; add it to the layer table in "
        "docs/architecture.md"
    )
    upward = []
    for line, module, _ in _gimwatch_imports(path):
        target = module.split(".")[1] if "." in module else "__init__"
        if target != source and LAYERS.get(target, 0) > LAYERS[source]:
            upward.append(f"line {line}: {module} (layer {LAYERS[target]})")
    assert not upward, (
        f"{path.relative_to(ROOT)} (layer {LAYERS[source]}) imports from a lower layer:\n  "
        + "\n  ".join(upward)
    )


def test_library_code_selects_no_backend_and_does_not_print():
    offences = []
    for path in _modules():
        in_cli = path.relative_to(PACKAGE).parts[0] in {"cli", "__main__.py"}
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.Call):
                continue
            call = ast.unparse(node.func)
            if call in {"matplotlib.use", "plt.show", "pyplot.show"}:
                offences.append(f"{path.relative_to(ROOT)}:{node.lineno}: {call}()")
            if call == "print" and not in_cli:
                offences.append(f"{path.relative_to(ROOT)}:{node.lineno}: print()")
    assert not offences, "library code selects a backend, shows or prints:\n  " + "\n  ".join(
        offences
    )


def test_every_warning_derives_from_gimwatch_warning():
    from gimwatch import errors

    warnings = [v for v in vars(errors).values() if isinstance(v, type) and issubclass(v, Warning)]
    assert errors.GimwatchWarning in warnings
    assert all(issubclass(w, errors.GimwatchWarning) for w in warnings)
    for path in _modules():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef) and node.name.endswith("Warning"):
                assert path.name == "errors.py", f"{path}: define warnings in gimwatch/errors.py"


def test_errors_are_exported():
    import gimwatch
    from gimwatch import errors

    assert set(errors.__all__) <= set(gimwatch.__all__)


def _module_name(path: Path) -> str:
    name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
    return name.removesuffix(".__init__")


def import_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """Module -> the gimwatch modules it imports, anywhere in it (functions and
    ``TYPE_CHECKING`` blocks included: a type-only circle is still a circle to read)."""
    paths = {
        _module_name(p): p
        for p in sorted((root / "gimwatch").rglob("*.py"))
        if "__pycache__" not in p.parts
    }

    def resolve(module: str) -> str:
        while module and module not in paths:
            module = module.rpartition(".")[0]
        return module

    graph = {}
    for name, path in paths.items():
        targets = set()
        for _, module, names in _gimwatch_imports(path):
            for imported in names or [""]:
                full = f"{module}.{imported}" if imported else module
                targets.add(full if full in paths else resolve(module))
        targets.discard(name)
        graph[name] = targets
    return graph


def import_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles = []
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in graph:
                    continue
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    cycles.append(sorted(component))
    return cycles


def test_no_import_cycles():
    cycles = import_cycles(import_graph())
    assert not cycles, "modules that import each other (directly or around a circle):\n" + (
        "\n".join("  " + " <-> ".join(c) for c in cycles)
    )


def test_the_cycle_check_finds_a_planted_cycle():
    graph = import_graph()
    graph["gimwatch.errors"] = graph["gimwatch.errors"] | {"gimwatch.model.robots"}
    cycles = import_cycles(graph)
    assert any({"gimwatch.errors", "gimwatch.model.robots"} <= set(c) for c in cycles)


def test_the_layer_table_is_read_from_the_page():
    """Every top-level package and module has exactly one layer, from 1 to the last."""
    tops = {p.name.removesuffix(".py") for p in PACKAGE.iterdir() if p.name != "__pycache__"}
    tops = {t for t in tops if (PACKAGE / t).is_dir() or (PACKAGE / f"{t}.py").is_file()}
    tops -= {"scenes"}  # package data (scene files), no Python
    assert LAYERS, f"{PAGE} has no layer table rows of the form | 1 | `errors`, ... |"
    assert set(LAYERS) == tops, (
        f"layer table of {PAGE}: missing {sorted(tops - set(LAYERS))}, "
        f"not in the package {sorted(set(LAYERS) - tops)}"
    )
    assert sorted(set(LAYERS.values())) == list(range(1, max(LAYERS.values()) + 1))


def package_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """Top-level package or module -> those it imports (``gimwatch.metrics.x`` -> ``metrics``)."""

    def top(module: str) -> str:
        return module.split(".")[1] if "." in module else "__init__"

    packages: dict[str, set[str]] = {}
    for module, targets in graph.items():
        packages.setdefault(top(module), set()).update(
            top(target) for target in targets if top(target) != top(module)
        )
    return packages


def test_no_circles_between_packages():
    """Two packages of one layer never import each other (metrics <-> stability was one)."""
    cycles = import_cycles(package_graph(import_graph()))
    assert not cycles, "packages that import each other (directly or around a circle):\n" + (
        "\n".join("  " + " <-> ".join(c) for c in cycles)
    )


def test_the_package_circle_check_finds_a_planted_circle():
    graph = import_graph()
    graph["gimwatch.stability.servos"] = graph["gimwatch.stability.servos"] | {
        "gimwatch.metrics.conditioning"
    }
    assert ["metrics", "stability"] in import_cycles(package_graph(graph))


def test_the_library_carries_no_test_hooks():
    """Fault tests pause a command by wrapping its functions (tests/fault_pause.py)."""
    hooks = ("FAULT_PAUSE", "phase_hook", "fault_pause")
    found = [
        f"{path.relative_to(ROOT)}: {hook}"
        for path in _modules()
        for hook in hooks
        if hook in path.read_text(encoding="utf-8")
    ]
    assert not found, "test hooks in library code:\n  " + "\n  ".join(found)
