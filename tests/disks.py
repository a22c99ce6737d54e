"""Helpers of the tests of a full disk: another program taking the room left."""

import os


def fill(folder) -> None:
    """Take all the room left on the disk of ``folder`` (a file ``filler`` there)."""
    fd = os.open(os.path.join(folder, "filler"), os.O_WRONLY | os.O_CREAT | os.O_APPEND)
    try:
        while os.write(fd, b"\0" * 4096):
            pass
    except OSError:  # the disk is full
        pass
    finally:
        os.close(fd)
