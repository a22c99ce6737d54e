"""The holographic job: prepared on Blender's main thread, run in a worker process."""
