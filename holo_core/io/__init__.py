"""Every file format, and nothing else: no physics is imported here.

- ``image.py``: atomic writes, PNG and OpenEXR images
- ``hologram.py``: hologram files (EXR with their metadata) and acquired scans
- ``mesh.py``: OBJ and PLY meshes
- ``view.py``: a rendered view as a multilayer EXR and a PNG preview
"""
