"""Sphinx configuration: MyST Markdown pages, executed MyST notebooks (the tutorials), furo,
autodoc with numpydoc; offline (no intersphinx) and, with ``-W -n``, free of warnings."""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).parent / "_ext"))
# the tutorials' kernels import the tree's holo_core, not an installed copy
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))

import holo_core  # noqa: E402

project = "Holo"
author = "Holo developers"
copyright = "2026, Holo developers"
release = version = holo_core.__version__

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax from the build, not a CDN: the pages read offline
    "numpydoc",
    "api_pages",
    "docstrings",
    "bench_results",
    "cli_help",
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "jupyter_execute", "**.ipynb_checkpoints"]
root_doc = "index"

# MyST: $…$ maths as the paper writes it, ::: fences, anchors for headings to three levels
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist", "substitution"]


def _formats():
    """The file formats' names and versions, as the readers and writers hold them."""
    import importlib

    found = {}
    for key, module, names in (
        ("hologram", "holo_core.io.hologram", ("FORMAT", "FORMAT_VERSION", "READS")),
        ("display", "holo_core.io.display", ("FORMAT", "VERSION")),
        ("slm", "holo_core.io.slm", ("FORMAT", "VERSION")),
        ("store", "holo_core.io.store", ("STORE_FORMAT",)),
        ("plate_set", "holo_core.io.plate_set", ("KIND", "VERSION")),
    ):
        try:
            m = importlib.import_module(module)
        except ImportError:  # a module moved: the page says so rather than a stale number
            m = None
        for name in names:
            value = getattr(m, name, "(see the module)")
            found[f"{key}_{name.lower()}"] = (
                ", ".join(map(str, value)) if isinstance(value, tuple) else str(value)
            )
    return found


myst_substitutions = {"version": holo_core.__version__, **_formats()}
myst_heading_anchors = 3

# The tutorials run at every build, each in a fresh kernel; a cell that raises fails the build
nb_execution_mode = "force"
nb_execution_timeout = 180
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

# autodoc and numpydoc over the docstrings as they are: types and members stay text, the
# prose is rendered; the signatures carry no annotations (they would be cross-references to
# NumPy's and Python's pages, which an offline build does not have)
autodoc_typehints = "none"
autodoc_member_order = "bysource"
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks = set()
numpydoc_xref_param_type = False
numpydoc_attributes_as_param_list = False

# Every cross-reference resolves (sphinx -n): what cannot, because it points outside this
# site, is named here
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|pyopencl|cl|dask|zarr|h5py|matplotlib|bpy|concurrent|pathlib|os)\..*"),
]

html_theme = "furo"
html_title = f"Holo {release}"
html_static_path = []
html_theme_options = {"source_repository": "", "navigation_with_keys": True}
html_show_sourcelink = False
