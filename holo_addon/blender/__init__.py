"""Blender helpers the rest of the add-on shares; nothing here imports another part of it."""
