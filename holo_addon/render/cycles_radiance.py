"""Cycles' radiance of the holographic emitters as the camera sees them: a script that Blender
runs in a process of its own (``blender -b --factory-startup scene.blend --python
cycles_radiance.py -- JSON``, or a Python with the bpy module: ``python cycles_radiance.py --
JSON``), started by the worker (:func:`holo_core.worker.lit_emitters`).

The scene is the user's, written by :func:`holo_addon.export.radiance.write_scene`, at the
frame being rendered, with the scene's own Cycles settings (light paths, clamping, world,
seed) but samples of its own (``samples``), denoised by OpenImageDenoise. Also: the emitters
are seen by the camera and every ray; every other object is hidden from the camera alone, so
it still casts its shadows on the emitters, lights them indirectly and shows in their
reflections, except the instancers of emitters (collection instances, geometry-node and
particle instancers), which Cycles' instances inherit their visibility from: those stay visible
to the camera with their own geometry off; the film is transparent; depth of field and motion blur are off (the hologram
makes its own); the render is cropped to the emitters' region; the compositor and sequencer
are off. The result is a float RGBA OpenEXR (premultiplied).

JSON: ``blend``, ``scene``, ``view_layer``, ``frame``, ``emitters`` (object names),
``border`` (min x, max x, min y, max y as Blender's render region), ``image`` (the output
path), ``samples``, ``compat`` (the path of :mod:`holo_addon.blender.compat`, loaded on its
own), ``view`` (the pose [Blender units] the radiance is seen from) and ``lens`` (None:
the scene camera's lens and the render's frame; else a view of its own, a holographic
display's eye box: ``lens`` and ``sensor_width``, ``sensor_height`` [mm], ``sensor_fit`` and
``resolution`` [px]).
It imports nothing of the add-on's package, which the process does not have.
"""

import importlib.util
import json
import os
import sys

import bpy
from mathutils import Matrix

RAYS = (
    "visible_camera",
    "visible_diffuse",
    "visible_glossy",
    "visible_transmission",
    "visible_volume_scatter",
    "visible_shadow",
)


def instancers_of(depsgraph, emitters: set) -> set:
    """Names of the objects that instance one of ``emitters`` (collection instances,
    geometry-node and particle instancers): Cycles gives an instance its instancer's ray
    visibility, so these must stay visible to the camera for the instances to be seen."""
    return {
        inst.parent.original.name
        for inst in depsgraph.object_instances
        if inst.is_instance
        and inst.parent is not None
        and inst.object.original.name in emitters
        and inst.parent.original.name not in emitters
    }


def view_from(scene, matrix, lens=None) -> None:
    """Render from the pose ``matrix`` (4×4, Blender units) where the scene's camera stands
    elsewhere (a plate's radiance is seen from its zone's centre): a stand-in object with the
    camera's own lens and frame, free of its parents, constraints and animation; with
    ``lens``, with that lens and frame (a display's eye box has no camera of the scene's)."""
    if lens is not None:
        data = bpy.data.cameras.new("Holo radiance lens")
        data.lens, data.sensor_fit = lens["lens"], lens["sensor_fit"]
        data.sensor_width, data.sensor_height = lens["sensor_width"], lens["sensor_height"]
        stand_in = bpy.data.objects.new("Holo radiance view", data)
        scene.collection.objects.link(stand_in)
        stand_in.matrix_world = Matrix(matrix)
        scene.camera = stand_in
        r = scene.render
        r.resolution_x, r.resolution_y = lens["resolution"]
        r.resolution_percentage = 100
        r.pixel_aspect_x = r.pixel_aspect_y = 1.0
        return
    camera = scene.camera
    if camera is None or camera.type != "CAMERA":
        return
    view = Matrix(matrix)
    if all(
        abs(a - b) <= 1e-6 * max(1.0, abs(b))
        for row, want in zip(camera.matrix_world, view)
        for a, b in zip(row, want)
    ):
        return
    stand_in = bpy.data.objects.new("Holo radiance view", camera.data)
    scene.collection.objects.link(stand_in)
    stand_in.matrix_world = view
    scene.camera = stand_in


def main(args: dict) -> None:
    if bpy.data.filepath != args["blend"]:  # the bpy module: the file is opened here
        bpy.ops.wm.open_mainfile(filepath=args["blend"], load_ui=False)
    spec = importlib.util.spec_from_file_location("holo_compat", args["compat"])
    compat = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(compat)
    handlers = bpy.app.handlers
    for kind in (
        "frame_change_pre",
        "frame_change_post",
        "render_init",
        "render_pre",
        "render_post",
        "render_write",
        "render_complete",
        "render_stats",
    ):
        getattr(handlers, kind).clear()  # no add-on makes a pass of this render
    scene = bpy.data.scenes[args["scene"]]
    scene.frame_set(args["frame"])
    emitters = set(args["emitters"])
    instancers = instancers_of(scene.view_layers[args["view_layer"]].depsgraph, emitters)
    for obj in bpy.data.objects:
        if obj.name in emitters:  # an ordinary object here, not the raster's holdout
            for name in RAYS:
                setattr(obj, name, True)
            obj.is_holdout = False
        elif obj.name in instancers:  # Cycles hides an instancer's instances with it
            obj.visible_camera = True
            obj.show_instancer_for_render = False  # its own geometry: not an emitter
        else:
            obj.visible_camera = False
    view_from(scene, args["view"], args.get("lens"))
    r = scene.render
    r.engine = "CYCLES"
    r.film_transparent = True
    r.use_motion_blur = False
    if scene.camera is not None and scene.camera.type == "CAMERA":
        scene.camera.data.dof.use_dof = False
    r.use_border = r.use_crop_to_border = True
    r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = args["border"]
    r.use_compositing = False
    r.use_sequencer = False
    scene.cycles.pixel_filter_type = "BOX"  # the texels are pixels: the hologram blurs them
    scene.cycles.samples = args["samples"]  # few, denoised: the radiance costs little
    scene.cycles.use_denoising = True
    scene.cycles.denoiser = "OPENIMAGEDENOISE"
    scene.cycles.denoising_prefilter = "FAST"
    compat.set_exr_output(scene, multilayer=False)
    r.image_settings.color_mode = "RGBA"
    r.filepath = args["image"]
    r.use_file_extension = False

    def stats(text):
        if "Sample " in text:
            try:
                done, total = text.rsplit("Sample ", 1)[1].split()[0].split("/")
                print(f"HOLO_PROGRESS {int(done) / int(total):.3f}", flush=True)
            except ValueError:
                pass

    handlers.render_stats.append(lambda *a: stats(str(a[-1])))
    bpy.ops.render.render(write_still=True, scene=scene.name, layer=args["view_layer"])


if __name__ == "__main__":
    main(json.loads(sys.argv[sys.argv.index("--") + 1]))
    # The image is written: the process ends here. After this render the bpy module's own exit
    # crashes in 4.2.0 (SIGSEGV) and never returns in 4.5.15, which the worker would take for
    # a failed or endless render.
    sys.stdout.flush()
    os._exit(0)
