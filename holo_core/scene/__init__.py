"""The nouns every stage passes around, in world metres and radians.

- ``camera.py``: :class:`Camera`, a camera's pose, lens and pixels (their direction cosines, Eq. 22)
- ``plate.py``: :class:`Plate`, the holographic plate's pose and size, and its
  :class:`ViewingZone`
- ``plate_set.py``: :class:`PlateSet`, a plate's parts along a camera path (:class:`PathPart`)
- ``field.py``: :class:`Field`, sampled complex fields with their wavelength, pitch and pose
- ``hologram.py``: :class:`Hologram`, the recorded holograms of one scene, one per wavelength
- ``mesh.py``: :class:`Mesh`, triangles with colours or a texture, and their point emitters
- ``radiance.py``: a renderer's radiance seen from a camera, projected onto the meshes
"""

from .camera import Camera, look_at
from .field import Field
from .hologram import Hologram
from .mesh import Mesh, sample_points
from .plate import Plate, ViewingZone

__all__ = [
    "Camera",
    "Field",
    "Hologram",
    "Mesh",
    "Plate",
    "ViewingZone",
    "look_at",
    "sample_points",
]
