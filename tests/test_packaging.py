"""The installed package is the tree: every folder of gearlab/ and plugins/ that Python imports as a
package is listed in pyproject.toml's [tool.setuptools] packages, so `pip install .` (not only an editable
install, which reads the tree itself) ships every module the product imports, and every data file there
(the built-in gearbox descriptions) is package data of its own folder's package."""

from __future__ import annotations

import fnmatch
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CONFIG = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]


def _shipped_files() -> dict[str, list[Path]]:
    """Each package folder (dotted name) -> its files, __pycache__ left out: a folder with an __init__.py, or
    one holding only data (gearlab/gearbox/presets), which Python imports as a namespace package and
    setuptools then warns of ('Package ... is absent from the `packages` configuration') where it is unlisted."""
    found: dict[str, list[Path]] = {}
    for name, folder in CONFIG["package-dir"].items():
        root = ROOT / folder
        for path in sorted(root.rglob("*")):
            parts = path.relative_to(root).parts
            if path.is_file() and "__pycache__" not in parts and not path.name.endswith((".pyc", ".nbi", ".nbc")):
                found.setdefault(".".join((name, *parts[:-1])), []).append(path)
    return found


def _packages_in_tree() -> set[str]:
    return set(_shipped_files())


def test_every_package_folder_is_listed_for_a_wheel():
    listed = set(CONFIG["packages"])
    missing = sorted(_packages_in_tree() - listed)
    assert not missing, f"pyproject.toml [tool.setuptools] packages lacks {missing}: a wheel would not hold them"
    assert not listed - _packages_in_tree(), "pyproject.toml lists packages the tree does not have"


def test_every_data_file_is_package_data_of_its_own_package():
    data = CONFIG.get("package-data", {})
    for package, files in _shipped_files().items():
        for path in files:
            if path.suffix != ".py":
                assert any(fnmatch.fnmatch(path.name, p) for p in data.get(package, [])), (
                    f"{path.relative_to(ROOT)}: no [tool.setuptools.package-data] pattern of '{package}' matches it"
                )


@pytest.mark.slow
def test_a_wheel_builds_without_warnings_and_carries_the_presets(tmp_path):
    pytest.importorskip("setuptools")
    tree = tmp_path / "tree"
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    for name in listed.decode().split("\0"):
        if name and (ROOT / name).is_file():
            (tree / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, tree / name)
    build = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", ".", "-w", str(tmp_path / "w")],
        cwd=tree,
        capture_output=True,
        text=True,
    )
    assert build.returncode == 0, build.stdout + build.stderr
    assert "absent from the `packages` configuration" not in build.stdout + build.stderr
    (wheel,) = (tmp_path / "w").glob("gearlab-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    presets = {p.relative_to(ROOT).as_posix() for p in (ROOT / "gearlab/gearbox/presets").glob("*.toml")}
    assert presets and presets <= names, sorted(presets - names)
