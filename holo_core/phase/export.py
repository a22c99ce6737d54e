"""One frame for a field-sequential phase display: each laser's wave encoded, the patterns and
their layouts written as one atomic set, and what the display will show simulated, compared
and written as a focal stack (EXR and a PNG contact sheet).

The scene is checked (:func:`holo_core.phase.slm.check_scene`) before any work. Files, for a
``stem`` (e.g. ``frame_0001``) in ``folder``:

- ``<stem>_<nm>nm.png`` and ``.json``: each laser's pattern as its driver shows it
  (:mod:`holo_core.io.slm`), all written together or none;
- ``<stem>_stack.exr`` and ``.png``: the simulated focal stack's intensities beside the
  complex wave's (channels ``z00.R`` …, ``ref.z00.R`` …; one channel ``Y`` a slice with one
  laser, R, G, B by falling wavelength with three), and its contact sheet, each slice
  labelled with its depth and PSNR.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .. import validate
from ..io import slm as slm_io
from ..validate import InputError
from . import levels
from .encode import encode
from .slm import SLMSetup, check_scene
from .stack import Optics, compare, fitted

log = logging.getLogger(__name__)


class Frame(NamedTuple):
    """patterns: the :class:`~holo_core.phase.encode.Pattern` per laser; comparisons: the
    :class:`~holo_core.phase.stack.Comparison` per laser (empty without simulation); files:
    every path written; seconds: wall time [s] of the encoding alone, all lasers."""

    patterns: list
    comparisons: list
    files: list
    seconds: float


def laser_name(wavelength: float) -> str:
    """A laser's tag in file names: its wavelength in nm, '638nm' (a tenth where needed)."""
    nm = wavelength * 1e9
    return f"{nm:.0f}nm" if abs(nm - round(nm)) < 0.05 else f"{nm:.1f}nm"


