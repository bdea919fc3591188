"""The package's architecture, checked (docs/overview.md, "Layout").

Layers: ``cli`` → ``workflows`` (and the public ``reference`` facade) → the families
(``rotation``, ``orbit``, ``hamilton``, independent of each other) → ``mechanics`` → ``core``.
The import contracts are import-linter's (``pyproject.toml``, run by ``lint-imports`` in CI):
the layers, and no import of a family from the workflows, the command line or the facades;
here the same contracts run inside the test suite, with what import-linter does not check:
no import cycle anywhere in the package, every name a public module advertises bound, and each
public name given one home (heyoka.py's ``test_package_layout.py`` is the model).
"""

from __future__ import annotations

import importlib
from pathlib import Path

import grimp
import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "cayley_heyoka"
#: The public modules, whose ``__all__`` is the API.
PUBLIC = ("cayley_heyoka", "cayley_heyoka.reference", "cayley_heyoka.testing")
#: Lines a package module may have (docstrings and comments included).
MAX_LINES = 800


def test_import_contracts_hold():
    from importlinter.cli import lint_imports

    assert lint_imports(config_filename=str(PACKAGE.parent / "pyproject.toml")) == 0


def _cycles(graph: grimp.ImportGraph) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.find_modules_directly_imported_by(v):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for module in sorted(graph.modules):
        if module not in index:
            visit(module)
    return found


def test_no_import_cycles():
    """Function-level imports count too: a cycle broken only by deferring an import is still
    a cycle in the design."""
    graph = grimp.build_graph("cayley_heyoka", cache_dir=None)
    assert _cycles(graph) == []


@pytest.mark.parametrize("name", PUBLIC)
def test_all_entries_are_bound(name):
    module = importlib.import_module(name)
    for entry in module.__all__:
        assert hasattr(module, entry), f"{name}.__all__ lists {entry!r}, which is not bound"


def test_public_names_have_one_home():
    """A public name is exported by one public module, and is the object its defining module
    holds (a re-export, never a copy)."""
    homes: dict[str, list[str]] = {}
    for name in PUBLIC:
        module = importlib.import_module(name)
        for entry in module.__all__:
            obj = getattr(module, entry)
            defined = getattr(obj, "__module__", None)
            if defined is not None and not isinstance(obj, type(module)):
                assert getattr(importlib.import_module(defined), obj.__name__) is obj, entry
            homes.setdefault(entry, []).append(name)
    shared = {entry: where for entry, where in homes.items() if len(where) > 1}
    assert shared == {}


def test_every_package_has_an_init():
    """A folder without ``__init__.py`` is a namespace package that tools (and import-linter)
    do not see as part of ours."""
    missing = [
        str(d.relative_to(PACKAGE.parent))
        for d in PACKAGE.rglob("*")
        if d.is_dir() and d.name != "__pycache__" and not (d / "__init__.py").exists()
    ]
    assert missing == []


def test_families_are_registered_by_their_own_record():
    from cayley_heyoka.core.families import FAMILIES, Family

    assert set(FAMILIES) >= {"rotation", "orbit", "hamiltonian"}
    for name in FAMILIES:
        family = FAMILIES[name]
        assert isinstance(family, Family) and family.name == name


def _unresolved(root: Path, top: Path, ours: set[str]) -> list[str]:
    """Every ``from X import name`` under ``root`` (modules named relative to ``top``) whose
    name neither X nor a submodule X.name provides; X is relative or one of ``ours``."""
    import ast

    broken = []
    for path in sorted(root.rglob("*.py")):
        parts = path.relative_to(top).with_suffix("").parts
        package = parts[:-1]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ImportFrom):
                continue
            if node.level:
                base = list(package)[: len(package) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            elif node.module and node.module.split(".")[0] in ours:
                target = node.module
            else:
                continue
            module = importlib.import_module(target)
            for alias in node.names:
                if hasattr(module, alias.name):
                    continue
                try:
                    importlib.import_module(f"{target}.{alias.name}")
                except ImportError:
                    broken.append(f"{path.relative_to(top)}: {target}.{alias.name}")
    return broken


def test_every_import_in_the_package_resolves():
    """Function-level imports included: a module moved or a name renamed breaks a deferred
    import only when that function first runs, which a test may never reach."""
    assert _unresolved(PACKAGE, PACKAGE.parent, {"cayley_heyoka"}) == []


def test_no_module_is_too_long():
    long = {
        str(p.relative_to(PACKAGE.parent)): n
        for p in PACKAGE.rglob("*.py")
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert long == {}


def test_no_module_takes_another_modules_private_names():
    import ast

    taken = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (
                node.level or (node.module or "").split(".")[0] == "cayley_heyoka"
            ):
                private = [a.name for a in node.names if a.name.startswith("_")]
                if private:
                    taken.append(f"{path.relative_to(PACKAGE.parent)}: {private}")
    assert taken == []


def test_every_import_in_validation_resolves():
    """The same for the validation scripts and their packages (tests run few of their paths)."""
    validation = PACKAGE.parent / "validation"
    ours = {p.stem for p in validation.glob("*.py")} | {
        p.parent.name for p in validation.glob("*/__init__.py")
    }
    assert _unresolved(validation, validation, ours | {"cayley_heyoka"}) == []
