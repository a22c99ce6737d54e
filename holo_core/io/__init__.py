"""Every file format, and nothing else: no physics is imported here.

- ``image.py``: atomic writes, PNG and OpenEXR images
- ``hologram.py``: hologram files (EXR with their metadata)
- ``plate_set.py``: a plate's parts along a path as one folder, its manifest naming each
  part's files and their digests
- ``acquired.py``: acquired scans and laboratory arrays in and out (PNG, TIFF, EXR, .npy, HDF5,
  MATLAB v7.3), nothing read from outside the file named
- ``jsonfile.py``: JSON metadata bounded (size, nesting depth) before it is parsed
- ``mesh.py``: OBJ and PLY meshes
- ``view.py``: a rendered view as a multilayer EXR and a PNG preview
- ``shared_view.py``: rendered pictures handed between processes through shared memory
- ``store.py``: a plate in tiles, a Zarr store for plates beyond memory; its parts:
  ``files.py`` (a store's files, read and written without following links), ``digests.py``
  (a recording's digest, the tiles' keys and checksums), ``store_lock.py`` (the lock a
  recording holds), ``tiled_wave.py`` (a store's plate read tile by tile, lazily) and
  ``plate_paths.py`` (a plate file or the store beside it)
"""
