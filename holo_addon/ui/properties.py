"""Holo settings stored in the .blend: ``Object.holo`` and ``Scene.holo``."""

from __future__ import annotations

import bpy
from bpy.props import (
    BoolProperty,
    BoolVectorProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    IntVectorProperty,
    PointerProperty,
    StringProperty,
)

from holo_core.scene.plate import SHOT_ZONE_MARGIN

from ..blender.objects import raster_visibility
from ..export.display import display_from_object
from ..export.job import EXPOSURE_STOPS
from ..export.scene import ExportError
from . import live, overlay

# 4.5+ ask a path property to declare that it takes "//" (relative to the .blend); 4.2 has no
# such option and takes it anyway
BLEND_RELATIVE = {"PATH_SUPPORTS_BLEND_RELATIVE"} if bpy.app.version >= (4, 5, 0) else set()

EMITTERS = [
    ("NONE", "None", "An ordinary object, rasterized by Blender"),
    ("POINTS", "Points", "Area-uniform point emitters on the surface (spherical waves)"),
    ("TRIANGLES", "Triangles", "Textured planar triangles carried by tilted-plane propagation"),
]


def _emitter_changed(self, context):
    raster_visibility(self.id_data)


def _zone_changed(self, context):
    self.zone_set = False  # set again around the camera, with the new margin, when recorded
    overlay.refresh(context)


def _plate_changed(self, context):
    obj = self.id_data
    raster_visibility(obj)
    if self.is_plate:
        obj.display_type = "WIRE"


def _display_marked(self, context):
    obj = self.id_data
    raster_visibility(obj)
    if self.is_display:
        obj.display_type = "WIRE"
        shape_display(obj)


def _display_changed(self, context):
    obj = self.id_data
    if obj.holo.is_display:
        shape_display(obj)


def shape_display(obj) -> None:
    """The display's plane drawn at its size in the scene: the active area (resolution ×
    pitch) over the Scene Scale, in Blender units, centred on the object's origin."""
    if obj.type != "MESH" or obj.library is not None:
        return
    try:
        spec = display_from_object(obj)
    except ExportError:
        return  # said when the display is exported; the plane keeps its last size
    unit = float(bpy.context.scene.unit_settings.scale_length) or 1.0
    w, h = (v / spec.scale / unit for v in spec.size)
    mesh = obj.data
    if len(mesh.vertices) != 4:
        mesh.clear_geometry()
        mesh.from_pydata([(0, 0, 0)] * 4, [], [(0, 1, 2, 3)])
    for v, (x, y) in zip(mesh.vertices, ((-1, -1), (1, -1), (1, 1), (-1, 1))):
        v.co = (x * w / 2, y * h / 2, 0.0)
    mesh.update()


DISPLAY_PRESETS = [
    (
        "FHD_8",
        "1920 × 1080, 8 µm",
        "A 1080p phase SLM at 8 µm (the splatting and Tensor Holography protocols)",
    ),
    ("FHD_6_4", "1920 × 1080, 6.4 µm", "A 1080p phase SLM at 6.4 µm (Neural Holography's)"),
    ("UHD_3_74", "3840 × 2160, 3.74 µm", "A 4K phase SLM at 3.74 µm"),
    ("UHD_3_6", "3840 × 2160, 3.6 µm", "A 4K phase SLM at 3.6 µm"),
    ("CUSTOM", "Custom", "Resolution, pitch and bit depth given here"),
]


