"""The package's layers point one way: the import graph between its packages has no cycle."""

import ast
from pathlib import Path

import pytest
import tomllib

PACKAGE = Path(__file__).resolve().parents[1] / "jugglerl"


def unit(module: str) -> str:
    """The package (or top-level module) of ``jugglerl`` that ``module`` belongs to."""
    return ".".join(module.split(".")[:2])


def import_graph() -> dict[str, set[str]]:
    """``{unit: the other units it imports}``, from every import statement of every module
    (those inside functions too: a deferred import is still a dependency)."""
    graph: dict[str, set[str]] = {}
    for path in PACKAGE.rglob("*.py"):
        module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        source = unit(module.removesuffix(".__init__"))
        targets = graph.setdefault(source, set())
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            inside = {unit(name) for name in names if name.startswith("jugglerl.")}
            targets.update(inside - {source})
    return graph


def cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as a path that returns to its start, or None."""
    state: dict[str, str] = {}
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = "open"
        path.append(node)
        for target in sorted(graph.get(node, ())):
            if state.get(target) == "open":
                return path[path.index(target) :] + [target]
            if target not in state and (found := visit(target)):
                return found
        state[node] = "done"
        path.pop()
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_the_graph_sees_the_packages_and_their_imports():
    graph = import_graph()
    layers = {"jugglerl.policies", "jugglerl.offpolicy", "jugglerl.networks", "jugglerl.state"}
    assert layers <= set(graph)
    assert "jugglerl.networks" in graph["jugglerl.offpolicy"]


def test_the_cycle_finder_finds_a_cycle_and_accepts_a_layered_graph():
    assert cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) is None


def test_no_two_packages_import_each_other_even_through_others():
    found = cycle(import_graph())
    assert found is None, "import cycle: " + " -> ".join(found)


@pytest.mark.parametrize("lower", ["jugglerl.policies", "jugglerl.networks", "jugglerl.state"])
def test_what_deploys_a_policy_never_needs_the_trainer(lower):
    assert "jugglerl.offpolicy" not in import_graph()[lower]


def test_every_package_folder_is_installed():
    """A non-editable ``pip install .`` installs only the packages pyproject.toml lists."""

    listed = set(
        tomllib.loads((PACKAGE.parent / "pyproject.toml").read_text())["tool"]["setuptools"][
            "packages"
        ]
    )
    folders = {
        ".".join(path.parent.relative_to(PACKAGE.parent).parts)
        for path in PACKAGE.rglob("__init__.py")
        if "_hydra_plugin" not in path.parts
    }
    assert folders - listed == set()
