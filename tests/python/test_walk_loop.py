"""The one frame loop (gigascroll.walk.loop.run_frames) with steps of the test's own: it opens
the loader and the steps' state once, runs every frame in order, stamps each record with its
end time, shows each frame to on_frame before the next starts, and closes the loader when a
step fails. FrameLoop and GalleryWalk run through it (test_frame_loop.py, test_gallery_walk.py)."""

import numpy as np
import pytest

from gigascroll import TileLoader, build_pack
from gigascroll.experiments import pattern_image
from gigascroll.walk.loop import run_frames


@pytest.fixture(scope="module")
def tiny_pack(tmp_path_factory):
    return build_pack(pattern_image(300, 200), tmp_path_factory.mktemp("walk_loop") / "t.pack")


class _Path:
    fps = 90.0

    def __init__(self, n):
        self.n = n

    def __len__(self):
        return self.n


class _Steps:
    """Steps that log what the loop asks of them; `fail_at`: the frame whose step raises."""

    def __init__(self, pack, frames, fail_at=None):
        self.pack, self.path, self.pace = pack, _Path(frames), False
        self.records, self.log, self.fail_at, self.loader = ["stale"], [], fail_at, None

    def loader_options(self):
        return {"mode": "lockfree", "threads": 1}

    def progress_label(self):
        return "test"

    def open_state(self, loader):
        self.log.append("open")
        self.loader = loader
        return {"opened": True}

    def step(self, frame, state):
        assert state == {"opened": True}
        self.log.append(("step", frame))
        if frame == self.fail_at:
            raise RuntimeError(f"frame {frame} failed")
        return {"frame": frame}, f"images {frame}"


def test_frames_run_in_order_with_their_end_times(tiny_pack):
    steps = _Steps(tiny_pack, 5)
    seen = []
    records = run_frames(steps, on_frame=lambda f, rec, images: (
        seen.append((f, rec["frame"], images)), steps.log.append(("shown", f))))
    assert records is steps.records and [r["frame"] for r in records] == list(range(5))
    assert steps.log == ["open"] + [e for f in range(5) for e in (("step", f), ("shown", f))]
    assert seen == [(f, f, f"images {f}") for f in range(5)]
    times = [r["time_s"] for r in records]
    assert all(t >= 0 for t in times) and times == sorted(times)
    assert isinstance(steps.loader, TileLoader)


def test_a_failed_step_closes_the_loader(tiny_pack):
    steps = _Steps(tiny_pack, 5, fail_at=2)
    with pytest.raises(RuntimeError, match="frame 2 failed"):
        run_frames(steps)
    assert [r["frame"] for r in steps.records] == [0, 1]
    assert steps.log[-1] == ("step", 2)
    with pytest.raises(ValueError, match="closed"):
        steps.loader.submit(np.zeros((1, 4), np.int64))


def test_no_frames_open_the_state_and_record_nothing(tiny_pack):
    steps = _Steps(tiny_pack, 0)
    assert run_frames(steps) == [] and steps.log == ["open"]