class HoloDisplaySettings(bpy.types.PropertyGroup):
    """A holographic display's settings (``Object.holo.display``); lengths in the unit their
    name gives (µm, nm, mm: as data sheets give them), metres inside."""

    preset: EnumProperty(
        name="Display",
        items=DISPLAY_PRESETS,
        default="FHD_8",
        update=_display_changed,
        description="The phase SLM the patterns are made for",
    )
    resolution: IntVectorProperty(
        name="Resolution",
        size=2,
        default=(256, 256),
        min=16,
        max=16384,
        update=_display_changed,
        description="Samples across and down (Custom)",
    )
    pitch: FloatProperty(
        name="Pitch (µm)",
        default=8.0,
        min=0.5,
        max=100.0,
        update=_display_changed,
        description="The SLM's sample spacing in micrometres (Custom)",
    )
    bit_depth: IntProperty(
        name="Bit Depth",
        default=8,
        min=1,
        max=16,
        description="Phase levels 2^bits the SLM resolves (Custom)",
    )
    pattern_format: EnumProperty(
        name="Pattern File",
        default="PNG8",
        items=[
            ("PNG8", "8-bit Grey PNG", "One grey level a code"),
            ("PNG16", "16-bit Grey PNG", "One 16-bit grey level a code"),
            (
                "PACKED10",
                "10-bit Packed",
                "10 bits in an 8-bit RGB PNG: the 8 high in "
                "red, the 2 low in blue (some SLMs' drivers)",
            ),
        ],
        description="How the SLM's driver takes each pattern",
    )
    phase_range: EnumProperty(
        name="Phase Range",
        default="2PI",
        items=[
            ("2PI", "2π", "The codes span one wave"),
            ("3PI", "3π", "The codes span 1.5 waves (SLMs driven beyond a wave)"),
        ],
        description="The phase the SLM's code range spans",
    )
    inverted: BoolProperty(
        name="Inverted", default=False, description="The SLM's phase falls as its code rises"
    )
    colours: BoolVectorProperty(
        name="Lasers",
        size=3,
        default=(True, True, True),
        description="Red, green and blue lasers: one pattern each, "
        "shown in turn (field-sequential colour)",
    )
    wavelengths: FloatVectorProperty(
        name="Wavelengths (nm)",
        size=3,
        default=(638.0, 520.0, 488.0),
        min=200.0,
        max=2000.0,
        description="The lasers' wavelengths, nanometres",
    )
    powers: FloatVectorProperty(
        name="Powers (mW)",
        size=3,
        default=(10.0, 10.0, 10.0),
        min=0.0,
        soft_max=1000.0,
        description="The lasers' powers, milliwatts (in the layout; "
        "the focal stack's colours are mixed by them)",
    )
    front: FloatProperty(
        name="In Front (mm)",
        default=0.0,
        min=0.0,
        soft_max=50.0,
        description="How far in front of the display (towards the viewer) "
        "the scene may reach, millimetres",
    )
    behind: FloatProperty(
        name="Behind (mm)",
        default=10.0,
        min=0.0,
        soft_max=500.0,
        description="How far behind the display the scene may reach, millimetres",
    )
    scene_scale: FloatProperty(
        name="Scene Scale",
        default=0.01,
        min=1e-6,
        max=1e3,
        precision=5,
        update=_display_changed,
        description="Display metres per scene metre: the scene is "
        "shown scaled by this about the display",
    )
    eye_distance: FloatProperty(
        name="Eye Distance (mm)",
        default=100.0,
        min=1.0,
        soft_max=2000.0,
        description="The eye box's centre from the display, millimetres, along its normal",
    )
    eye_box: FloatProperty(
        name="Eye Box (mm)",
        default=1.0,
        min=0.01,
        soft_max=50.0,
        description="The eye box's width and height, millimetres: where "
        "an eye sees the scene whole",
    )
    pupil: FloatProperty(
        name="Pupil (mm)",
        default=1.0,
        min=0.01,
        soft_max=10.0,
        description="The eye's or camera's pupil in the eye box, millimetres "
        "(the focal stack is seen through it)",
    )
    table_red: StringProperty(
        name="Red Table",
        subtype="FILE_PATH",
        default="",
        options=BLEND_RELATIVE,
        description="The red laser's measured phase per code (a "
        "look-up table file; empty: the display's line)",
    )
    table_green: StringProperty(
        name="Green Table",
        subtype="FILE_PATH",
        default="",
        options=BLEND_RELATIVE,
        description="The green laser's measured phase per code",
    )
    table_blue: StringProperty(
        name="Blue Table",
        subtype="FILE_PATH",
        default="",
        options=BLEND_RELATIVE,
        description="The blue laser's measured phase per code",
    )
    method: EnumProperty(
        name="Encoding",
        default="double-phase",
        items=[
            (
                "double-phase",
                "Double-Phase",
                "Two phases a sample pair, for a 4f filter that keeps half the band",
            ),
            (
                "gradient-descent",
                "Gradient Descent",
                "Adam over the focal stack, from double-phase (Iterations)",
            ),
            (
                "gerchberg-saxton",
                "Gerchberg–Saxton",
                "Projections between the display and the stack's planes (Iterations)",
            ),
        ],
        description="How the complex wave becomes the SLM's phase",
    )
    iterations: IntProperty(
        name="Iterations",
        default=100,
        min=1,
        max=100000,
        description="Steps of the iterative encodings",
    )
    phases: EnumProperty(
        name="Phase",
        default="SMOOTH",
        items=[
            (
                "SMOOTH",
                "Smooth",
                "One phase over the scene's surfaces: the eye's pupil sees a "
                "picture (display holograms are made so)",
            ),
            (
                "RANDOM",
                "Random",
                "A random phase a surface point, as a diffuse surface: "
                "speckle through the eye's pupil",
            ),
        ],
        description="The phase of the scene's light in the recorded wave",
    )
    slices: IntProperty(
        name="Focal Slices",
        default=5,
        min=1,
        max=64,
        description="Slices of the simulated focal stack, over the volume's depth",
    )


