"""A rendered view's files: a multilayer EXR as Blender reads it, and a PNG preview."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..validate import InputError
from ..view import RenderResult
from .image import read_exr, srgb, write_exr


def write_view(result: RenderResult, path, *, layer="ViewLayer") -> tuple[Path, Path]:
    """Write a rendered view as a multilayer EXR and a PNG preview beside it, as one unit.

    Parameters
    ----------
    result : RenderResult
        The view.
    path : str or Path
        The ``.exr`` file: ``<layer>.Combined.R/G/B/A`` premultiplied float32 and
        ``<layer>.Depth.Z`` [m], as Blender's Image node reads them.
    layer : str
        The view layer's name in the channels.

    Returns
    -------
    (Path, Path)
        The EXR and the PNG; both are renamed into place together, or neither is.

    Raises
    ------
    InputError
        Where the view holds NaN or infinite values, or no pixels, or ``path`` does not end in
        .exr.

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from holo_core import RenderResult, write_view
    >>> view = RenderResult(rgb=np.full((4, 6, 3), 0.5), alpha=np.ones((4, 6)),
    ...                     depth=np.ones((4, 6)))
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     exr, png = write_view(view, os.path.join(folder, "view.exr"))
    ...     print(exr.name, png.suffix)
    view.exr .png
    """
    path = Path(path)
    planes = {"rgb": result.rgb, "alpha": result.alpha, "depth": result.depth}
    for name, a in planes.items():
        if not np.size(a) or not np.isfinite(a).all():
            raise InputError(
                f"{path}: the view's {name} is empty or not finite; nothing is written"
            )
    rgb = result.rgb * result.alpha[..., None]  # premultiplied (emission: dark where clear)
    channels = {f"{layer}.Combined.{c}": rgb[..., i] for i, c in enumerate("RGB")}
    channels[f"{layer}.Combined.A"] = result.alpha
    channels[f"{layer}.Depth.Z"] = result.depth
    write_exr(
        path,
        channels,
        preview=srgb(rgb),  # as the EXR shows over black
        holo=json.dumps(result.info, default=float),
    )
    return path, path.with_suffix(".png")


def copy_view(source, path, **info) -> tuple[Path, Path]:
    """The view file ``source`` and its PNG preview written as ``path`` (as one unit, as
    :func:`write_view` writes them), its pixels as they are, the ``info`` of its header
    updated with ``info``: a static shot's pass, the same for each of its frames."""
    source, path = Path(source), Path(path)
    header, channels = read_exr(source, what="view")
    stored = header.get("holo") or "{}"
    try:
        meta = json.loads(stored.decode() if isinstance(stored, bytes) else stored)
    except ValueError:
        raise InputError(f"{source}: damaged view metadata") from None
    write_exr(
        path,
        channels,
        preview=source.with_suffix(".png").read_bytes(),
        holo=json.dumps({**meta, **info}, default=float),
    )
    return path, path.with_suffix(".png")
