"""The docstrings rendered as they are written, and their references resolved where they can be.

- Prose parameter lists (``name : text`` lines, continued indented) are set apart by blank
  lines, so that reStructuredText reads each as its own item rather than a broken block quote;
  a ``|`` outside a literal (``|O + R|²``) is text, not a substitution.
- A reference that names an object by another path than the one it is documented under
  (``holo_core.acquired.sideband`` for ``holo_core.sideband``, ``Camera`` inside
  ``holo_core.scene``) links to where it is documented.
- A reference in a docstring to a name the reference does not document (a private helper, a
  module-level constant) is set as code without a link, and listed in
  ``_build/unresolved-docstring-references.txt`` for the docstrings' own pass. References in
  the pages themselves stay strict (``nitpicky``): one that does not resolve fails the build.
"""

import importlib
import re
from pathlib import Path

from docutils import nodes

ITEM = re.compile(r"^[A-Za-z_*][\w, .*\[\]]*\s:\s")
LITERAL = re.compile(r"(``.+?``|:\w+:`[^`]+`|`[^`]+`)")


# a lone * that starts no emphasis: ``(field, *, pitch)``
STAR = re.compile(r"(?<![*\w\\])\*(?=[\s,)\]])")
# characters rST accepts beside an inline literal's start and end
OPEN_OK = set(" \t([{<'\"/-:")
CLOSE_OK = set(" \t-.,:;!?\\/'\")]}>")


def _text(part):
    return STAR.sub(r"\*", part.replace("|", r"\|"))


def escaped(line):
    """Escape ``|`` and lone ``*`` outside literals and roles (a table row keeps its bars),
    and set a break between a literal and a letter glued to it."""
    stripped = line.strip()
    if stripped.startswith(("+-", "+=")) or (
        stripped.startswith("|") and stripped.endswith("|") and stripped.count("|") > 2
    ):
        return line
    parts = LITERAL.split(line)
    for i in range(1, len(parts), 2):  # a literal glued to a letter (``spacing``²) gets a break
        if parts[i].startswith("``"):
            if parts[i - 1] and parts[i - 1][-1] not in OPEN_OK:
                parts[i] = "\\ " + parts[i]
            if parts[i + 1] and parts[i + 1][0] not in CLOSE_OK:
                parts[i] += "\\ "
    return "".join(p if i % 2 else _text(p) for i, p in enumerate(parts))


def tidy(app, what, name, obj, options, lines):
    out = []
    for line in lines:
        if ITEM.match(line) and out and out[-1].strip():
            out.append("")
        out.append(escaped(line))
    lines[:] = out


def _lookup(path):
    """The object a dotted path names, or None."""
    parts = path.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except Exception:  # noqa: BLE001 -- not a module there (or one that fails): shorter
            continue
        try:
            for attr in parts[cut:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def _documented(env):
    """id(object) -> the name the Python domain documents it under."""
    cache = getattr(env, "_holo_documented", None)
    if cache is None or len(cache[0]) != len(env.domains["py"].objects):
        found = {}
        for full in env.domains["py"].objects:
            obj = _lookup(full)
            if obj is not None:
                found.setdefault(id(obj), full)
        cache = (dict(env.domains["py"].objects), found)
        env._holo_documented = cache
    return cache[1]


def _candidates(node):
    target = node["reftarget"].lstrip("~")
    module = node.get("py:module") or ""
    if target.startswith("."):
        target = target.lstrip(".")
        yield f"{module}.{target}"
        parent = module.rsplit(".", 1)[0]
        yield f"{parent}.{target}"
        return
    yield target
    if module:
        yield f"{module}.{target}"
        yield f"{module.rsplit('.', 1)[0]}.{target}"
    yield f"holo_core.{target}"


def resolve(app, env, node, contnode):
    if node.get("refdomain") != "py":
        return None
    documented = _documented(env)
    for path in _candidates(node):
        obj = _lookup(path)
        if obj is not None and id(obj) in documented:
            name = documented[id(obj)]
            kind = env.domains["py"].objects[name].objtype
            role = {
                "function": "func",
                "method": "meth",
                "class": "class",
                "exception": "exc",
                "module": "mod",
                "data": "data",
                "attribute": "attr",
            }.get(kind, "obj")
            return env.domains["py"].resolve_xref(
                env, node.get("refdoc", ""), app.builder, role, name, node, contnode
            )
    source = node.source or ""
    if "docstring of" in source:
        app._holo_unresolved.add(f"{source.split('docstring of ')[-1]}: {node['reftarget']}")
        return nodes.literal(node["reftarget"], node["reftarget"].lstrip("~."))
    return None


def finished(app, exception):
    if exception is None and app._holo_unresolved:
        path = Path(app.outdir).parent / "unresolved-docstring-references.txt"
        path.write_text("\n".join(sorted(app._holo_unresolved)) + "\n")


def setup(app):
    app._holo_unresolved = set()
    app.connect("autodoc-process-docstring", tidy, priority=900)  # after numpydoc
    app.connect("missing-reference", resolve)
    app.connect("build-finished", finished)
    return {"parallel_read_safe": False, "parallel_write_safe": True}
