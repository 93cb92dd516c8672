"""The files a room names, opened safely (regular files only, checked before they are opened),
and the limits on a room's size.

A room file names other files: a glTF file its buffers and images, an OBJ file its material
libraries (`mtllib`), an MTL file its texture maps (`map_Kd` and the like). A FIFO named there
would block the reader forever and a device such as /dev/zero would never end, so every named
file that exists must be a regular file (a symbolic link counts as what it points to). It is
checked with stat before it is opened, then opened with O_NONBLOCK (so that a FIFO put there
in between cannot block the open) and checked again on the open descriptor with fstat, and read
up to a stated size. Files the room names but the gallery does not use (images and texture
maps: a room's surfaces take their material factors only) are checked but never opened."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from .. import _core

__all__ = ["check_regular", "read_regular", "check_triangles", "MAX_FILE_BYTES", "MAX_TRIANGLES",
           "MAX_VERTICES"]

MAX_FILE_BYTES = 1 << 30       # 1 GiB: a room, not a city (a room file and each file it names)
# What the irradiance bake can hold: a triangle needs at least 3 lattice points and a bake
# holds at most BAKE_MAX_POINTS (2^25) of them, so at most 11184810 triangles.
BAKE_MAX_POINTS = int(_core.BAKE_MAX_POINTS)
MAX_TRIANGLES = BAKE_MAX_POINTS // 3
MAX_VERTICES = 3 * MAX_TRIANGLES  # mesh instances' vertices, each transformed on its own

_KINDS = ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISDIR, "a directory"),
          (stat.S_ISSOCK, "a socket"))


def _require_regular(mode: int, what: str):
    if not stat.S_ISREG(mode):
        kind = next((name for test, name in _KINDS if test(mode)), "not a file")
        raise OSError(f"{what} is not a regular file ({kind})")


def check_regular(path: Path, what: str, missing_ok: bool = False) -> os.stat_result | None:
    """stat of `path` when it is a regular file; OSError naming `what` when it is anything
    else (FileNotFoundError when it does not exist, unless missing_ok: then None). A path is a
    str, bytes or os.PathLike: TypeError for anything else (os.stat would take an int as an
    open file descriptor)."""
    if not isinstance(path, (str, bytes, os.PathLike)):
        raise TypeError(f"{what}: a path must be a str or a Path, got {type(path).__name__}")
    try:
        st = os.stat(path)
    except FileNotFoundError:
        if missing_ok:
            return None
        raise FileNotFoundError(f"{what} not found") from None
    except (OSError, ValueError) as e:  # a name too long, a NUL byte, no permission
        raise OSError(f"{what}: {e}") from None
    _require_regular(st.st_mode, what)
    return st


def read_regular(path: Path, what: str, limit: int, length: int | None = None) -> bytes:
    """The bytes of the regular file `path` (its first `length` bytes when given: OSError if
    it is shorter). ValueError when what would be read exceeds `limit` bytes; OSError naming
    `what` for a missing file, a FIFO, a device or a directory."""
    check_regular(path, what)
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as e:
        raise OSError(f"{what}: {e.strerror or e}") from None
    try:
        st = os.fstat(fd)
        _require_regular(st.st_mode, what)  # replaced between the stat and the open
        want = st.st_size if length is None else length
        if want > limit:
            raise ValueError(f"{what}: {want} bytes is too large (more than {limit})")
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read(want)
    finally:
        os.close(fd)
    if len(data) < want:
        raise OSError(f"{what}: {len(data)} bytes, {want} expected (truncated)")
    return data


def check_triangles(path: Path, triangles: int, what: str = ""):
    """ValueError when a room has more triangles than the gallery can bake."""
    if triangles > MAX_TRIANGLES:
        raise ValueError(f"{path}: {triangles} triangles{what}, more than the {MAX_TRIANGLES} a "
                         f"room can have (the gallery's irradiance bake needs at least 3 lattice "
                         f"points per triangle and holds at most {BAKE_MAX_POINTS})")
