"""The house's rules, read from the code's own imports (README, "Architecture"):

- holo_core never imports bpy, and pyopencl only under holo_core/opencl/;
- the plate and the camera hologram are siblings: neither imports the other;
- io/ holds file formats only: no physics (plate, camera, optics, propagation, opencl);
- scene/ holds the nouns: it imports no stage (plate, camera, io, optics, propagation, opencl);
- the add-on's folders import only those below them: ui → compositor → render → export →
  blender, and blender/ imports nothing else of the add-on;
- no private name (``_x``) is imported from another module.
"""

import ast
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LAYERS = ["blender", "export", "render", "compositor", "ui"]  # each may import those before it


def _module(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path):
    """(imported module, names) for each import of ``path``, relative ones resolved."""
    here = _module(path).split(".")
    package = here if path.name == "__init__.py" else here[:-1]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name, []
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            names = [a.name for a in node.names]
            yield module, names
            for n in names:  # `from . import sub` imports a module
                yield f"{module}.{n}", []


def _edges(package: str):
    for path in sorted((ROOT / package).rglob("*.py")):
        for module, names in _imports(path):
            yield _module(path), module, names


def _places(module: str) -> list[str]:
    return module.split(".")[:2]


@pytest.mark.parametrize("rule, bad", [
    ("holo_core imports bpy", lambda a, b: b.split(".")[0] == "bpy"),
    ("pyopencl outside holo_core.opencl",
     lambda a, b: b.split(".")[0] == "pyopencl" and _places(a) != ["holo_core", "opencl"]),
    ("plate imports camera", lambda a, b: _places(a) == ["holo_core", "plate"]
     and _places(b) == ["holo_core", "camera"]),
    ("camera imports plate", lambda a, b: _places(a) == ["holo_core", "camera"]
     and _places(b) == ["holo_core", "plate"]),
    ("io imports physics", lambda a, b: _places(a) == ["holo_core", "io"] and _places(b)[1:] in (
        ["plate"], ["camera"], ["optics"], ["propagation"], ["opencl"])),
    ("scene imports a stage", lambda a, b: _places(a) == ["holo_core", "scene"] and _places(b)[1:] in (
        ["plate"], ["camera"], ["io"], ["optics"], ["propagation"], ["opencl"])),
])
def test_holo_core_rules(rule, bad):
    hits = [f"{a} -> {b}" for a, b, _ in _edges("holo_core") if b.startswith(("holo_core", "bpy", "pyopencl")) and bad(a, b)]
    assert hits == [], f"{rule}: {hits}"


def test_addon_folders_import_only_those_below():
    hits = []
    for a, b, _ in _edges("holo_addon"):
        pa, pb = a.split("."), b.split(".")
        if pb[0] != "holo_addon" or len(pa) < 3 or len(pb) < 2 or pa[1] not in LAYERS:
            continue
        if pb[1] in LAYERS and LAYERS.index(pb[1]) > LAYERS.index(pa[1]):
            hits.append(f"{a} -> {b}")
        if pa[1] == "blender" and pb[1] != "blender":
            hits.append(f"{a} -> {b}")
    assert hits == [], hits


@pytest.mark.parametrize("package", ["holo_core", "holo_addon"])
def test_no_private_name_crosses_a_module(package):
    hits = [f"{a} imports {b}.{n}" for a, b, names in _edges(package) for n in names
            if b.split(".")[0] in ("holo_core", "holo_addon") and n.startswith("_")
            and not n.startswith("__")]
    assert hits == [], hits


def test_the_rules_see_real_imports():
    """The reader resolves relative imports: the plate's view is seen importing the scene."""
    edges = {(a, b) for a, b, _ in _edges("holo_core")}
    assert ("holo_core.plate.view", "holo_core.scene.camera") in edges
    assert ("holo_addon.ui.panels", "holo_addon.compositor.session") in \
        {(a, b) for a, b, _ in _edges("holo_addon")}


def test_each_kernel_file_lies_beside_its_module_and_ships():
    """A ``.cl`` file lies beside the host module of the same name that launches it (only the
    shared headers stay in opencl/), and the package data patterns ship every one of them."""
    core = ROOT / "holo_core"
    kernels = sorted(core.rglob("*.cl"))
    assert kernels, "no kernel files found"
    orphans = [str(k.relative_to(ROOT)) for k in kernels if not k.with_suffix(".py").is_file()]
    assert orphans == [], f"kernel files without their host module: {orphans}"
    in_opencl = [str(k.relative_to(ROOT)) for k in kernels if k.parent.name == "opencl"]
    assert in_opencl == [], f"opencl/ keeps only the shared headers: {in_opencl}"
    patterns = tomllib.loads((ROOT / "pyproject.toml").read_text())[
        "tool"]["setuptools"]["package-data"]["holo_core"]
    shipped = {p for pattern in patterns for p in core.glob(pattern)}
    missing = [str(p.relative_to(ROOT)) for p in kernels + sorted(core.rglob("*.h"))
               if p not in shipped]
    assert missing == [], f"not in the package data: {missing}"
