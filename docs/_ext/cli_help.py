"""``{command-help}``: the command line's own help, run at build time (``python -m holo_core
--help``, then each subcommand's), so the reference page is what the program says."""

import os
import re
import subprocess
import sys
from pathlib import Path

from docutils import nodes
from sphinx.util.docutils import SphinxDirective

ROOT = Path(__file__).resolve().parents[2]


def _help(*args):
    env = dict(os.environ, COLUMNS="96", PYTHONPATH=str(ROOT))
    run = subprocess.run(
        [sys.executable, "-m", "holo_core", *args, "--help"],
        env=env,
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    )
    return run.stdout.replace(Path(sys.executable).name, "python")


class CommandHelp(SphinxDirective):
    def run(self):
        top = _help()
        out = [nodes.literal_block(top, top)]
        found = re.search(r"\{([\w,-]+)\}", top)
        for command in found.group(1).split(",") if found else ():
            section = nodes.section(ids=[f"command-{command}"])
            title = f"python -m holo_core {command}"
            section += nodes.title(title, "", nodes.literal(title, title))
            text = _help(command)
            section += nodes.literal_block(text, text)
            out.append(section)
        return out


def setup(app):
    app.add_directive("command-help", CommandHelp)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
