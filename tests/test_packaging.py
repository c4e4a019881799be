"""One import name: the wheel installs afford and nothing else at the top of site-packages."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: repository folder -> the package it is in the wheel
FOLDERS = {"afford_cli": "afford", "sim": "afford.sim", "features": "afford.features",
           "learn": "afford.learn", "plan": "afford.plan"}


def _repo_packages() -> set[str]:
    found = set()
    for folder, package in FOLDERS.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT / folder).parts
            found.add(".".join((package, *rel)))
    return found


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> zipfile.ZipFile:
    # built from a copy, so that setuptools' build/ and egg-info land in no checkout
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        if (ROOT / name).exists():
            shutil.copy(ROOT / name, src / name)
    for folder in FOLDERS:
        shutil.copytree(ROOT / folder, src / folder, ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation",
                    "--disable-pip-version-check", "-w", str(out), str(src)], check=True, capture_output=True)
    (path,) = out.glob("afford-*.whl")
    return zipfile.ZipFile(path)


def test_the_wheel_has_one_top_level_name(wheel):
    top = {name.split("/")[0] for name in wheel.namelist()}
    assert {t for t in top if not t.endswith(".dist-info")} == {"afford"}
    dist_info = next(t for t in top if t.endswith(".dist-info"))
    assert wheel.read(f"{dist_info}/top_level.txt").decode().split() == ["afford"]


def test_every_package_folder_is_in_the_wheel(wheel):
    names = set(wheel.namelist())
    missing = [p for p in sorted(_repo_packages()) if p.replace(".", "/") + "/__init__.py" not in names]
    assert not missing, f"add {missing} to [tool.setuptools] packages in pyproject.toml"
    assert "afford/sim/scenes/traverse.py" in names and "afford/app.py" in names


def test_the_import_contracts_name_every_module_of_the_cli():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    cli = {f"afford.{p.stem}" for p in (ROOT / "afford_cli").glob("*.py") if p.stem not in ("__init__", "__main__")}
    cli |= {f"afford.{p.parent.name}" for p in (ROOT / "afford_cli").glob("*/__init__.py")}
    for contract in config["contracts"]:
        forbidden = set(contract["forbidden_modules"])
        assert cli <= forbidden | {"afford.sim", "afford.features", "afford.learn", "afford.plan"}, \
            f"contract {contract['name']!r} does not forbid {sorted(cli - forbidden)}"
