"""The walk's H.264 MP4, written by ffmpeg (imageio-ffmpeg's binary) from raw RGB frames on its
standard input. ffmpeg's own exit status is checked when the video is closed (imageio-ffmpeg's
writer does not check it, so a video cut short by a full disk looked finished), and any failure
is one OSError line with ffmpeg's first error line."""

from __future__ import annotations

import math
import signal
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ..outputs import full_reason

__all__ = ["VideoWriter", "check_fps", "FPS_RANGE"]

FPS_RANGE = (0.01, 1000.0)   # frame rates the MP4 is written at (ffmpeg takes them as %.3f)


def check_fps(fps) -> float:
    """The path's frame rate as a float, or ValueError naming the range the video takes."""
    try:
        f = float(fps)
    except (TypeError, ValueError):
        f = math.nan
    if not (FPS_RANGE[0] <= f <= FPS_RANGE[1]):
        raise ValueError(f"the camera path's frame rate must be in [{FPS_RANGE[0]:g}, "
                         f"{FPS_RANGE[1]:g}] frames per second for the video, got {fps!r}")
    return f


class VideoWriter:
    """`send(rgb8)` frames of `size` (width, height, both even) to `path`; `close()` waits for
    ffmpeg and raises OSError unless it wrote the whole video; `abort()` stops it."""

    def __init__(self, path: Path, size: tuple[int, int], fps: float, params: list[str]):
        import imageio_ffmpeg
        self.path, self.size = Path(path), size
        self._log = tempfile.TemporaryFile()
        cmd = [imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-nostdin", "-loglevel", "error",
               "-f", "rawvideo", "-vcodec", "rawvideo", "-s", f"{size[0]}x{size[1]}",
               "-pix_fmt", "rgb24", "-r", f"{check_fps(fps):.3f}", "-i", "-", "-an",
               "-vcodec", "libx264", "-pix_fmt", "yuv420p", *params, str(self.path)]
        try:
            self._proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                          stderr=self._log)
        except OSError as e:
            self._log.close()
            raise OSError(f"cannot start ffmpeg for {self.path}: {e.strerror or e}") from None

    def send(self, rgb8: np.ndarray) -> None:
        if rgb8.shape != (self.size[1], self.size[0], 3) or rgb8.dtype != np.uint8:
            raise ValueError(f"video frame {rgb8.shape} {rgb8.dtype}, expected "
                             f"{(self.size[1], self.size[0], 3)} uint8")
        try:
            self._proc.stdin.write(np.ascontiguousarray(rgb8).data)
        except (BrokenPipeError, OSError):
            self._proc.wait()
            raise self._failure() from None

    def close(self) -> None:
        try:
            self._proc.stdin.close()
        except (BrokenPipeError, OSError):
            pass
        if self._proc.wait() != 0:
            raise self._failure()
        self._log.close()

    def abort(self) -> None:
        if self._proc.poll() is None:
            self._proc.kill()
        self._proc.wait()
        self._log.close()

    def _failure(self) -> OSError:
        self._log.seek(0)
        lines = [ln.strip() for ln in self._log.read().decode("utf-8", "replace").splitlines()
                 if ln.strip()]
        self._log.close()
        rc = self._proc.returncode
        why = (full_reason(self.path) or (lines[0][:300] if lines else None)
               or (f"ffmpeg was stopped by {signal.Signals(-rc).name}" if rc < 0 else
                   f"ffmpeg exited with status {rc}"))
        return OSError(f"cannot write {self.path}: {why}")
