"""The one way every command writes, replaces and removes its outputs.

A command deletes only what it provably made:

- an existing directory output is replaced only when it is empty or when its marker says the
  same command made it (`owned(path)`: for a pack its manifest, for the others the MARK file
  `write_mark` puts in it); never `.`, `..`, `/`, the home directory or an ancestor of the
  working directory (also after resolving symbolic links), never through a symbolic link;
- an existing file is replaced only with force (and never when it is a directory).

No output looks complete when it is not: every file is written under a temporary name in its
own directory, flushed and closed with errors checked, then renamed; a directory is built
under a temporary name and swapped in at the end, its mark of completeness written last. A
full disk (ENOSPC) or a file-size limit (EFBIG: `ignore_sigxfsz` keeps SIGXFSZ from killing the
process) is an OSError naming the file, and the temporaries are gone. `signals_interrupt`
turns SIGTERM and SIGHUP into `Interrupted` (a KeyboardInterrupt) in the main thread, so the
same cleanup runs for them as for Ctrl-C."""

from __future__ import annotations

import contextlib
import ctypes
import errno
import io
import itertools
import json
import os
import re
import shutil
import signal
import threading
from pathlib import Path
from typing import Callable

__all__ = ["MARK", "beside", "protected_reason", "refuse_protected", "refuse_input", "check_output",
           "write_mark", "has_mark", "owned_by", "temp_dir", "remove_stale_temps", "atomic_file", "write_bytes",
           "write_text", "replace_dir", "write_image", "encode_image", "Interrupted",
           "signals_interrupt", "signals_deferred", "ignore_sigxfsz", "write_error", "WriteError",
           "oiio_reason", "full_reason"]

MARK = ".gigascroll-output.json"   # in a directory a command made: which command made it

_counter = itertools.count()
_FULL = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)  # the disk or the size limit is full


class WriteError(OSError):
    """'cannot write PATH: REASON', one line for the CLI, with the system's errno."""


def write_error(path, e: OSError) -> OSError:
    """A WriteError for `path` that keeps `e`'s errno (`e` itself when it already is one)."""
    if isinstance(e, WriteError):
        return e
    err = WriteError(f"cannot write {path}: {e.strerror or e}")
    err.errno = e.errno
    return err


# ----------------------------------------------------------------------------- what may go

def _home() -> Path | None:
    try:
        return Path.home().resolve()
    except (RuntimeError, KeyError, OSError):
        return None


def protected_reason(path) -> str | None:
    """Why `path` must never be replaced or removed (None when it may be): `.`, `..`, `/`, the
    home directory, the working directory or one of its ancestors, by name or once
    symbolic links are resolved."""
    p = Path(path)
    if p.is_absolute() and p == Path(p.anchor):
        return "is the root directory"
    if p.name in ("", ".", ".."):
        return "is the working directory or its parent"
    try:
        cwds = {Path.cwd(), Path.cwd().resolve()}
    except OSError:  # the working directory was removed: no path is inside it
        cwds = set()
    candidates = {Path(os.path.abspath(p))} if cwds else {p} if p.is_absolute() else set()
    with contextlib.suppress(OSError, RuntimeError):
        candidates.add(p.resolve())
    home = _home()
    for c in candidates:
        if c == Path(c.anchor):
            return "is the root directory"
        if home is not None and (c == home or c == Path(os.path.expanduser("~"))):
            return "is the home directory"
        for d in cwds:
            if c == d or c in d.parents:
                return "is the working directory or one of its ancestors"
    return None


def refuse_protected(path) -> Path:
    """`path` as a Path, or OSError when it is a protected place (protected_reason)."""
    p = Path(path)
    reason = protected_reason(p)
    if reason:
        raise OSError(f"{p}: {reason}; refusing to write there")
    return p


def _places(path) -> set[Path]:
    """`path` absolute by name and with symbolic links resolved (where that works)."""
    p = Path(path)
    places = {Path(os.path.abspath(p))}
    with contextlib.suppress(OSError, RuntimeError):
        places.add(p.resolve())
    return places