class HoloObjectSettings(bpy.types.PropertyGroup):
    emitter: EnumProperty(
        name="Emitter",
        items=EMITTERS,
        default="NONE",
        update=_emitter_changed,
        description="How this mesh is recorded into the hologram",
    )
    is_plate: BoolProperty(
        name="Hologram Plate",
        default=False,
        update=_plate_changed,
        description="This plane is the holographic plate: its local z = 0 "
        "plane, viewed from its +Z side",
    )
    is_display: BoolProperty(
        name="Holographic Display",
        default=False,
        update=_display_marked,
        description="This plane is a holographic display (a phase SLM): "
        "its local z = 0 plane, viewed from its +Z side; "
        "Render Animation writes its patterns per frame",
    )
    display: PointerProperty(type=HoloDisplaySettings)
    hologram: StringProperty(
        name="Hologram",
        default="",
        subtype="FILE_PATH",
        options={"HIDDEN"} | BLEND_RELATIVE,
        description="The plate's hologram file (first iteration), "
        "written by Record Hologram or imported",
    )
    fingerprint: StringProperty(
        name="Fingerprint",
        default="",
        options={"HIDDEN"},
        description="Digest of what the hologram was recorded from",
    )
    imported: BoolProperty(
        name="Imported",
        default=False,
        options={"HIDDEN"},
        description="The hologram was imported (File > Import > Hologram): "
        "it is viewed as it is, never recorded",
    )
    zone_margin: FloatProperty(
        name="Zone Margin",
        default=SHOT_ZONE_MARGIN,
        min=0.0,
        soft_max=1.0,
        subtype="DISTANCE",
        update=_zone_changed,
        description="How far the viewing zone reaches beyond the "
        "camera's pupil: cameras inside it see the plate "
        "sharp and complete, and never record it again. "
        "The recording grows as the zone's width squared: "
        "raise it to look around the shot, at that cost",
    )
    part_length: FloatProperty(
        name="Part Length",
        default=0.1,
        min=0.001,
        soft_max=1.0,
        subtype="DISTANCE",
        description="How much of the camera's path one part of the "
        "plate serves: Fit Zone to Shot makes a set of "
        "parts along a path longer than this (each part's "
        "recording grows as the square of its length, the "
        "set's as the path's length)",
    )
    parts: StringProperty(
        name="Parts",
        default="",
        options={"HIDDEN"},
        description="The plate's parts along the camera's path (Fit Zone to "
        "Shot), each a plate facing its stretch of the path "
        "[m, world] (JSON); empty: one plate",
    )
    zone_set: BoolProperty(
        name="Zone Set",
        default=False,
        options={"HIDDEN"},
        description="The viewing zone below is the plate's (else it is "
        "set around the scene camera when the plate is "
        "recorded)",
    )
    zone_centre: FloatVectorProperty(
        name="Zone Centre",
        size=3,
        options={"HIDDEN"},
        description="The viewing zone's centre [m] in the plate's frame",
    )
    zone_half: FloatVectorProperty(
        name="Zone Half Extents",
        size=3,
        min=0.0,
        options={"HIDDEN"},
        description="The viewing zone's half widths [m] along the plate's axes",
    )
    zone_pupil: FloatProperty(
        name="Zone Pupil",
        default=0.0,
        min=0.0,
        options={"HIDDEN"},
        description="The entrance pupil [m] the zone is made for",
    )
    zone_pixel: FloatProperty(
        name="Zone Pixel",
        default=0.0,
        min=0.0,
        options={"HIDDEN"},
        description="The pixel angle [rad] of the views the zone is made "
        "for: with the pupil, it sets how sharp they are",
    )


