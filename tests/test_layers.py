"""The package's layers point one way (docs/design.md, section 1): the pipeline's
stages and the environments never import the tools above them, graspenv never
imports the repository's agents, and only the physics stage imports pybullet."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "graspenv"

#: The tools: the benchmarks, the demo, replay, charts, the live table, scale-out and
#: the command line.
TOOLS = (
    "graspenv.bench",
    "graspenv.demo",
    "graspenv.replay",
    "graspenv.plots",
    "graspenv.cli",
    "graspenv.live",
    "graspenv.cluster",
)


def _module(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """Every module a file imports, at its top or inside functions."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found.update(f"{node.module}.{alias.name}" for alias in node.names)
    return found


MODULES = {_module(p): _imports(p) for p in sorted(PACKAGE.rglob("*.py"))}


def _within(name: str, prefixes: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


@pytest.mark.parametrize("module", [m for m in MODULES if not _within(m, TOOLS)])
def test_no_stage_or_environment_imports_a_tool(module: str) -> None:
    assert not [name for name in MODULES[module] if _within(name, TOOLS)]


def test_graspenv_never_imports_the_agents_and_only_physics_imports_pybullet() -> None:
    for module, names in MODULES.items():
        assert not [n for n in names if _within(n, ("agents", "graspenv_agents"))], module
        if not _within(module, ("graspenv.physics",)):
            assert "pybullet" not in names and "pybullet_data" not in names, module


def test_the_layer_rules_see_the_imports() -> None:
    """A rule that reads no imports would pass anything."""
    assert "graspenv.bench.frontier" in MODULES["graspenv.bench.grid"] or any(
        n.startswith("graspenv.bench") for n in MODULES["graspenv.bench.grid"]
    )
    assert "pybullet" in set().union(
        *(MODULES[m] for m in MODULES if m.startswith("graspenv.physics"))
    )
