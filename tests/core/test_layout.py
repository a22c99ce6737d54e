"""The house's rules, read from the code's own imports (README, "Architecture"):

- holo_core never imports bpy, and pyopencl only under holo_core/opencl/;
- the plate and the camera hologram are siblings: neither imports the other;
- io/ holds file formats only: no physics (plate, camera, optics, propagation, opencl);
- scene/ holds the nouns: it imports no stage (plate, camera, io, optics, propagation, opencl);
- the add-on's folders import only those below them: ui → compositor → render → export →
  blender, and blender/ imports nothing else of the add-on;
- no private name (``_x``) is imported from another module;
- no circle of imports among a package's modules, imports inside functions included.
"""

import ast
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LAYERS = ["blender", "export", "render", "compositor", "ui"]  # each may import those before it


def _module(path: Path, root: Path = ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, root: Path = ROOT):
    """(imported module, names) for each import of ``path``, relative ones resolved."""
    here = _module(path, root).split(".")
    package = here if path.name == "__init__.py" else here[:-1]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name, []
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            names = [a.name for a in node.names]
            yield module, names
            for n in names:  # `from . import sub` imports a module
                yield f"{module}.{n}", []


def _edges(package: str):
    for path in sorted((ROOT / package).rglob("*.py")):
        for module, names in _imports(path):
            yield _module(path), module, names


def _graph(package: str, root: Path = ROOT) -> dict[str, set[str]]:
    """Module -> the modules of ``package`` it imports, read from every import statement
    (inside functions too). ``from p import x`` reaches the module ``p.x`` where there is one,
    else ``p``; a package's ``__init__`` run before its submodules is no edge."""
    paths = sorted((root / package).rglob("*.py"))
    graph = {_module(path, root): set() for path in paths}
    for path in paths:
        a = _module(path, root)
        for module, names in _imports(path, root):
            subs = [f"{module}.{n}" for n in names if f"{module}.{n}" in graph]
            for b in subs or [module]:
                if b in graph and b != a and not (subs and b == module):
                    graph[a].add(b)
    return graph


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's), each sorted."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while not component or component[-1] != v:
                component.append(stack.pop())
                on.discard(component[-1])
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def _places(module: str) -> list[str]:
    return module.split(".")[:2]


@pytest.mark.parametrize(
    "rule, bad",
    [
        ("holo_core imports bpy", lambda a, b: b.split(".")[0] == "bpy"),
        (
            "pyopencl outside holo_core.opencl",
            lambda a, b: b.split(".")[0] == "pyopencl" and _places(a) != ["holo_core", "opencl"],
        ),
        (
            "plate imports camera",
            lambda a, b: (
                _places(a) == ["holo_core", "plate"] and _places(b) == ["holo_core", "camera"]
            ),
        ),
        (
            "camera imports plate",
            lambda a, b: (
                _places(a) == ["holo_core", "camera"] and _places(b) == ["holo_core", "plate"]
            ),
        ),
        (
            "io imports physics",
            lambda a, b: (
                _places(a) == ["holo_core", "io"]
                and _places(b)[1:]
                in (["plate"], ["camera"], ["optics"], ["propagation"], ["opencl"])
            ),
        ),
        (
            "scene imports a stage",
            lambda a, b: (
                _places(a) == ["holo_core", "scene"]
                and _places(b)[1:]
                in (["plate"], ["camera"], ["io"], ["optics"], ["propagation"], ["opencl"])
            ),
        ),
    ],
)
def test_holo_core_rules(rule, bad):
    hits = [
        f"{a} -> {b}"
        for a, b, _ in _edges("holo_core")
        if b.startswith(("holo_core", "bpy", "pyopencl")) and bad(a, b)
    ]
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
    hits = [
        f"{a} imports {b}.{n}"
        for a, b, names in _edges(package)
        for n in names
        if b.split(".")[0] in ("holo_core", "holo_addon")
        and n.startswith("_")
        and not n.startswith("__")
    ]
    assert hits == [], hits


def _file(module: str) -> str:
    path = ROOT.joinpath(*module.split("."))
    return str(
        (
            path.with_suffix(".py") if path.with_suffix(".py").is_file() else path / "__init__.py"
        ).relative_to(ROOT)
    )


@pytest.mark.parametrize("package", ["holo_core", "holo_addon"])
def test_no_import_circle(package):
    """Every module of a package can be imported after the ones it imports: no module reaches
    itself through the imports of others, an import inside a function counted like one at the
    top (it only moves the circle from import time to call time)."""
    circles = [" <-> ".join(_file(m) for m in c) for c in _circles(_graph(package))]
    assert circles == [], f"import circles in {package}: {circles}"


def test_the_circle_reader_sees_hidden_and_relative_imports(tmp_path):
    """A circle closed by an import inside a function, written with relative imports and
    ``from . import x``, is found; the package's ``__init__`` importing its modules is none."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("from .a import f\nfrom . import sub\n")
    (pkg / "a.py").write_text("from .sub import b\n")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "sub" / "b.py").write_text("def g():\n    from .. import c\n")
    (pkg / "c.py").write_text("import pkg.a\nfrom . import d\n")
    (pkg / "d.py").write_text("from pkg import a\n")
    circles = _circles(_graph("pkg", tmp_path))
    assert circles == [["pkg.a", "pkg.c", "pkg.d", "pkg.sub.b"]], circles


def test_the_rules_see_real_imports():
    """The reader resolves relative imports: the plate's view is seen importing the scene."""
    edges = {(a, b) for a, b, _ in _edges("holo_core")}
    assert ("holo_core.plate.view", "holo_core.scene.camera") in edges
    assert ("holo_addon.ui.panels", "holo_addon.compositor.session") in {
        (a, b) for a, b, _ in _edges("holo_addon")
    }


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
    patterns = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"
    ]["holo_core"]
    shipped = {p for pattern in patterns for p in core.glob(pattern)}
    missing = [
        str(p.relative_to(ROOT)) for p in kernels + sorted(core.rglob("*.h")) if p not in shipped
    ]
    assert missing == [], f"not in the package data: {missing}"
