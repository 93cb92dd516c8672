"""The browser client's folder (python/gigascroll/web/) and the one way into it.

A request names a relative path; it is served only when every part is a plain name (no empty
part, no `.` or `..`, no hidden file, no NUL or backslash), its suffix is one the client ships,
and the file it resolves to (symlinks followed) is a regular file inside the folder. Anything
else is a 404, the same answer as a missing file, so a probe learns nothing. No listings."""

from __future__ import annotations

from pathlib import Path

__all__ = ["CLIENT_DIR", "CONTENT_TYPES", "client_path"]

CLIENT_DIR = Path(__file__).resolve().parent.parent / "web"
CONTENT_TYPES = {".js": "text/javascript", ".mjs": "text/javascript", ".html": "text/html",
                 ".css": "text/css", ".glsl": "text/plain", ".json": "application/json"}
MAX_PATH = 512


def client_path(relative: str, root: Path = CLIENT_DIR, types=CONTENT_TYPES) -> Path | None:
    """The file `relative` names inside `root`, or None when it is not servable (`types`: the
    suffixes served, the client's by default)."""
    if not relative or len(relative) > MAX_PATH or "\0" in relative or "\\" in relative:
        return None
    parts = relative.split("/")
    if any(not p or p.startswith(".") for p in parts):
        return None
    if Path(parts[-1]).suffix not in types:
        return None
    try:
        base = root.resolve(strict=True)
        target = (base / relative).resolve(strict=True)
    except (OSError, RuntimeError, ValueError):  # missing, a symlink loop, a bad name
        return None
    if not target.is_relative_to(base) or not target.is_file() or target.suffix not in types:
        return None
    return target
