"""The add-on's runtime state in one object, :data:`session`: what a render is doing with its
holographic pass, what it warned of, the planner's lines, the device listing and the viewport
preview. Handlers and operators change it through its methods; panels read it. Nothing of it
is saved with the .blend (a file loaded starts a new render's life: :meth:`Session.new_file`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field


@dataclass
class Running:
    """The pass a render is making, in the render's thread: its frame, progress (0 … 1), and
    whether *Cancel Pass* asked it to stop."""

    frame: int | None = None
    fraction: float = 0.0
    cancel: bool = False


@dataclass
class Session:
    """Runtime state of the add-on (module docstring).

    running : the pass a render is making (:class:`Running`)
    warnings : the latest rendered frame and the pass warnings it gave, as they arose
    warned : what the current render has warned of once (an animation included)
    started : when the current render frame began [s, ``time.time()``]: the holographic
        layers written since are this frame's
    made : (scene name, frame) of the pass an operator has just made for the render it
        starts (*Render with Hologram*): that render composites it as it is
    frame_done : (scene name, frame) whose pass the render has seen to (Blender evaluates a
        frame's own time again after its motion-blur steps)
    shutter : the frame whose pass waits for the render to evaluate its shutter
        (:class:`holo_addon.export.motion.Shutter`), or None
    plans : the planner's lines per plate object
    devices : the device listing of *Check Devices*
    exit_on_failure : None: a failed pass ends a background Blender with status 1 (as farms
        need); True or False decide it (tests keep their process)
    shown : the status bar's text as it was last set
    preview : what the viewport's preview shows and makes (:class:`holo_addon.ui.preview.Preview`)
    live : the plate's live view in the viewport (:class:`holo_addon.ui.live.Live`)
    """

    running: Running = field(default_factory=Running)
    warnings: dict = field(default_factory=lambda: {"frame": None, "texts": []})
    warned: set = field(default_factory=set)
    started: float = 0.0
    made: tuple | None = None
    frame_done: tuple | None = None
    shutter: object | None = None
    plans: dict = field(default_factory=dict)
    devices: list = field(default_factory=list)
    exit_on_failure: bool | None = None
    shown: str | None = None
    preview: object | None = None
    live: object | None = None

    # -- a render ------------------------------------------------------------------------
    def render_started(self) -> None:
        self.warned, self.started = set(), time.time()

    def frame_started(self, frame: int) -> None:
        self.started = time.time()
        self.warnings = {"frame": frame, "texts": []}

    def warn_once(self, key: str) -> bool:
        """Whether ``key`` is new to this render (and now known)."""
        new = key not in self.warned
        self.warned.add(key)
        return new

    def warning(self, text: str) -> None:
        self.warnings["texts"].append(text)

    # -- the pass a render makes -----------------------------------------------------------
    def pass_started(self, frame: int) -> None:
        self.running = Running(frame=frame)

    def pass_ended(self) -> None:
        self.running = Running()

    def cancel_pass(self) -> int | None:
        """*Cancel Pass*: the running pass stops at its next progress report."""
        self.running.cancel = self.running.frame is not None
        return self.running.frame

    def made_for_render(self, scene: str, frame: int) -> None:
        self.made = (scene, frame)

    def take_made(self, scene: str, frame: int) -> bool:
        """Whether an operator made this frame's pass for this render (asked once)."""
        made, self.made = self.made, None
        return made == (scene, frame)

    def new_file(self) -> None:
        """A file was loaded: nothing of another file's render is shown."""
        self.warnings = {"frame": None, "texts": []}
        self.made = self.frame_done = self.shutter = None
        self.plans.clear()


session = Session()
