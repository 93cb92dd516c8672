"""The walk's two frame rates, each with what it measures.

A recorded walk reports two rates that differ several-fold, and a bare "fps" hides which is
which:

- `fps`: frames a second of wall-clock time over the whole walk, first frame to last. It
  counts everything between two frames: the frame loop, the oracle comparison (a second
  virtual texture loaded synchronously and a second display pass, per frame) and, in
  `gigascroll gallery` and `demo`, composing, tone-mapping, encoding and saving each frame.
- `fps_from_frame_time`: 1000 / the mean of the frames' `total_ms`, the frame loop's timed
  stages alone (feedback, processing, issue, drain, update, display): the rate a headset
  running the same loop would get, without the oracle or the recording.
"""

from __future__ import annotations

__all__ = ["FPS_MEANING", "fps_text"]

FPS_MEANING = {
    "fps": "wall-clock frames a second over the walk, including the oracle comparison and "
           "the recording (composing, encoding and saving each frame)",
    "fps_from_frame_time": "1000 / mean total_ms: the frame loop's stages alone (feedback, "
                           "processing, issue, drain, update, display), no oracle, no recording",
}


def fps_text(summary: dict) -> str:
    """Both rates of a recorded walk's summary in words, for the console and the report, e.g.
    '14.79 fps in the frame loop alone (feedback to display), 2.72 fps of wall clock with the
    oracle and recording' (without an oracle, 'with recording')."""
    extra = "the oracle and recording" if "error_mean" in summary else "recording"
    return (f"{summary['fps_from_frame_time']:.2f} fps in the frame loop alone (feedback to "
            f"display), {summary['fps']:.2f} fps of wall clock with {extra}")