def refuse_input(path, source, what: str = "an input of this command") -> Path:
    """`path` as a Path, or OSError when writing it would write over or into `source` (a file
    or directory the command reads): `path` is `source`, lies inside it, or holds it (by name
    or once symbolic links are resolved). `export PACK -o PACK/index.bin` would otherwise
    replace the pack's own index while it is being read."""
    p = Path(path)
    for out in _places(p):
        for src in _places(source):
            if out == src or src in out.parents or out in src.parents:
                where = "is" if out == src else "is inside" if src in out.parents else "holds"
                raise OSError(f"{p}: {where} {what} ({source}); refusing to write there")
    return p


def check_output(path, *, force: bool, directory: bool, owned: Callable[[Path], bool] | None = None,
                 what: str = "an output of this command") -> bool:
    """Raises OSError unless `path` may be written: absent, or (with force) a file for a file
    output, an empty or `owned` directory for a directory output, and never a protected place
    (protected_reason) or a link to a directory. Returns whether something is there now."""
    p = refuse_protected(path)
    if not (p.exists() or p.is_symlink()):
        return False
    if not force:
        raise OSError(f"{p}: already exists (use --force / force=True to overwrite)")
    if p.is_symlink() and (directory or p.is_dir()):
        raise OSError(f"{p}: is a symbolic link to a directory; refusing to replace it")
    if directory:
        if not p.is_dir():
            raise OSError(f"{p}: exists and is not a directory; refusing to overwrite it")
        if any(p.iterdir()) and not (owned is not None and owned(p)):
            raise OSError(f"{p}: exists and is not {what}; refusing to overwrite it")
    elif p.is_dir():
        raise OSError(f"{p}: is a directory; refusing to overwrite it")
    return True


def write_mark(directory, command: str, **details) -> None:
    """Marks `directory` as made by `command` (written last: it also says the output is whole)."""
    write_text(Path(directory) / MARK, json.dumps({"made_by": "gigascroll", "command": command,
                                                   **details}) + "\n")


def has_mark(directory, command: str, **details) -> bool:
    """Whether `directory` holds the mark of `command` (a regular file, not a link) whose
    details equal `details`."""
    mark = Path(directory) / MARK
    try:
        if mark.is_symlink() or not mark.is_file() or mark.stat().st_size > 65536:
            return False
        m = json.loads(mark.read_text())
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):
        return False
    return (isinstance(m, dict) and m.get("made_by") == "gigascroll"
            and m.get("command") == command and all(m.get(k) == v for k, v in details.items()))


def owned_by(command: str, **details) -> Callable[[Path], bool]:
    """The `owned` test of check_output for directories marked by `command`."""
    return lambda p: has_mark(p, command, **details)


# ----------------------------------------------------------------------------- default places

def beside(anchor, suffix: str) -> Path:
    """Where an output made from `anchor` (a pack, an image, another output) goes when the
    user names none: next to it and named after it, `shows/a.pack` -> `shows/a-walk` for
    suffix "walk", wherever the command runs from. Absolute, so the command can say where."""
    a = Path(os.path.abspath(anchor))
    return a.parent / f"{a.stem or 'output'}-{suffix}"


# ----------------------------------------------------------------------------- temporaries

def temp_dir(out, hidden: bool = False, command: str | None = None, **details) -> Path:
    """A new empty directory beside `out`, `OUT.tmp-PID` (`.OUT.tmp-PID` when hidden; a
    suffix -1, -2, ... when that name is taken: an existing one is never reused or removed).
    With `command` it is marked as that command's at once (write_mark), so that a run killed
    outright leaves a temporary the next run can prove is one (remove_stale_temps)."""
    out = Path(out)
    base = f"{'.' if hidden else ''}{out.name}.tmp-{os.getpid()}"
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise write_error(out, e) from None
    for k in range(1000):
        p = out.parent / (base if k == 0 else f"{base}-{k}")
        try:
            p.mkdir()
        except FileExistsError:
            continue
        except OSError as e:
            raise write_error(out, e) from None
        if command is not None:
            try:
                write_mark(p, command, **details)
            except BaseException:
                shutil.rmtree(p, ignore_errors=True)
                raise
        return p
    raise OSError(f"cannot write {out}: no free temporary name beside it")