def export_frame(
    fields,
    setup: SLMSetup,
    folder,
    *,
    stem="frame",
    distance=0.0,
    method="double-phase",
    simulate=True,
    pupil=None,
    eye=None,
    frame=None,
    extent=None,
    stack_compression="zip",
    **settings,
) -> Frame:
    """Encode, write and (``simulate``) judge one frame.

    Parameters
    ----------
    fields : sequence of (rows, cols) complex arrays
        The wave at the display for each of ``setup.lasers``, in their order.
    setup : SLMSetup
    folder : path-like
        Where the files go (it must exist).
    stem : str
        The files' common name.
    distance : float
        The scene's signed distance from the display [m], written into the layouts.
    method : str
        The encoding (:data:`holo_core.phase.encode.METHODS`).
    simulate : bool
        Reconstruct the focal stack from the quantised patterns and compare it with the
        complex wave's.
    pupil : (x, y, diameter), optional
        A pupil in the eye box as a Fourier plane [m] (a near-eye display's eyepiece,
        :class:`~holo_core.phase.stack.Optics` ``pupil``) for the simulation and the fit;
        default the whole band.
    eye : EyePupil, optional
        An eye looking straight at the display for the simulation (each slice as it sees
        it focused there, :meth:`~holo_core.phase.stack.Optics.seen`); the iterative
        encodings still fit the planes' own amplitudes.
    frame : int, optional
        The animation's frame, written into the layouts.
    extent : (x, y), optional
        The scene's half-size [m] for :func:`~holo_core.phase.slm.check_scene`.
    stack_compression : {'zip', 'none'}
        The stack's EXR compression (:func:`holo_core.io.slm.write_stack`).
    **settings
        For :func:`~holo_core.phase.encode.encode` (iterations, learning_rate, ...).

    Examples
    --------
    >>> import tempfile
    >>> import numpy as np
    >>> from holo_core.phase import Display, Laser, SLMSetup, export_frame
    >>> setup = SLMSetup(display=Display(name="lab", resolution=(64, 48), pitch=8e-6),
    ...                  lasers=[Laser(wavelength=520e-9)], depth_range=(-2e-3, 0.0), slices=2)
    >>> y, x = np.mgrid[:48, :64]
    >>> wave = np.exp(-((x - 32) ** 2 + (y - 24) ** 2) / 200.0).astype(complex)
    >>> frame = export_frame([wave], setup, tempfile.mkdtemp(), stem="frame_0001")
    >>> sorted(p.name for p in frame.files)
    ['frame_0001_520nm.json', 'frame_0001_520nm.png', 'frame_0001_stack.exr', 'frame_0001_stack.png']
    """
    if not isinstance(setup, SLMSetup):
        raise InputError(f"setup must be an SLMSetup; got {type(setup).__name__}")
    fields = list(fields)
    if len(fields) != len(setup.lasers):
        raise InputError(
            f"fields must hold one wave per laser ({len(setup.lasers)}); got {len(fields)}"
        )
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"folder {folder}: no such folder")
    if not isinstance(stem, str) or not stem or Path(stem).name != stem:
        raise InputError(f"stem must be a plain file name; got {stem!r}"[:200])
    for note in check_scene(setup, extent=extent):
        log.warning("display: %s", note)
    eye = setup.eye_box
    pupil_at = None
    if pupil is not None:
        if eye is None:
            raise InputError("pupil: a pupil sits in the eye box; the setup has none")
        x, y, diameter = validate.vector("pupil", pupil, 3, "m")
        pupil_at = (x, y, diameter, eye.distance)
    display = setup.display
    patterns, optics_list, refs, seconds = [], [], [], 0.0
    for laser, field in zip(setup.lasers, fields):
        optics = Optics(
            display.shape,
            pitch=display.pitch,
            wavelength=laser.wavelength,
            distances=setup.distances(),
            band=setup.band,
            pupil=pupil_at,
            eye=eye,
        )
        targets = optics.stack(field) if method != "double-phase" else None
        ref = (
            (targets if eye is None and targets is not None else optics.seen(field))
            if simulate
            else None
        )
        p = encode(
            field,
            setup,
            wavelength=laser.wavelength,
            method=method,
            optics=optics,
            targets=targets,
            **settings,
        )
        seconds += p.seconds
        patterns.append(p)
        optics_list.append(optics)
        refs.append(ref)
    extra = {
        "frame": frame,
        "band": setup.band,
        "slices": setup.slices,
        "depth_range": list(setup.depth_range),
        "eye_box": None
        if eye is None
        else {
            "size": list(eye.size),
            "distance": eye.distance,
            "pupil": eye.pupil,
            "centre": list(eye.centre),
        },
    }
    items = []
    for laser, p in zip(setup.lasers, patterns):
        table = setup.table_for(laser.wavelength)
        items.append(
            (
                folder / f"{stem}_{laser_name(laser.wavelength)}.png",
                p.codes,
                dict(
                    response=levels.response(display, table),
                    display=display.name,
                    pitch=display.pitch,
                    bit_depth=display.bit_depth,
                    phase_range=display.phase_range,
                    inverted=display.inverted,
                    wavelength=laser.wavelength,
                    power=laser.power,
                    distance=distance,
                    encoding=method,
                    table=p.table,
                    extra=extra,
                ),
            )
        )
    files = [f for pair in slm_io.write_patterns(items) for f in pair]
    comparisons = []
    if simulate:
        shown, wanted = [], []
        for p, optics, ref in zip(patterns, optics_list, refs):
            s = optics.seen(np.exp(1j * p.phase))
            c = compare(s, ref)
            comparisons.append(c)
            shown.append(fitted(s, ref)[0] ** 2)
            wanted.append(np.asarray(ref, np.float64) ** 2)
            log.info(
                "display: %s %s: focal stack %.2f dB PSNR, SSIM %.3f (mean of %d slices)",
                stem,
                laser_name(p.wavelength),
                c.mean_psnr_db,
                c.mean_ssim,
                len(c.psnr_db),
            )
        order = np.argsort([-x.wavelength for x in setup.lasers])  # R, G, B
        if len(shown) == 3:
            sim = np.stack([shown[i] for i in order], axis=-1)
            ref_stack = np.stack([wanted[i] for i in order], axis=-1)
        else:
            sim, ref_stack = shown[0], wanted[0]
        psnrs = np.mean([c.psnr_db for c in comparisons], axis=0)
        labels = [f"{z * 1e3:+.2f} mm {q:.1f} dB" for z, q in zip(setup.distances(), psnrs)]
        metrics = {
            laser_name(x.wavelength): {"psnr_db": c.psnr_db, "ssim": c.ssim}
            for x, c in zip(setup.lasers, comparisons)
        }
        files += slm_io.write_stack(
            folder / f"{stem}_stack.exr",
            sim,
            reference=ref_stack,
            distances=setup.distances(),
            metrics=metrics,
            labels=labels,
            compression=stack_compression,
        )
    return Frame(patterns, comparisons, files, seconds)
