"""A scene recorded onto a plate, for researchers: :func:`record_hologram` records meshes as a
plate of meshes (the zone's, :mod:`.looks`) or as a point sum (:mod:`.points`), and bare
points as a point sum.
"""

from __future__ import annotations

from .. import jobs, validate
from ..scene.hologram import ENCODINGS, Hologram
from ..scene.mesh import Mesh
from ..scene.plate import DEFAULT_ZONE_MARGIN, Plate
from ..validate import InputError
from .looks import record_plate
from .points import record_scene_points

PLATE_METHODS = ("zone", "auto", "direct", "wrp")


@validate.scale_free()
def record_hologram(
    emitters=(),
    *,
    plate: Plate,
    triangles=(),
    camera=None,
    zone=None,
    zone_margin=DEFAULT_ZONE_MARGIN,
    resolution=None,
    max_resolution=2048,
    wavelength=None,
    encoding="complex",
    depth=True,
    seed=0,
    method="zone",
    cull=True,
    code=None,
    budget=(None, None),
    progress: jobs.Progress = None,
) -> Hologram:
    """Record a scene in world metres onto ``plate``, choosing the optics automatically.

    The choice (:mod:`holo_core.plate.sampling`) is logged and stored in the hologram.

    Parameters
    ----------
    emitters : Mesh, sequence of Mesh, or (positions (N, 3) [m], colours (N, 3))
        World-space surfaces, or bare point emitters. Colours are linear RGB intensities.
    plate : Plate
        The plate recorded onto (its pose and size [m], and its zone if it has one).
    triangles : sequence of Mesh
        World-space meshes recorded as textured triangles (their texture, else the mean of
        their corners' colours): with ``method='zone'`` as the other meshes; with a point
        sum, each carried to the plate by tilted-plane propagation.
    camera : holo_core.scene.camera.Camera, optional
        With ``method='zone'``: the zone's reference view where the zone does not give one
        (:func:`~holo_core.plate.looks.record_plate`). With a point sum, it sizes the cone and the wavelength to
        this view (:func:`holo_core.plate.sampling.choose`).
    zone, zone_margin, code, budget
        As for :func:`~holo_core.plate.looks.record_plate` (the budget applies to plates of meshes).
    encoding : {'complex', 'intensity'}
        A point sum's: 'complex' (the object wave, the default) or 'intensity'
        (``|O + R|²``); a plate of meshes is complex
        (:func:`~holo_core.plate.looks.record_plate`).
    resolution, max_resolution : int, optional
        A point sum's samples (:func:`holo_core.plate.sampling.choose`); a plate of meshes
        takes what its zone asks (:mod:`holo_core.plate.plan`).
    wavelength : float, optional
        λ1 [m] instead of the chosen one.
    depth : bool
        Also record the depth partner λ2 (Sect. VII-C).
    seed : int
        Seeds the emitters' random phases (and the mesh sampling).
    method : {'zone', 'auto', 'direct', 'wrp'}
        'zone' (the default for meshes): the plate as a scene asset, independent of any
        camera, with occlusion, its samples against the carrier converging on its zone
        (:func:`~holo_core.plate.looks.record_plate`). Bare points and the others: the point sums of
        :func:`holo_core.plate.point_sources.point_wave`, without occlusion.
    cull : bool
        For a point sum with a camera, keep only the points and triangles it sees
        (:func:`holo_core.scene.mesh.visible_from`): a hologram shows surfaces hidden from its
        recording viewpoint through the ones in front, as light does not occlude itself.
    progress : callable, optional
        Given the fraction done in [0, 1] between units of work.

    Returns
    -------
    Hologram
        The plate's hologram: complex (the object wave, against the zone's carrier for
        ``method='zone'``) or intensity, one channel per colour (and the depth partner's),
        with its optics and pose.

    Raises
    ------
    InputError
        Where the scene, the plate or a setting is out of range, or the recording would exceed
        ``budget``, naming what.

    Notes
    -----
    The object wave O is the sum of the emitters' spherical waves (Eq. 3) on the plate; an
    intensity hologram is H = ``|O + R|²`` (Eq. 16), sampled finely enough for its reference
    angle (Eq. 19).

    Examples
    --------
    A triangle 1 cm behind a 3 cm plate, for a camera 30 cm in front:

    >>> import numpy as np
    >>> from holo_core import Camera, Mesh, Plate, look_at, record_hologram
    >>> camera = Camera(matrix_world=look_at((0, 0, 0.3), (0, 0, -0.01), up=(0, 1, 0)),
    ...                 resolution=(32, 24), fstop=8.0, focus_distance=0.31)
    >>> triangle = Mesh(vertices=np.array([[-0.01, -0.01, -0.01], [0.01, -0.01, -0.01],
    ...                                    [0.0, 0.01, -0.01]]),
    ...                 triangles=np.array([[0, 1, 2]]), colours=np.ones((3, 3)))
    >>> plate = Plate(matrix_world=np.eye(4), width=0.03, height=0.03)
    >>> h = record_hologram([triangle], plate=plate, camera=camera)
    >>> len(h.wavelengths), h.carrier is not None
    (4, True)
    """
    seed = validate.seed(seed)
    if not isinstance(plate, Plate):
        raise InputError(f"plate must be a Plate; got {type(plate).__name__}")
    validate.choice("method", method, PLATE_METHODS)
    validate.choice("encoding", encoding, ENCODINGS)
    meshes = [emitters] if isinstance(emitters, Mesh) else None
    if meshes is None and all(isinstance(e, Mesh) for e in emitters):
        meshes = list(emitters)
    triangles = list(triangles)
    if method == "zone" and meshes is not None:
        if resolution is not None:
            raise InputError(
                "resolution applies to point sums; a plate of meshes takes the "
                "samples its zone asks (holo_core.plate.plan): give a wavelength "
                "to change them"
            )
        return record_plate(
            meshes + triangles,
            plate=plate,
            camera=camera,
            zone=zone,
            zone_margin=zone_margin,
            wavelength=wavelength,
            encoding=encoding,
            depth=depth,
            seed=seed,
            code=code,
            budget=budget,
            progress=progress,
        )
    if code is not None:
        raise InputError(
            "code applies to plates of meshes (method 'zone'); bare points and "
            "point sums take independent seeds"
        )
    if method == "zone":
        method = "auto"  # bare points: no surface to be hidden by
    return record_scene_points(
        emitters,
        meshes,
        triangles,
        plate=plate,
        camera=camera,
        zone=zone,
        zone_margin=zone_margin,
        resolution=resolution,
        max_resolution=max_resolution,
        wavelength=wavelength,
        encoding=encoding,
        depth=depth,
        seed=seed,
        method=method,
        cull=cull,
        progress=progress,
    )
