"""The installed package is the tree: every folder of gearlab/ and plugins/ that Python imports as a
package is listed in pyproject.toml's [tool.setuptools] packages, so `pip install .` (not only an editable
install, which reads the tree itself) ships every module the product imports."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _packages_in_tree() -> set[str]:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    found = set()
    for name, folder in config["package-dir"].items():
        for init in (ROOT / folder).rglob("__init__.py"):
            parts = init.parent.relative_to(ROOT / folder).parts
            if "__pycache__" not in parts:
                found.add(".".join((name, *parts)))
    return found


def test_every_package_folder_is_listed_for_a_wheel():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    missing = sorted(_packages_in_tree() - listed)
    assert not missing, f"pyproject.toml [tool.setuptools] packages lacks {missing}: a wheel would not hold them"
    assert not listed - _packages_in_tree(), "pyproject.toml lists packages the tree does not have"
