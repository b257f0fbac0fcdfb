"""The house's one-way streets, read from every import statement of the product packages.

``service -> planner`` and never back; ``planner`` imports no transport; the lab (:mod:`lab`) imports the product
and the product never imports the lab, except lazily inside the CLI verbs that run it (``bench`` and
``controllers tune|figures|bench``); and no two product modules import each other.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
TRANSPORTS = {"fastapi", "uvicorn", "zenoh", "pydantic", "starlette", "httpx"}
#: the only product modules allowed to reach into the lab, and only from inside a function
LAB_DOORS = {"service/cli/bench.py", "service/cli/controllers.py"}


def _imports(path: Path) -> list[tuple[str, bool]]:
    """(imported module, at module level?) for every import in ``path``."""
    tree = ast.parse(path.read_text(), str(path))
    top = set(map(id, tree.body))
    found: list[tuple[str, bool]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(a.name, id(node) in top) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.append((node.module, id(node) in top))
    return found


def _files(package: str) -> list[Path]:
    return sorted((REPO / package).rglob("*.py"))


@pytest.mark.parametrize("path", _files("planner"), ids=lambda p: str(p.relative_to(REPO)))
def test_planner_imports_no_transport_no_service_no_lab(path: Path) -> None:
    for module, _ in _imports(path):
        root = module.split(".")[0]
        assert root not in TRANSPORTS | {"service", "lab"}, f"{path.relative_to(REPO)} imports {module}"


@pytest.mark.parametrize("path", _files("service"), ids=lambda p: str(p.relative_to(REPO)))
def test_service_reaches_the_lab_only_lazily_from_its_verbs(path: Path) -> None:
    rel = str(path.relative_to(REPO))
    for module, top_level in _imports(path):
        if module.split(".")[0] == "lab":
            assert rel in LAB_DOORS and not top_level, f"{rel} imports {module}"


def test_no_import_circle_between_product_modules() -> None:
    names = {}
    for package in ("planner", "service"):
        for path in _files(package):
            mod = ".".join(path.relative_to(REPO).with_suffix("").parts)
            names[mod.removesuffix(".__init__")] = path
    edges: dict[str, set[str]] = {}
    for mod, path in names.items():
        targets = set()
        for module, _ in _imports(path):
            while module and module not in names:
                module = module.rpartition(".")[0]
            if module and module != mod and not mod.startswith(module + ".") and not module.endswith("__init__"):
                if names[module].name != "__init__.py":
                    targets.add(module)
        edges[mod] = targets
    for a, targets in edges.items():
        for b in targets:
            assert a not in edges.get(b, set()), f"{a} and {b} import each other"
