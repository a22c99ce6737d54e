"""Add-on preferences: the OpenCL device the worker uses, what each device can do, and Intel's
CPU runtime installed on demand.

Blender's own process never loads an OpenCL driver: the device listing comes from a child
Python (``python -m holo_core devices``) with the worker's environment. Intel's CPU runtime
(276 MB of wheels, too large to ship inside the extension) is what makes CPUs newer than PoCL's
LLVM work (AMD Zen 5); *Install CPU Runtime* installs it with pip into the extension's own user
folder, never system-wide, and only with Blender's online access allowed.
"""

from __future__ import annotations

import subprocess
import sys

import bpy
from bpy.props import FloatProperty, StringProperty

from holo_core.worker import environment

from ..compositor.session import session
from ..render.options import ADDON, device, runtime_paths, runtime_prefix

CPU_RUNTIME = ("intel-opencl-rt", "intel-cmplr-lib-rt")


def list_devices() -> list[str]:
    """``python -m holo_core devices`` in a child process, as the worker would see them."""
    r = subprocess.run(
        [sys.executable, "-m", "holo_core", "devices"],
        capture_output=True,
        text=True,
        env=environment(runtime_paths(), device() or None),
        timeout=120,
    )
    lines = (r.stdout + (r.stderr if r.returncode else "")).strip().splitlines()
    return lines or [f"the device listing failed (exit code {r.returncode})"]


class HOLO_OT_check_devices(bpy.types.Operator):
    """List the OpenCL devices Holo finds, whether each works, and which one it would use"""

    bl_idname = "holo.check_devices"
    bl_label = "Check Devices"

    def execute(self, context):
        session.devices = list_devices()
        for line in session.devices:
            self.report({"INFO"}, line)
        return {"FINISHED"}


class HOLO_OT_install_cpu_runtime(bpy.types.Operator):
    """Download Intel's CPU runtime (about 280 MB) into this add-on's folder; it runs on every current x86-64 CPU"""  # noqa: E501 -- one line: Blender shows it as the tooltip

    bl_idname = "holo.install_cpu_runtime"
    bl_label = "Install CPU Runtime"

    @classmethod
    def poll(cls, context):
        if not bpy.app.online_access:
            cls.poll_message_set("Allow Online Access in Preferences > System > Network")
            return False
        if sys.platform != "linux":
            cls.poll_message_set("Intel's CPU runtime from PyPI is used on Linux only")
            return False
        return True

    def execute(self, context):
        cmd = [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--prefix",
            str(runtime_prefix()),
            "--no-warn-script-location",
            "--disable-pip-version-check",
            *CPU_RUNTIME,
        ]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode:
            tail = (r.stderr or r.stdout).strip().splitlines()[-1:] or ["no output"]
            self.report({"ERROR"}, f"installing {' '.join(CPU_RUNTIME)} failed: {tail[0]}")
            return {"CANCELLED"}
        session.devices = list_devices()
        self.report({"INFO"}, f"installed into {runtime_prefix()}")
        return {"FINISHED"}


class HoloPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON

    device: StringProperty(
        name="Device",
        default="",
        description="The OpenCL device for recording and rendering. Empty: the best that "
        "works (a GPU, else a CPU). Or 'gpu', 'cpu', a number pair such as 1:0, "
        "or part of a device name, as Check Devices lists them",
    )
    memory_limit: FloatProperty(
        name="Memory Limit",
        default=0.0,
        min=0.0,
        soft_max=256.0,
        precision=1,
        description="The most memory (GiB) Holo may use; a larger pass is refused with the "
        "size it needs. 0: what the system has free (set it on shared farm nodes)",
    )

    scheduler: StringProperty(
        name="Dask Scheduler",
        default="",
        description="The Dask scheduler (tcp://host:8786) that records a plate too large for "
        "memory tile by tile on many machines. Empty: DASK_SCHEDULER_ADDRESS, "
        "else a local cluster of this machine's cores",
    )

    cache_dir: StringProperty(
        name="Cache Folder",
        subtype="DIR_PATH",
        default="",
        description="Where compiled OpenCL kernels and FFT plans are kept between runs. Empty: "
        "the system's user cache folder",
    )

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "device")
        layout.prop(self, "memory_limit")
        layout.prop(self, "scheduler")
        layout.prop(self, "cache_dir")
        row = layout.row()
        row.operator(HOLO_OT_check_devices.bl_idname, icon="VIEWZOOM")
        row.operator(HOLO_OT_install_cpu_runtime.bl_idname, icon="IMPORT")
        box = layout.box()
        for line in session.devices or ["Check Devices lists what the worker process finds."]:
            box.label(text=line.strip())


CLASSES = (HOLO_OT_check_devices, HOLO_OT_install_cpu_runtime, HoloPreferences)

register, unregister = bpy.utils.register_classes_factory(CLASSES)
