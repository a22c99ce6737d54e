"""The plate test scene: a textured cube partly hiding a textured sphere behind it, a 10 cm
plate halfway between them and the cameras, and cameras a few centimetres apart, 50 mm at f/2.8.
World = the plate's frame: the plate is z = 0, the objects about 0.3 m behind it, the cameras
0.3 m in front. ``scale`` shrinks the image (160x90 at 0.25 against the full 640x360); ``crop``
renders only the pixels around the objects (each pixel keeps its ray).
"""

import numpy as np

from holo_core.scene.camera import Camera, look_at
from holo_core.scene.mesh import Mesh
from holo_core.scene.plate import Plate

TARGET = np.array([0.0, 0.0, -0.32])
CUBE_CENTRE, CUBE_SIZE = np.array([-0.008, -0.003, -0.30]), 0.036
SPHERE_CENTRE, SPHERE_RADIUS = np.array([0.016, 0.008, -0.355]), 0.024
PLATE = Plate(matrix_world=np.eye(4), width=0.1, height=0.1)
EYES = {"left": (-0.02, 0.0, 0.3), "centre": (0.0, 0.0, 0.3), "right": (0.02, 0.0, 0.3)}
SMALL = 0.25  # the cameras at 160x90: a plate for them holds about 640x640 samples


def rotation(ax, ay):
    cx, sx, cy, sy = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    return ry @ rx


def checker(n, a, b):
    """An n×n checker of colours ``a`` and ``b`` (linear RGB), row 0 on top."""
    odd = (np.add.outer(np.arange(n), np.arange(n)) % 2)[..., None]
    return np.where(odd, np.asarray(b, float), np.asarray(a, float))


def cube(centre=CUBE_CENTRE, size=CUBE_SIZE, angles=(0.35, 0.6)):
    """A cube, each face a 4×4 checker of its own two colours (a texture atlas of 6 cells)."""
    faces = [
        ((0, 0, 1), (1, 0, 0)),
        ((0, 0, -1), (-1, 0, 0)),
        ((1, 0, 0), (0, 0, -1)),
        ((-1, 0, 0), (0, 0, 1)),
        ((0, 1, 0), (1, 0, 0)),
        ((0, -1, 0), (1, 0, 0)),
    ]
    colours = [
        ((0.9, 0.2, 0.1), (0.9, 0.8, 0.2)),
        ((0.2, 0.3, 0.9), (0.8, 0.8, 0.8)),
        ((0.1, 0.7, 0.3), (0.9, 0.9, 0.5)),
        ((0.7, 0.2, 0.7), (0.3, 0.9, 0.9)),
        ((0.95, 0.55, 0.1), (0.2, 0.2, 0.6)),
        ((0.5, 0.5, 0.5), (0.9, 0.3, 0.4)),
    ]
    cell = 16
    atlas = np.zeros((cell, 6 * cell, 3))
    verts, uvs, tris = [], [], []
    for f, ((nx, ny, nz), (ux, uy, uz)) in enumerate(faces):
        n, u = np.array([nx, ny, nz], float), np.array([ux, uy, uz], float)
        v = np.cross(n, u)
        atlas[:, f * cell : (f + 1) * cell] = np.repeat(
            np.repeat(checker(4, *colours[f]), 4, 0), 4, 1
        )
        base = len(verts)
        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            verts.append((n + su * u + sv * v) * size / 2)
            uvs.append(((f + (su + 1) / 2 * 0.98 + 0.01) / 6, (sv + 1) / 2 * 0.98 + 0.01))
        tris += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    r = rotation(*angles)
    return Mesh(
        vertices=np.asarray(verts) @ r.T + centre,
        triangles=np.asarray(tris),
        uvs=np.asarray(uvs),
        texture=atlas,
    )


def sphere(centre=SPHERE_CENTRE, radius=SPHERE_RADIUS, n=48):
    """A UV sphere with 8 × 12 checker squares of two colours."""
    th, ph = np.meshgrid(
        np.linspace(0, np.pi, n + 1), np.linspace(0, 2 * np.pi, 2 * n + 1), indexing="ij"
    )
    v = np.stack([np.sin(th) * np.cos(ph), np.cos(th), np.sin(th) * np.sin(ph)], -1)
    uv = np.stack([ph / (2 * np.pi), 1 - th / np.pi], -1)
    idx = np.arange(v.shape[0] * v.shape[1]).reshape(v.shape[:2])
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, :-1], idx[1:, 1:]
    tri = np.concatenate(
        [np.stack([a, c, d], -1).reshape(-1, 3), np.stack([a, d, b], -1).reshape(-1, 3)]
    )
    tex = np.repeat(np.repeat(checker(12, (0.85, 0.85, 0.85), (0.15, 0.45, 0.8))[:8], 8, 0), 8, 1)
    return Mesh(
        vertices=v.reshape(-1, 3) * radius + centre,
        triangles=tri,
        uvs=uv.reshape(-1, 2),
        texture=tex,
    )


def meshes():
    return [cube(), sphere()]


def camera(eye="centre", scale=1.0, fstop=2.8, crop=False):
    """The scene's camera at ``eye`` (a name of EYES or a position [m]), 640x360 × ``scale``,
    50 mm, 36 mm sensor, focused on the cube; with ``crop``, its image cropped to the objects
    and 6 pixels around them."""
    e = np.asarray(EYES.get(eye, eye) if isinstance(eye, str) else eye, float)
    size = (round(640 * scale), round(360 * scale))
    cam = Camera(
        matrix_world=look_at(e, TARGET, up=(0, 1, 0)),
        lens=50,
        sensor_width=36,
        resolution=size,
        fstop=fstop,
        focus_distance=float(np.linalg.norm(CUBE_CENTRE - e)) if fstop else None,
    )
    if not crop:
        return cam
    xy = cam.project(np.concatenate([m.vertices for m in meshes()]))[0]
    (c0, r0), (c1, r1) = np.floor(xy.min(0)) - 6, np.ceil(xy.max(0)) + 6
    return cam.cropped(int(c0), int(r0), int(c1 - c0), int(r1 - r0))
