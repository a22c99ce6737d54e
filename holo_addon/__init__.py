"""Blender side of Holo: scene export, operators, panel and compositing (work in progress).

For now it registers nothing; the extension is built in its own issue.
"""


def register():
    pass


def unregister():
    pass