def _process_gone(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OSError:  # it exists and is someone else's
        return False
    return False


def remove_stale_temps(out, command: str | None, hidden: bool = False,
                       belongs: Callable[[Path], bool] | None = None, **details) -> list[Path]:
    """Removes the temporaries of `out` (temp_dir's names, and replace_dir's `-old`) that a
    run of `command` killed outright left: its process is gone and the directory holds its
    mark (or, with `belongs`, `belongs(directory)` says it is that command's: a pack build
    tells its own by its files). Anything else with such a name stays. Returns what was
    removed."""
    out = Path(out)
    if belongs is None:
        belongs = lambda p: has_mark(p, command, **details)  # noqa: E731
    pattern = re.compile(("\\." if hidden else "") + re.escape(out.name)
                         + r"\.tmp-([0-9]{1,10})(-[0-9]{1,3}|-old)?")
    removed = []
    try:
        siblings = list(out.parent.iterdir())
    except OSError:
        return removed
    for p in siblings:
        m = pattern.fullmatch(p.name)
        if (m and int(m.group(1)) != os.getpid() and _process_gone(int(m.group(1)))
                and p.is_dir() and not p.is_symlink() and belongs(p)):
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    return removed


@contextlib.contextmanager
def atomic_file(path, durable: bool = False):
    """Yields a temporary path beside `path` (same directory and extension) for the caller to
    write and close with errors checked; on leaving it is renamed to `path` (fsynced first when
    durable). On an exception the temporary is removed and the error is raised."""
    path = Path(path)
    if path.is_dir() and not path.is_symlink():
        raise OSError(f"{path}: is a directory; refusing to overwrite it")
    tmp = path.parent / f".{path.stem}.tmp-{os.getpid()}-{next(_counter)}{path.suffix}"
    try:
        yield tmp
        if durable:
            fd = os.open(tmp, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        os.replace(tmp, path)
    except BaseException as e:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(e, OSError) and not isinstance(e, WriteError) and (
                e.errno in _FULL or e.filename in (str(tmp), tmp)):
            raise write_error(path, e) from None
        raise


def write_bytes(path, data: bytes, durable: bool = False) -> None:
    """Writes `data` to `path` atomically (see atomic_file); OSError 'cannot write PATH: ...'."""
    with atomic_file(path, durable) as tmp:
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
            try:
                view = memoryview(data).cast("B")
                while view:
                    view = view[os.write(fd, view):]
            finally:
                os.close(fd)
        except OSError as e:
            raise write_error(path, e) from None


def write_text(path, text: str, durable: bool = False) -> None:
    write_bytes(path, text.encode("utf-8"), durable)


# ----------------------------------------------------------------------------- images

def encode_image(pixels, fmt: str, quality: int = 90) -> bytes:
    """PNG or JPEG (4:4:4) bytes of an (H, W, 3) or (H, W) uint8 image, encoded in memory by
    Pillow: a failing disk reaches neither libjpeg's error exit nor a PNG writer that reports
    success for a truncated file (OpenImageIO's close() does)."""
    import numpy as np
    from PIL import Image
    buf = io.BytesIO()
    img = Image.fromarray(np.ascontiguousarray(pixels))
    if fmt == "JPEG":
        img.save(buf, "JPEG", quality=int(quality), subsampling=0)
    else:
        img.save(buf, fmt)
    return buf.getvalue()


def write_image(path, pixels, quality: int = 90, durable: bool = False) -> None:
    """Writes an (H, W, C) array atomically: uint8 PNG and JPEG through encode_image, any other
    format OpenImageIO knows by extension (EXR, HDR, TIFF; float32 or uint8) into a temporary
    file whose write and close are checked."""
    import numpy as np
    path = Path(path)
    data = np.ascontiguousarray(pixels)
    if data.dtype not in (np.uint8, np.float32) or data.ndim not in (2, 3):
        raise ValueError(f"write_image takes (H, W[, C]) uint8 or float32, got {data.dtype} "
                         f"{data.shape}")
    fmt = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG"}.get(path.suffix.lower())
    if fmt is not None and data.dtype == np.uint8:
        write_bytes(path, encode_image(data, fmt, quality), durable)
        return
    import OpenImageIO as oiio
    with atomic_file(path, durable) as tmp:
        out = oiio.ImageOutput.create(str(tmp))
        if out is None:
            raise OSError(f"cannot write {path}: {' '.join(oiio.geterror().split()) or 'unknown format'}")
        spec = oiio.ImageSpec(data.shape[1], data.shape[0], data.shape[2] if data.ndim == 3 else 1,
                              "float" if data.dtype == np.float32 else "uint8")
        ok = out.open(str(tmp), spec) and out.write_image(data)
        closed = out.close()
        if not (ok and closed):
            raise OSError(f"cannot write {path}: {oiio_reason(out, tmp)}")


def full_reason(path) -> str | None:
    """The system's words when a write to `path` failed because its disk is full or the file
    reached the file-size limit (libraries that write files themselves often say less)."""
    with contextlib.suppress(OSError, ValueError, ImportError):
        if os.statvfs(Path(path).parent).f_bavail == 0:
            return "No space left on device"
        import resource
        limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        if limit != resource.RLIM_INFINITY and os.path.getsize(path) >= limit:
            return "File too large (the file-size limit)"
    return None


def oiio_reason(out, tmp: Path) -> str:
    """OpenImageIO's error, or the system's words when the disk is full."""
    return full_reason(tmp) or " ".join((out.geterror() or "").split())[:300] or "write failed"


# ----------------------------------------------------------------------------- directories

_RENAME_EXCHANGE = 2


def _exchange(a: Path, b: Path) -> bool:
    """Atomically swaps two directory entries (Linux renameat2 RENAME_EXCHANGE). False when
    the system or file system does not support it."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    at_fdcwd = -100
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (22, 38, 95):  # EINVAL, ENOSYS, EOPNOTSUPP: not supported here
        return False
    raise OSError(err, f"cannot replace {b}: {os.strerror(err)}")


def fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def replace_dir(tmp, out, owned: Callable[[Path], bool] | None = None) -> None:
    """Puts the finished directory `tmp` at `out`. An existing `out` (which check_output let
    through: empty or `owned`, checked again here) is swapped out in one step (readers see the
    old or the new one, never none) and then deleted; without RENAME_EXCHANGE it is moved
    aside first. Signals wait until the swap is done."""
    tmp, out = Path(tmp), Path(out)
    with signals_deferred():  # no half-done swap
        if out.exists() or out.is_symlink():
            if out.is_symlink() or os.path.samefile(tmp, out):
                raise OSError(f"{out}: is not a directory this command may replace")
            if out.is_symlink() or not out.is_dir() or protected_reason(out) or (
                    any(out.iterdir()) and not (owned is not None and owned(out))):
                raise OSError(f"{out}: changed while it was being written; refusing to replace it")
            if not _exchange(tmp, out):
                aside = out.parent / f"{out.name}.tmp-{os.getpid()}-old"
                os.rename(out, aside)
                os.rename(tmp, out)
                tmp = aside
            fsync_dir(out.parent)
            shutil.rmtree(tmp)
        else:
            os.rename(tmp, out)
            fsync_dir(out.parent)  # make the rename itself durable


@contextlib.contextmanager
def signals_deferred():
    """SIGINT, SIGTERM and SIGHUP wait (blocked) while the block runs: renames that together
    publish an output are done all or none."""
    blocked = {signal.SIGINT, signal.SIGTERM, signal.SIGHUP}
    old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, blocked)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)


# ----------------------------------------------------------------------------- signals

class Interrupted(KeyboardInterrupt):
    """A command stopped by SIGTERM or SIGHUP (SIGINT stays a plain KeyboardInterrupt); its
    temporaries have been removed by the cleanup that ran. `signum` is the signal's number."""

    def __init__(self, signum: int):
        super().__init__(f"stopped by {signal.Signals(signum).name}")
        self.signum = signum


@contextlib.contextmanager
def signals_interrupt():
    """While the block runs, SIGTERM and SIGHUP raise Interrupted in the main thread (as SIGINT
    raises KeyboardInterrupt), once: a second signal during the cleanup is ignored, so the
    cleanup finishes. Outside the main thread, or where the caller set its own handlers (nohup),
    nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    fired = []

    def handler(signum, frame):
        if fired:
            return
        fired.append(signum)
        raise Interrupted(signum)

    saved = {}
    for sig in (signal.SIGTERM, signal.SIGHUP):
        if signal.getsignal(sig) in (signal.SIG_DFL, None):  # leave the caller's own handlers
            saved[sig] = signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, old in saved.items():
            signal.signal(sig, old)


def ignore_sigxfsz() -> None:
    """A write past the file-size limit (RLIMIT_FSIZE) fails with EFBIG, an OSError the command
    reports, instead of SIGXFSZ killing the process."""
    if hasattr(signal, "SIGXFSZ") and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