def _show_coverage(_settings, context):
    overlay.refresh(context)


def _live_plate(_settings, context):
    live.toggled(context)


class HoloSceneSettings(bpy.types.PropertyGroup):
    mode: EnumProperty(
        name="Hologram",
        default="CAMERA",
        items=[
            (
                "CAMERA",
                "Camera",
                "Record the hologram for the render camera, on a virtual "
                "plate at its lens: sharp at the render's resolution, with "
                "its depth of field (no plate needed)",
            ),
            (
                "PLATE",
                "Plate",
                "Record the plate's hologram once and view it from the "
                "camera, as a holographic display would show it: its "
                "sharpness is limited by the plate's size and resolution",
            ),
        ],
        description="Where the hologram is recorded",
    )
    lighting: EnumProperty(
        name="Lighting",
        default="SCENE",
        items=[
            (
                "SCENE",
                "Scene",
                (
                    "The holographic objects' colours are Cycles' render of "
                    "them from the camera, lit by the scene: direct and "
                    "indirect light, shadows, textures, normal maps, specular "
                    "highlights (Lighting Samples sets its samples)"
                ),
            ),
            (
                "ALBEDO",
                "Albedo",
                (
                    "The holographic objects show their Base Color alone, "
                    "unlit (the colour attribute, texture or bake)"
                ),
            ),
        ],
        description="Where the holographic objects' colours come from",
    )
    lighting_samples: IntProperty(
        name="Lighting Samples",
        default=8,
        min=1,
        max=4096,
        description="Cycles samples of the holographic objects' radiance (Lighting: Scene), "
        "denoised; the scene's other Cycles settings (light paths, clamping) apply",
    )
    speckle: EnumProperty(
        name="Speckle",
        items=[
            (
                "EXACT",
                "Exact",
                (
                    "The random-phase looks' limit in one pass: the emitters as "
                    "mutually incoherent sources, no speckle"
                ),
            ),
            (
                "LOOKS",
                "Looks",
                (
                    "Looks with independent random phases, averaged "
                    "progressively (Samples); a running pass can be kept"
                ),
            ),
        ],
        description="How the camera hologram averages the emitters' random phases",
    )
    samples: IntProperty(
        name="Samples",
        default=16,
        min=1,
        max=4096,
        description="Looks with independent random phases, averaged: more samples, less speckle",
    )
    output_dir: StringProperty(
        name="Output Folder",
        subtype="DIR_PATH",
        default="//holo/",
        options=BLEND_RELATIVE,
        description="Where holograms and the holographic pass of each "
        "frame are written (// is the .blend's folder)",
    )
    plate_memory: FloatProperty(
        name="Memory Budget",
        default=8.0,
        min=0.1,
        soft_max=256.0,
        description="What recording a plate may hold in memory [GiB]: "
        "a plate that needs more is recorded tile by tile "
        "into a store; one whose tile needs more is "
        "refused before any work, with its size (Plan "
        "Plate says it)",
    )
    plate_disk: FloatProperty(
        name="Disk Budget",
        default=100.0,
        min=0.1,
        soft_max=10000.0,
        description="What a plate's files may take on disk [GiB], every "
        "iteration: a plate that needs more is refused "
        "before any work, with its size",
    )
    outside_zone: EnumProperty(
        name="Outside Zone",
        default="CAMERA",
        items=[
            (
                "CAMERA",
                "Camera Hologram",
                (
                    "A frame whose camera reaches beyond the plate's "
                    "viewing zone renders whole as a camera "
                    "hologram of that frame (as Camera mode does); "
                    "its log line says so"
                ),
            ),
            (
                "WARN",
                "Warn",
                (
                    "A frame whose camera reaches beyond the plate's viewing "
                    "zone renders from the plate with a warning: what the plate "
                    "cannot send there is left out, transparent"
                ),
            ),
            (
                "FAIL",
                "Fail",
                (
                    "A frame whose camera reaches beyond the plate's viewing "
                    "zone fails (a background render, a farm's, exits with "
                    "status 1)"
                ),
            ),
        ],
        description="What a render does with a frame the plate was not recorded for",
    )
    wavelength: FloatProperty(
        name="Wavelength",
        default=0.0,
        min=0.0,
        max=1.0,
        precision=6,
        subtype="DISTANCE",
        unit="LENGTH",
        description="Recording wavelength (0: chosen for the image's resolution)",
    )
    iterations: IntProperty(
        name="Iterations",
        default=0,
        min=0,
        max=64,
        description="Looks of the plate, averaged against speckle "
        "(Sect. VII-E); 0: Auto, the looks Plan Plate chooses "
        "for the scene's views to reach 30 dB. 2 or a square "
        "number are coded looks whose neighbouring emitters' "
        "cross terms cancel; others use independent random "
        "phases. Each look adds to the recording and to every "
        "frame's view",
    )
    supersample: IntProperty(
        name="Supersample",
        default=0,
        min=0,
        max=4,
        description="Render at this multiple of the resolution, then "
        "low-pass and downsample; 0: Auto (a plate's views: "
        "what Plan Plate chooses; camera holograms: 2)",
    )
    composition: EnumProperty(
        name="Composition",
        default="mean",
        items=[
            ("mean", "Mean", "Average the iterations' intensities"),
            ("max", "Maximum", "Brightest iteration per pixel"),
        ],
        description="How the recordings combine into the image: the mean "
        "is smoother, the maximum brighter",
    )
    exposure: FloatProperty(
        name="Exposure",
        default=0.0,
        soft_min=-10.0,
        soft_max=10.0,
        min=-EXPOSURE_STOPS,
        max=EXPOSURE_STOPS,
        description="Brightness of the holographic objects [stops], as "
        "Blender's Film Exposure: +1 doubles it",
    )
    opacity_threshold: FloatProperty(
        name="Opacity Threshold",
        default=0.5,
        min=0.0,
        max=1.0,
        description="Alpha is 1 where the holographic surfaces "
        "cover more than this fraction of a pixel "
        "(0.5: at the geometric silhouette)",
    )
    seed: IntProperty(name="Seed", default=0, min=0, description="Random phases and sampling")
    show_coverage: BoolProperty(
        name="Plate Coverage",
        default=True,
        update=_show_coverage,
        description="Draw in the viewport the lines of sight the "
        "plate covers from the camera: green when they "
        "take in every holographic object, orange when "
        "part, red when none",
    )
    preview: BoolProperty(
        name="Viewport Preview",
        default=True,
        description="In camera view, show the holographic objects in the "
        "viewport: the latest pass, and a preview pass at a "
        "quarter of the render's resolution made again when the "
        "scene changes (Camera mode)",
    )
    live_plate: BoolProperty(
        name="Live Plate View",
        default=False,
        update=_live_plate,
        description="In Plate mode, a 3D view in Rendered shading shows "
        "the recorded plate's view from the view's own camera "
        "as you orbit, pan, zoom and refocus: a coarse picture "
        "while it moves, the full one once it stops",
    )
    live_pixels: IntProperty(
        name="Live Resolution",
        default=640,
        min=64,
        max=4096,
        subtype="PIXEL",
        description="The live view's picture, its larger side [px] (the "
        "view's aspect): fewer pixels come sooner",
    )
    pass_on_render: BoolProperty(
        name="Pass on Every Render",
        default=True,
        description="Render the holographic pass before each Blender "
        "render or animation frame (recording again only "
        "when the scene changed)",
    )


CLASSES = (HoloDisplaySettings, HoloObjectSettings, HoloSceneSettings)


_register_classes, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def register():
    _register_classes()
    bpy.types.Object.holo = PointerProperty(type=HoloObjectSettings)
    bpy.types.Scene.holo = PointerProperty(type=HoloSceneSettings)


def unregister():
    del bpy.types.Scene.holo
    del bpy.types.Object.holo
    _unregister_classes()
