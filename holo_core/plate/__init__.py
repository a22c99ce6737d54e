"""The plate hologram: a scene asset, recorded once on a plate in the scene for a viewing zone,
viewed by any camera in that zone.

- ``plan.py``: a plate's samples, wavelengths, emitters and costs, from its zone and the views
  it serves (pure arithmetic: no driver)
- ``plan_summary.py``: the plan in plain words, the verdict first
- ``zone_light.py``: the light from the objects to the zone as it crosses the plate: the
  window, its band, the surfaces the zone sees (pure arithmetic: no driver)
- ``quality.py``: the looks and supersampling its views need to reach a quality target,
  predicted from their defocus and the objects' size in pixels (pure arithmetic: no driver)
- ``carrier.py``: the spherical carrier converging on the zone that the samples are stored
  against, and the exact re-modulation to the physical object wave
- ``emitters.py``: the surfaces the zone sees, one emitter per resolved spot, and the zone
  points each is seen from (depth buffers over the zone)
- ``zone_sum.py``: the samples as a sum of the emitters' waves towards the zone (Eq. 3)
- ``recording.py``: a plate of meshes planned once, its emitters and amplitudes prepared for
  the sums
- ``look_codes.py``: each look's emitter phases: coded looks of one seed, or seeds of their own
- ``looks.py``: the looks of a plate of meshes recorded in one pass, in memory or into stores
- ``tiles.py``: plates larger than memory, recorded tile by tile as Dask tasks into a tiled
  store (plates of meshes against their carrier; point sums)
- ``tile_tasks.py``: a tiled recording's tasks, one a tile, as a Dask worker runs them
- ``reference.py``: the plane reference wave and H = |O + R|² (Eq. 4, 16)
- ``sampling.py``: the point sums' pitch, wavelengths and band (Sect. V)
- ``point_sources.py``: the object wave of point emitters on the plate (Eq. 16-18), by the
  cheaper of two sums:
- ``point_sum.py``: every point–pixel pair inside each point's cone, on the device
- ``recording_planes.py``: wavefront recording planes carried to the plate
- ``triangles.py``: the object wave of textured triangles, by spectrum rotation (Sect. IV-C)
- ``points.py``: point sums (complex, or against their reference, Eq. 19) of points and
  textured triangles
- ``record.py``: a scene onto a plate, as a plate of meshes or a point sum (researchers')
- ``reconstruction.py``: R'·H with the DC term suppressed (Sect. VI)
- ``window.py``: the camera in the plate's frame, the part of the plate its pupil sees the
  objects through, the pupil's grid and a pinhole's pupil
- ``to_pupil.py``: the plate's light carried to a camera's entrance pupil (a carrier plate's
  by demodulation, decimation and a non-uniform FFT; a full-band one by the angular spectrum)
- ``gather.py``: a carrier plate's decimated samples summed onto the pupil's plane waves (the
  non-uniform FFT's spread, layer by layer in depth)
- ``pupil_images.py``: each look's images at the pixels, by the camera hologram's own pupil
  stage: the carrier plate's route and the full-band plate's
- ``composition.py``: the looks' images composed into the view: radiance, alpha, depth
- ``view.py``: a camera's image of the plate (Sect. VII), dispatching on its route; a plate
  set's from the part that holds its pupil
- ``path.py``: a plate's parts along a camera path (a long dolly, an orbit), each facing its
  stretch, and the part that holds a pupil (pure arithmetic: no driver)
- ``parts.py``: the parts recorded from one set of emitters
- ``viewer.py``: a plate (or set, or their files) held for the views of a moving camera:
  full, coarse, and whether the pupil lies inside the zone
- ``inside_zone.py``: whether a pupil lies inside the zone, and how far beyond it, in words
- ``coarse_view.py``: a coarse view's camera (larger pixels, the same rays) and its upsampling
- ``view_plans.py``: what a held plate's views share, planned once and reused as the camera
  moves
"""

from ..lazy import lazy_package

# the names below import their modules on first use: the planner (plan.py) is pure arithmetic,
# and Blender's process imports it without the OpenCL driver the recorder and the viewer load
_API = {
    "Reference": ".reference",
    "record_hologram": ".record",
    "record_plate": ".looks",
    "record_looks": ".looks",
    "record_points": ".points",
    "reconstruct": ".reconstruction",
    "render_view": ".view",
    "physical_field": ".carrier",
    "parts_along": ".path",
    "record_set": ".parts",
    "render_set_view": ".view",
    "PlateViewer": ".viewer",
    "find_carrier": "..acquired",
    "sideband": "..acquired",
}  # their home: acquired/
__all__ = sorted(_API)


lazy_package(__name__, _API)
