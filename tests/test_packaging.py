"""What the distribution installs: every package folder, and none under a generic name."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
SETUPTOOLS = PYPROJECT["tool"]["setuptools"]


def _packages(folder: Path, name: str) -> set[str]:
    """The dotted names of ``folder`` and of every sub-folder with an ``__init__.py``,
    installed under ``name``."""
    return {
        ".".join((name, *init.parent.relative_to(folder).parts))
        for init in folder.rglob("__init__.py")
    }


def test_every_package_folder_is_listed() -> None:
    expected = _packages(ROOT / "graspenv", "graspenv") | _packages(
        ROOT / "agents", "graspenv_agents"
    )
    assert set(SETUPTOOLS["packages"]) == expected


def test_the_agents_folder_installs_as_graspenv_agents() -> None:
    assert SETUPTOOLS["package-dir"] == {"graspenv_agents": "agents"}
    top_level = {name.split(".")[0] for name in SETUPTOOLS["packages"]}
    assert top_level == {"graspenv", "graspenv_agents"}
    assert set(SETUPTOOLS["package-data"]) <= top_level


def _source(module: str) -> Path:
    """The file a dotted module name installs from (``package-dir`` applied)."""
    top, _, rest = module.partition(".")
    path = ROOT / SETUPTOOLS["package-dir"].get(top, top)
    path = path.joinpath(*rest.split(".")) if rest else path
    return path.with_suffix(".py") if path.with_suffix(".py").is_file() else path / "__init__.py"


def test_entry_points_name_installed_modules() -> None:
    modules = set(SETUPTOOLS["packages"])
    groups = {"scripts": PYPROJECT["project"]["scripts"], **PYPROJECT["project"]["entry-points"]}
    for group, targets in groups.items():
        for name, target in targets.items():
            module = target.split(":")[0]
            assert module in modules or module.rpartition(".")[0] in modules, f"{group} {name}"
            assert _source(module).is_file(), f"{group} {name}: no source for {module}"
