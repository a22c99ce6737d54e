"""The version is written once, as ``holo_core.__version__``: pyproject.toml reads it from there
(a dynamic version), and Blender's manifest, which must hold a literal, repeats it."""

import re
import tomllib
from pathlib import Path

import holo_core

ROOT = Path(__file__).resolve().parents[2]


def test_the_manifest_holds_the_core_version():
    manifest = tomllib.loads((ROOT / "blender_manifest.toml").read_text())
    assert manifest["version"] == holo_core.__version__, (
        f"blender_manifest.toml version {manifest['version']!r}, "
        f"holo_core.__version__ {holo_core.__version__!r}"
    )


def test_pyproject_takes_the_version_from_the_core():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "version" not in project["project"], "pyproject.toml writes a version of its own"
    assert project["project"]["dynamic"] == ["version"]
    attr = project["tool"]["setuptools"]["dynamic"]["version"]["attr"]
    assert attr == "holo_core.__version__", attr


def test_the_version_is_a_release_number():
    # Blender's extension platform takes semantic versions only
    assert re.fullmatch(r"\d+\.\d+\.\d+", holo_core.__version__), holo_core.__version__
