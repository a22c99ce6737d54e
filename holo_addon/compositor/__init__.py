"""The holographic pass in Blender's compositor, and the frame handlers that make it."""
