"""What a resumed sharded build may trust in `OUT.shards/`: the files a shard left there are
read only when they are regular files (checked before opening and again on the open
descriptor, so a FIFO never blocks the build and a link to /dev/zero is never read without
end), a record is at most a few kilobytes, and a record's fields follow the manifest schema
(a colour record is a painting's `colour` there) and hash to the digest it carries, before
anything of it is copied into a manifest."""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

__all__ = ["NotRegularFile", "require_regular_or_missing", "open_regular", "file_hash",
           "read_record", "record_digest", "record_problem"]

_CHUNK = 1 << 22
MAX_RECORD_BYTES = 1 << 20  # a record is ~1 KB; a colour record with chromaticities a few more
_XXH3 = frozenset("0123456789abcdef")


class NotRegularFile(OSError):
    """A FIFO, device, socket or directory where a shard's file should be."""


def _refuse_unless_regular(path: Path, mode: int) -> None:
    if not stat.S_ISREG(mode):
        kind = ("a FIFO" if stat.S_ISFIFO(mode) else "a device" if stat.S_ISCHR(mode)
                or stat.S_ISBLK(mode) else "a directory" if stat.S_ISDIR(mode) else
                "a socket" if stat.S_ISSOCK(mode) else "not a file")
        link = " (through a symbolic link)" if os.path.islink(path) else ""
        raise NotRegularFile(f"{path}: {kind}{link}, not a regular file; refusing to read it")


def require_regular_or_missing(path: Path) -> None:
    """NotRegularFile unless `path` is a regular file (through links) or does not exist."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return
    _refuse_unless_regular(path, mode)


def open_regular(path: Path) -> int:
    """A read-only descriptor of `path` if it is a regular file: NotRegularFile for a FIFO,
    a device, a socket or a directory (also through a link), FileNotFoundError if missing.
    Checked before opening (opening some devices acts) and on the descriptor (the name may
    have been replaced in between); O_NONBLOCK keeps the open of a FIFO that appears in
    between from blocking."""
    _refuse_unless_regular(path, os.stat(path).st_mode)
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    try:
        _refuse_unless_regular(path, os.fstat(fd).st_mode)
        os.set_blocking(fd, True)
    except BaseException:
        os.close(fd)
        raise
    return fd


def file_hash(path: Path) -> str:
    """XXH3-64 of a regular file's bytes (hex)."""
    import xxhash
    h = xxhash.xxh3_64()
    with os.fdopen(open_regular(path), "rb") as f:
        while chunk := f.read(_CHUNK):
            h.update(chunk)
    return h.hexdigest()


def read_record(path: Path) -> dict:
    """A shard record's JSON object: OSError or ValueError when it is not a regular file,
    larger than MAX_RECORD_BYTES, not JSON or not an object."""
    with os.fdopen(open_regular(path), "rb") as f:
        data = f.read(MAX_RECORD_BYTES + 1)
    if len(data) > MAX_RECORD_BYTES:
        raise ValueError(f"{path}: larger than {MAX_RECORD_BYTES} bytes")
    record = json.loads(data)
    if not isinstance(record, dict):
        raise ValueError(f"{path}: not a JSON object")
    return record


def record_digest(record: dict) -> str:
    """XXH3-64 of the record's fields other than its digest, in canonical JSON: a record
    edited since the worker wrote it (a colour record, a name) does not match."""
    import xxhash
    body = {k: v for k, v in record.items() if k != "record_xxh3"}
    return xxhash.xxh3_64_hexdigest(json.dumps(body, sort_keys=True, allow_nan=False).encode())


def _is_hash(v) -> bool:
    return isinstance(v, str) and len(v) == 16 and set(v) <= _XXH3


def _is_size(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= 1 << 30


def record_problem(record, check_digest: bool = True) -> str | None:
    """Why a shard record cannot go into a manifest (None when it can): its fields' types
    and ranges as the manifest schema has them for a painting, its colour record against
    the schema (the same rules as both pack readers), its hashes, and its own digest."""
    from .reader import validate_colour_record
    if not isinstance(record, dict):
        return "not a JSON object"
    name = record.get("name")
    if not isinstance(name, str) or not name:
        return "field 'name' is not a non-empty string"
    for key in ("source", "conversion"):
        if not isinstance(record.get(key), str):
            return f"field '{key}' is not a string"
    for key in ("width", "height"):
        if not _is_size(record.get(key)):
            return f"field '{key}' is not an integer in [1, 2^30]"
    for key in ("tiles_xxh3", "index_xxh3"):
        if not _is_hash(record.get(key)):
            return f"field '{key}' is not an XXH3-64 digest"
    if record.get("colour") is not None:
        try:
            validate_colour_record(record["colour"], "field 'colour'")
        except OSError as e:
            return str(e)
    try:
        json.dumps(record, allow_nan=False, ensure_ascii=False).encode()
    except (ValueError, UnicodeEncodeError) as e:  # NaN; a lone surrogate in a string
        return f"not valid JSON text ({str(e)[:100]})"
    if check_digest and record.get("record_xxh3") != record_digest(record):
        return "its digest does not match its fields (edited since it was written)"
    return None
