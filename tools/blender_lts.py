"""The built extension in another Blender release, end to end (``make check-lts``).

Run by that release's bpy module (its own virtual environment, see the Makefile):

    python tools/blender_lts.py holo-<version>.zip WORKDIR

Installs the zip with Blender's own extension installer into a fresh user folder, then on a
small scene (a holographic sphere, a plate, a camera) records the hologram, renders the
holographic pass, sets up the Depth Combine on that release's compositor API and renders the
frame. Exits non-zero with the reason when any step fails. Not part of ``make test``: each
release is a 370 MB download.
"""

import os
import sys
from pathlib import Path

import bpy


def install(zip_path: str) -> None:
    sys.path.insert(0, str(Path(bpy.utils.system_resource("SCRIPTS")) / "addons_core"))
    from bl_pkg import cli_extension
    bpy.ops.wm.read_homefile(app_template="")
    rc = cli_extension(["install-file", zip_path, "--repo", "user_default", "--enable"])
    if rc or not hasattr(bpy.types.Scene, "holo"):
        sys.exit(f"the extension did not install and register (exit {rc})")


def scene(work: Path):
    s = bpy.context.scene
    for obj in list(s.objects):
        bpy.data.objects.remove(obj)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.3)
    bpy.context.object.holo.emitter = "POINTS"
    bpy.ops.object.camera_add(location=(0, -3, 0), rotation=(1.5708, 0, 0))
    s.camera = bpy.context.object
    bpy.ops.mesh.primitive_plane_add(size=0.8, location=(0, -1.5, 0), rotation=(1.5708, 0, 0))
    bpy.context.object.holo.is_plate = True  # its +Z faces the camera
    s.render.resolution_x, s.render.resolution_y, s.render.resolution_percentage = 48, 36, 100
    s.render.engine = "CYCLES"  # Workbench draws every object: the emitter too
    s.cycles.samples = 4
    s.holo.iterations, s.holo.max_resolution = 1, 512
    s.holo.output_dir = str(work / "holo") + os.sep
    s.render.filepath = str(work / "frame.png")
    return s


def main(zip_path: str, work: str) -> None:
    work = Path(work)
    install(zip_path)
    import pyopencl

    import holo_core
    s = scene(work)
    for op in (bpy.ops.holo.render_pass, bpy.ops.holo.setup_compositing):
        if op() != {"FINISHED"}:
            sys.exit(f"{op.idname_py()} did not finish")
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(s.render.filepath)
    w, h = image.size
    px = list(image.pixels)
    centre, corner = ((h // 2 * w + w // 2) * 4, 0)
    if not sum(px[centre:centre + 3]) > sum(px[corner:corner + 3]) + 0.1:
        sys.exit("the holographic sphere is missing from the composited frame")
    layers = sorted(work.glob("holo_frame*.exr"))
    if not layers or not layers[0].stat().st_size:
        sys.exit(f"no holographic layers beside the render in {work}")
    print(f"Blender {bpy.app.version_string}: installed, registered (core at "
          f"{holo_core.__file__}, {len(pyopencl.get_platforms())} OpenCL platform), recorded, "
          f"pass rendered and composited, layers "
          f"written beside the frame ({layers[0].name}): OK")


if __name__ == "__main__":
    main(*sys.argv[1:3])
