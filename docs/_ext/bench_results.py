"""The Performance page's tables, rendered from the code and the data at build time.

``{bench-list}`` lists every ``bench/*.py`` with the first paragraph of its docstring (what it
measures); ``{bench-results}`` renders each ``bench/results/NAME.json`` (written by
``bench/results.py``) as a table of its figures under the machine, its load and the date.
Both are for MyST pages: they write Markdown (a definition list, pipe tables).
"""

import ast
import datetime
import json
import re
from pathlib import Path

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective

BENCH = Path(__file__).resolve().parents[2] / "bench"
HELPERS = {"results.py"}  # bench/ modules that measure nothing themselves


def _literal_roles(text):
    """``:meth:`x``` and the like as inline code: the benches' docstrings name code that the
    API pages need not document."""
    return re.sub(r":[a-z]+:`~?([^`]+)`", r"``\1``", text)


def _value(v):
    if isinstance(v, float):
        return f"{v:.3g}" if abs(v) < 1e5 else f"{v:.3e}"
    if isinstance(v, list):
        return ", ".join(_value(x) for x in v)
    return str(v)


def _date(iso):
    try:
        return (
            datetime.datetime.fromisoformat(iso)
            .astimezone(datetime.UTC)
            .strftime("%Y-%m-%d %H:%M UTC")
        )
    except ValueError:
        return iso


def _cell(text):
    """Figures are text, not markup."""
    text = str(text).replace("\n", " ")
    for c in "\\|*_`$<[":
        text = text.replace(c, "\\" + c)
    return text or "—"


def _table(header, rows):
    """A Markdown pipe table."""
    out = ["| " + " | ".join(_cell(c) for c in header) + " |", "|" + "---|" * len(header)]
    return out + ["| " + " | ".join(_cell(c) for c in row) + " |" for row in rows]


class _Markdown(SphinxDirective):
    def parse(self, lines):
        container = nodes.container()
        flat = [part for line in lines for part in line.split("\n")]  # a line an entry
        self.state.nested_parse(StringList(flat, source=str(BENCH)), self.content_offset, container)
        return container.children


class BenchList(_Markdown):
    """Each bench and what it measures (its docstring's first paragraphs)."""

    def run(self):
        lines = []
        for path in sorted(BENCH.glob("*.py")):
            if path.name in HELPERS:
                continue
            self.env.note_dependency(str(path))
            doc = ast.get_docstring(ast.parse(path.read_text())) or "(no docstring)"
            first = doc.split("\n\n")[0]
            lines += [
                f"`bench/{path.name}`",
                ": " + _literal_roles(first).replace("\n", "\n  "),
                "",
            ]
        return self.parse(lines)


class BenchResults(_Markdown):
    """The latest result of every bench that has one."""

    def run(self):
        found = sorted((BENCH / "results").glob("*.json"))
        if not found:
            return self.parse(
                [
                    "No bench has written its figures here yet: run one (`python "
                    "bench/sweep.py`) and build again."
                ]
            )
        lines = []
        for path in found:
            self.env.note_dependency(str(path))
            r = json.loads(path.read_text())
            m = r.get("machine", {})
            lines += [
                f"**`bench/{r.get('bench', path.stem)}.py`**",
                "",
                f"`{r.get('command', '')}` on {_date(r.get('date', ''))}: "
                f"{_cell(m.get('cpu', '?'))}, {m.get('cores', '?')} cores "
                f"({m.get('usable_cpus', '?')} usable), load average "
                f"{_value(m.get('load_at_start', []))} at the start and "
                f"{_value(m.get('load_at_end', []))} at the end (1, 5, 15 min)"
                + (f"; device {_cell(r['device'])}" if r.get("device") else "")
                + ".",
                "",
            ]
            figures = r.get("figures", {})
            tables = {k: v for k, v in figures.items() if isinstance(v, dict)}
            scalars = [(k, _value(v)) for k, v in figures.items() if not isinstance(v, dict)]
            if scalars:
                lines += _table(("figure", "value"), scalars) + [""]
            if tables:
                columns = list(dict.fromkeys(c for row in tables.values() for c in row))
                lines += _table(
                    ("case", *columns),
                    [(k, *(_value(row.get(c, "")) for c in columns)) for k, row in tables.items()],
                ) + [""]
        return self.parse(lines)


def setup(app):
    app.add_directive("bench-list", BenchList)
    app.add_directive("bench-results", BenchResults)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
