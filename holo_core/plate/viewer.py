"""A recorded plate held for views as a camera moves: :class:`PlateViewer` holds a plate (its
coded looks, a plate set, or their files) and the plans of its views, says whether a camera's
pupil lies inside the zone the plate serves (:meth:`PlateViewer.where`), and returns views,
full (:func:`~holo_core.plate.view.render_view`'s picture) or coarse (one look, no
supersampling, fewer pixels upsampled: a preview while the camera moves).

What does not change while the camera moves is planned once and reused: the device buffers,
the FFT plans and the pupil's designs, at sizes rounded up with slack so that nearby cameras
reuse them (:class:`~holo_core.plate.view_plans.ViewPlans`). Files are named by their
identity (path, size, modification time, inode) and read again when it changes.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..io.kept_plates import KeptPlates
from ..io.plate_paths import file_identity
from ..io.plate_set import MANIFEST
from ..scene.camera import Camera
from ..scene.hologram import Hologram
from ..scene.plate_set import PlateSet
from ..validate import InputError
from ..view import RenderResult
from .coarse_view import coarser, upsampled
from .inside_zone import INSIDE, beyond_words, zone_sentence
from .path import part_for
from .view_plans import ViewPlans

# render_view's settings a viewer keeps for every view
RENDER_OPTIONS = (
    "aperture",
    "apodize",
    "chromatic",
    "composition",
    "supersample",
    "exposure",
    "opacity_threshold",
    "source",
    "depth_estimate",
)
COARSE_PIXELS = 320 * 180  # a coarse view's pixels at most, upsampled to the camera's


class OutsideZoneError(InputError):
    """A view asked of a camera whose pupil lies outside every zone the plate serves (the
    message says how far, which way, and what to do); never a cut-off picture."""


class PlateViewer:
    """A recorded plate (or plate set) held with the plans of its views, for views of a
    moving camera.

    Parameters
    ----------
    plate : Hologram, sequence of Hologram, PlateSet, path or sequence of paths
        The plate's coded looks (one Hologram a look, all of one recording), a plate set
        (:func:`holo_core.record_set`), the plate files of its looks (``.exr``, or the tiled
        store beside one), or a plate set's folder (its ``plate_set.json``). Files are read
        as the worker reads them (``holo_core.io.kept_plates.KeptPlates``) and read again when
        their identity (path, size, modification time, inode) changes.
    scene : str, optional
        The recording digest the plate must be (the scene's): a plate of another recording,
        or of none, is refused naming its file.
    **render_options
        :func:`holo_core.render_view`'s settings, kept for every view: ``composition``,
        ``supersample``, ``exposure``, ``opacity_threshold``, ``aperture``, ``apodize``,
        ``chromatic``, ``source``, ``depth_estimate``.

    Raises
    ------
    InputError
        Where ``plate`` is none of the above, a setting is unknown, the looks are not of one
        recording, or the plate is not ``scene``'s (``HologramFileError``, an InputError,
        naming the file for files).

    Notes
    -----
    ``recording`` is the digest of the recording the plate is ('' where its looks name none).
    ``where(camera)`` is None where the camera's pupil (its aperture, ``lens / fstop`` [m];
    a point for a pinhole) lies inside a zone the plate serves, else a sentence saying how far
    [m] beyond the nearest zone it reaches, which way along the plate's axes, and the zone;
    ``contains(camera)`` is ``where(camera) is None``.

    ``view(camera)`` is the full view: the picture :func:`holo_core.render_view` gives of the
    same looks with the same settings (a plate set's from the part whose zone holds the
    pupil), planned once for the moving camera: the sizes of the pupil's spectrum and of the
    decimation's filters rounded up with slack, so that nearby cameras reuse the transforms'
    plans and the kernels' builds, and the pupil's plans kept for the last cameras.
    ``view(camera, coarse=True)`` is a preview: the first look alone, one sample a pixel, at
    most 320×180 pixels, upsampled bilinearly to the camera's resolution
    (``info['coarse']`` is True). A camera outside every zone gets no view: ``view`` raises
    ``OutsideZoneError`` (an InputError) with the sentence of ``where``, never a cut-off
    picture. A file that changed since the last view is read again; one that vanished, or
    now holds another recording, is named in the error.

    ``close()`` lets go of the plate and its plans; a closed viewer refuses views (a ``with``
    block closes it). ``widget(camera)`` gives a notebook widget (ipywidgets, optional) whose
    sliders move the camera and its focus.

    Examples
    --------
    >>> import numpy as np
    >>> from holo_core import Camera, Mesh, Plate, PlateViewer, look_at, record_hologram
    >>> camera = Camera(matrix_world=look_at((0, 0, 0.3), (0, 0, -0.01), up=(0, 1, 0)),
    ...                 resolution=(32, 24), fstop=8.0, focus_distance=0.31)
    >>> triangle = Mesh(vertices=np.array([[-0.01, -0.01, -0.01], [0.01, -0.01, -0.01],
    ...                                    [0.0, 0.01, -0.01]]),
    ...                 triangles=np.array([[0, 1, 2]]), colours=np.ones((3, 3)))
    >>> plate = Plate(matrix_world=np.eye(4), width=0.03, height=0.03)
    >>> h = record_hologram([triangle], plate=plate, camera=camera)
    >>> with PlateViewer(h, supersample=1) as viewer:
    ...     inside = viewer.contains(camera)
    ...     view = viewer.view(camera)
    >>> inside, view.rgb.shape
    (True, (24, 32, 3))
    """

    def __init__(self, plate, *, scene: str | None = None, **render_options):
        unknown = sorted(set(render_options) - set(RENDER_OPTIONS))
        if unknown:
            raise InputError(
                f"PlateViewer has no setting {', '.join(map(repr, unknown))}; "
                f"render settings are {', '.join(RENDER_OPTIONS)}"
            )
        if scene is not None and not isinstance(scene, str):
            raise InputError(
                f"scene must be a recording digest (text) or None; got {type(scene).__name__}"
            )
        self.scene = scene
        self.options = dict(render_options)
        self._source = _source_of(plate, scene)
        self._plans = ViewPlans()
        self._closed = False
        self._source.current()  # read now: a missing or foreign file is said at once

    # -- the plate ---------------------------------------------------------------------------
    @property
    def recording(self) -> str:
        """The digest (hex) of the recording the plate is ('' where its looks name none)."""
        return self._source.current().recording

    def where(self, camera: Camera) -> str | None:
        """Why ``camera``'s pupil lies outside every zone the plate serves, or None where it
        lies inside one.

        Parameters
        ----------
        camera : Camera
            The camera; its pupil is its aperture (``lens / fstop``), a point for a pinhole.

        Returns
        -------
        str or None
            A sentence: how far [m] the pupil reaches beyond the nearest zone, which way
            (along the plate's axes), and the zone; None inside.

        Examples
        --------
        See :class:`PlateViewer`.
        """
        self._check_open()
        if not isinstance(camera, Camera):
            raise InputError(f"camera must be a Camera; got {type(camera).__name__}")
        return self._source.current().where(camera)

    def contains(self, camera: Camera) -> bool:
        """Whether ``camera``'s pupil lies inside a zone the plate serves
        (:meth:`where` is None)."""
        return self.where(camera) is None

    # -- views -------------------------------------------------------------------------------
    def view(self, camera: Camera, *, coarse: bool = False) -> RenderResult:
        """``camera``'s view of the plate.

        Parameters
        ----------
        camera : Camera
            Its pose, lens (``fstop``, ``focus_distance`` [m]) and resolution [px]; its pupil
            must lie inside a zone the plate serves (:meth:`where`).
        coarse : bool
            A quick preview: the first look alone, one sample a pixel, at most
            ``COARSE_PIXELS`` pixels upsampled (bilinear) to the camera's resolution; its
            ``info['coarse']`` is True. Else the full view: the picture
            :func:`holo_core.render_view` gives of the same looks with the same settings.

        Returns
        -------
        RenderResult
            Radiance, alpha, planar depth [m] at ``camera.resolution``.

        Raises
        ------
        OutsideZoneError
            (an :class:`InputError`) Where the pupil lies outside every zone (the sentence of
            :meth:`where`).
        InputError
            Where a setting is out of range, or a file changed into another recording's or
            vanished (naming it).
        """
        self._check_open()
        if not isinstance(camera, Camera):
            raise InputError(f"camera must be a Camera; got {type(camera).__name__}")
        held = self._source.current()
        why = held.where(camera)
        if why is not None:
            raise OutsideZoneError(f"{why}: no view is made from there")
        looks = held.looks_for(camera)
        if not coarse:
            return self._plans.render(looks, camera, **self.options)
        return self._coarse(looks, camera)

    def _coarse(self, looks, camera: Camera) -> RenderResult:
        w, h = camera.resolution
        factor = max(1, math.ceil(math.sqrt(w * h / COARSE_PIXELS)))
        small = coarser(camera, factor)
        options = {**self.options, "supersample": 1}
        if options.get("composition") == "max" or options.get("depth_estimate") == "brightest":
            options.pop("composition", None)  # one look: mean and max are the same
            options.pop("depth_estimate", None)
        view = self._plans.render(looks[:1], small, **options)
        rgb, alpha = (upsampled(a, factor, (h, w)) for a in (view.rgb, view.alpha))
        # depth by the pixel that holds it: a surface's beside the background's is no mean
        rows, cols = (
            np.minimum(np.arange(n) // factor, m - 1) for n, m in zip((h, w), view.depth.shape)
        )
        depth = view.depth[np.ix_(rows, cols)]
        return RenderResult(
            rgb=rgb,
            alpha=alpha,
            depth=depth,
            info={**view.info, "coarse": True, "coarse_factor": factor},
        )

    # -- the end -----------------------------------------------------------------------------
    def close(self) -> None:
        """Let go of the plate and its plans (device buffers, transforms); a closed viewer
        refuses views."""
        self._plans.clear()
        self._source.clear()
        self._closed = True

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _check_open(self):
        if self._closed:
            raise InputError("the PlateViewer is closed: make a new one for more views")

    def widget(self, camera: Camera, *, coarse: bool = True):
        """A notebook widget: sliders move ``camera`` (its position [m] across, up and along
        the view, its aim [°]) and its focus [m]; the view is drawn on each change.

        Parameters
        ----------
        camera : Camera
            The camera the sliders start from (inside the zone).
        coarse : bool
            Draw coarse views while a slider moves (:meth:`view`); the widget's button draws
            the full view (and so does every move with ``coarse=False``).

        Returns
        -------
        ipywidgets.VBox
            The sliders and the picture.

        Raises
        ------
        InputError
            Where ipywidgets is not installed (``pip install ipywidgets``).
        """
        from .viewer_widget import widget

        return widget(self, camera, coarse=coarse)


class _Looks:
    """One plate's looks, held: the zone check and the looks a camera is viewed from."""

    def __init__(self, holos, name: str):
        self.holos, self.name = list(holos), name
        first = self.holos[0]
        self.recording = first.recording
        for i, h in enumerate(self.holos[1:], 1):
            if h.recording != first.recording:
                raise InputError(
                    f"{name}: look {i} is of recording {h.recording or '(none)'}, "
                    f"look 0 of {first.recording or '(none)'}: a plate's looks "
                    f"are of one recording"
                )

    def where(self, camera: Camera) -> str | None:
        return zone_sentence(self.holos[0], camera)

    def looks_for(self, camera: Camera):
        return self.holos


class _Set:
    """A plate set, held: the part whose zone holds a pupil, and its looks."""

    def __init__(self, plates: PlateSet, name: str):
        self.plates, self.name, self.recording = plates, name, plates.recording

    def where(self, camera: Camera) -> str | None:
        k, beyond = part_for(self.plates, camera)
        if beyond <= INSIDE:
            return None
        part = self.plates.parts[k]
        local = part.plate.to_plate(np.asarray(camera.position, np.float64)[None])[0]
        return (
            f"the camera's pupil lies outside every part of the plate set; "
            f"{beyond_words(part.plate.zone, local, camera.aperture_diameter or 0.0)} of "
            f"the nearest, part {k} ({part.plate.zone.describe()})"
        )

    def looks_for(self, camera: Camera):
        k, _ = part_for(self.plates, camera)
        return list(self.plates.part_looks(k))


class _Held:
    """A plate given in memory: always current."""

    def __init__(self, held):
        self.held = held

    def current(self):
        if self.held is None:
            raise InputError("the PlateViewer is closed: make a new one for more views")
        return self.held

    def clear(self):
        self.held = None


class _Files:
    """A plate's files (its looks, or a set's folder): read again whenever a file's identity
    changes, refused by name where it vanished or holds another recording."""

    def __init__(self, paths, scene: str | None, folder: bool):
        self.paths, self.scene, self.folder = paths, scene, folder
        self._kept = KeptPlates()
        self._held, self._names = None, None

    def _identities(self):
        listed = [self.paths / MANIFEST] if self.folder else self.paths
        return [file_identity(p) for p in listed]

    def current(self):
        names = self._identities()
        if self._held is not None and names == self._names and None not in names:
            return self._held
        from ..io.hologram import HologramFileError

        if self.folder:
            plates = self._kept.read_set(self.paths)
            if self.scene is not None and plates.recording != self.scene:
                raise HologramFileError(
                    f"{self.paths}: holds the plate set of recording "
                    f"{plates.recording or '(none)'}, not {self.scene} (this scene's): another "
                    f"recording's set is never viewed; record the set again"
                )
            held = _Set(plates, str(self.paths))
        else:
            holos = self._kept.read(self.paths, self.scene or "")
            self._kept.hold(self.paths, holos)
            held = _Looks(holos, ", ".join(map(str, self.paths)))
        self._held, self._names = held, names
        return held

    def clear(self):
        self._kept.clear()
        self._held = self._names = None


def _source_of(plate, scene: str | None):
    """The held plate behind a viewer: in memory (checked against ``scene`` here) or files."""
    if isinstance(plate, (str, Path)):
        path = Path(plate)
        return _Files(path, scene, True) if path.is_dir() else _Files([path], scene, False)
    if isinstance(plate, PlateSet):
        _check_scene(plate.recording, scene, "the plate set")
        return _Held(_Set(plate, "the plate set"))
    if isinstance(plate, Hologram):
        plate = [plate]
    try:
        items = list(plate)
    except TypeError:
        items = []
    if items and all(isinstance(h, Hologram) for h in items):
        looks = _Looks(items, "the plate")
        _check_scene(looks.recording, scene, "the plate")
        return _Held(looks)
    if items and all(isinstance(p, (str, Path)) for p in items):
        return _Files([Path(p) for p in items], scene, False)
    raise InputError(
        f"plate must be a Hologram, a sequence of Hologram (its looks), a "
        f"PlateSet, or the path(s) of its files; got {type(plate).__name__}"
    )


def _check_scene(recording: str, scene: str | None, name: str) -> None:
    if scene is not None and recording != scene:
        raise InputError(
            f"{name} is of recording {recording or '(none named)'}, not {scene} "
            f"(this scene's): another recording's plate is never viewed; record "
            f"the plate again"
        )
