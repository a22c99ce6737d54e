"""Blender → holo_core.scene: meshes, camera and plate in metres, as the render sees them."""
