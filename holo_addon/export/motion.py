"""The holographic objects across the shutter (motion blur, Camera mode): where each
emitter's triangles are at the times Blender evaluates for its own motion blur, as the camera
at the frame's own time sees them (a moving camera blurs them too), for
:attr:`holo_core.scene.mesh.Mesh.motion`.

A render evaluates the shutter's opening and closing itself (its frame handlers see those
sub-frames: :class:`Shutter` collects them); an operator outside a render evaluates them with
:func:`evaluate_shutter`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from holo_core.job import Job

from .scene import camera_matrix, corner_positions, emitter_instances, scale

TOLERANCE = 1e-4  # frames: a sub-frame is the shutter's opening or closing within this


@dataclass(frozen=True)
class Sample:
    """The emitters at one time: ``time`` [frames], the camera's world matrix [m] and each
    emitter's (kind, triangle corners (3T, 3) [m]) in the export's order."""

    time: float
    camera: np.ndarray
    corners: tuple


def shutter(scene) -> tuple[float, float]:
    """(opening, closing) [frames] of the current frame's shutter: Blender's Shutter (in
    frames) placed by its Position (start, centre or end on the frame)."""
    r = scene.render
    frame, length = scene.frame_current, r.motion_blur_shutter
    start = {"START": 0.0, "CENTER": -0.5, "END": -1.0}[r.motion_blur_position] * length
    return frame + start, frame + start + length


def blurs(scene) -> bool:
    """Whether the holographic objects are to be motion-blurred: the render's motion blur
    is on, in Camera mode (a plate is recorded once for many frames, unblurred)."""
    return (
        scene.render.use_motion_blur
        and scene.holo.mode == "CAMERA"
        and scene.render.motion_blur_shutter > 0
    )


def sample(scene, depsgraph) -> Sample:
    """The emitters and the camera where ``depsgraph`` evaluates them now."""
    unit = scale(scene)
    corners = []
    for inst, kind in emitter_instances(depsgraph):
        try:
            corners.append(
                (kind, corner_positions(inst.object, depsgraph, unit, np.array(inst.matrix_world)))
            )
        except ValueError:  # left out of the export too (no faces)
            continue
    return Sample(
        time=scene.frame_current + scene.frame_subframe,
        camera=camera_matrix(scene, depsgraph, unit),
        corners=tuple(corners),
    )


@dataclass
class Shutter:
    """The samples a render's frame has evaluated so far (its handlers see each sub-frame);
    complete once the shutter's opening and closing are in. ``job``: the frame's job, read
    at its own time, that waits for them."""

    frame: int
    opening: float
    closing: float
    job: object = None
    samples: dict = field(default_factory=dict)

    def add(self, s: Sample) -> None:
        self.samples[round(s.time, 6)] = s

    def complete(self) -> bool:
        times = np.array(list(self.samples))
        return all(
            np.abs(times - t).min(initial=1.0) <= TOLERANCE for t in (self.opening, self.closing)
        )


def evaluate_shutter(scene, depsgraph_of) -> list[Sample]:
    """Outside a render: the emitters at the shutter's opening and closing, the scene set to
    those sub-frames and back (``depsgraph_of()``: the evaluated depsgraph after a frame
    change)."""
    frame, subframe = scene.frame_current, scene.frame_subframe
    out = []
    try:
        for t in shutter(scene):
            whole = int(np.floor(t))
            scene.frame_set(whole, subframe=t - whole)
            out.append(replace(sample(scene, depsgraph_of()), time=t))
    finally:
        scene.frame_set(frame, subframe=subframe)
    return out


def with_motion(job: Job, samples, opening: float, closing: float) -> Job:
    """``job`` whose emitters carry their motion across the shutter (``Mesh.motion``): the
    samples' corners in the camera's frame at the frame's own time (a camera that moves
    blurs its view), resampled at equally spaced times from ``opening`` to ``closing``
    [frames] (linearly between Blender's samples, as Cycles interpolates). Emitters whose
    meshes change across the shutter (particles born, topology) stay still."""
    samples = sorted(samples, key=lambda s: s.time)
    times = np.array([s.time for s in samples])
    if len(samples) < 2 or times[-1] - times[0] <= 0:
        return job
    even = np.linspace(opening, closing, max(len(samples), 2))
    at = np.clip(np.searchsorted(times, even, side="right") - 1, 0, len(times) - 2)
    f = np.clip((even - times[at]) / (times[at + 1] - times[at]), 0, 1)[:, None, None]
    now = job.camera.matrix_world
    moved = {"POINTS": [], "TRIANGLES": []}
    for s in samples:
        to_now = now @ np.linalg.inv(s.camera)
        per = {"POINTS": [], "TRIANGLES": []}
        for kind, corners in s.corners:
            per[kind].append(corners @ to_now[:3, :3].T + to_now[:3, 3])
        for kind in moved:
            moved[kind].append(per[kind])

    def moving(meshes, kind):
        steps = moved[kind]
        if any(len(step) != len(meshes) for step in steps):
            return meshes
        out = []
        for i, mesh in enumerate(meshes):
            track = [step[i] for step in steps]
            if any(t.shape != mesh.vertices.shape for t in track):
                out.append(mesh)
                continue
            track = np.stack(track)  # (S, V, 3) at the samples' times
            resampled = (1 - f) * track[at] + f * track[at + 1]
            out.append(
                mesh
                if np.array_equal(resampled.min(0), resampled.max(0))
                else replace(mesh, motion=resampled)
            )
        return tuple(out)

    return replace(
        job, points=moving(job.points, "POINTS"), triangles=moving(job.triangles, "TRIANGLES")
    )
