"""Public functions given an object of the wrong type raise one TypeError naming the argument,
not an AttributeError from deep inside (issue 11 §6: misuse gets a clear exception)."""

import pytest

import gigascroll as g

WRONG = [None, "a string", 3.5, object()]


def _calls(x):
    return [
        ("read_level", lambda: g.read_level(x, 0, 0), "pack"),
        ("verify_pack", lambda: g.verify_pack(x), "pack"),
        ("pack_summary", lambda: g.pack_summary(x), "pack"),
        ("single_scroll", lambda: g.single_scroll(x), "spec"),
        ("run_processor", lambda: g.run_processor(x, None, None, 0), "processor"),
        ("default_radius", lambda: g.default_radius(x), "scene"),
        ("render", lambda: g.render(x, None), "scene"),
        ("render_stereo", lambda: g.render_stereo(x, None), "scene"),
        ("FrameLoop", lambda: g.FrameLoop(g.single_scroll(), x, None), "pack"),
    ]


@pytest.mark.parametrize("wrong", WRONG, ids=lambda w: type(w).__name__)
def test_wrong_type_is_a_type_error_naming_the_argument(wrong):
    for name, call, arg in _calls(wrong):
        with pytest.raises(TypeError) as e:
            call()
        message = str(e.value)
        assert arg in message, (name, message)
        assert type(wrong).__name__ in message, (name, message)
        assert "\n" not in message, (name, message)


def test_the_right_types_still_pass(tmp_path):
    # The checks accept what the functions always took: a pack from the builder (either
    # reader), a Scene (its radius is 1% of the diagonal, computed here from its bounds).
    import math
    import numpy as np
    from gigascroll.pack.reader import PurePack
    img = (np.arange(40 * 24 * 3) % 251).astype(np.uint8).reshape(24, 40, 3)
    pack = g.build_pack(img, tmp_path / "p", tile_size=16, border=2)
    assert np.array_equal(g.read_level(pack, 0, 0), img)
    with PurePack(pack.path) as pure:
        assert np.array_equal(g.read_level(pure, 0, 0), img)
    scene, _camera = g.builtin_scene("cornell")
    lo, hi = scene.bounds
    assert g.default_radius(scene) == pytest.approx(0.01 * math.dist(lo, hi))


def test_run_processor_accepts_every_processing_method():
    # Each of make_processor's methods (cpu-async has submit/poll instead of process) passes
    # the type check: the same requests as the basic processor on one frame of feedback.
    import numpy as np
    keys = np.full((4, 4), g.NO_REQUEST, np.uint64)
    for method in g.PROCESSING_METHODS:
        try:
            g.run_processor(g.make_processor(method), keys, g.ResidencyLookup(), 0)
        except TypeError as e:
            assert "processor must be" not in str(e), (method, e)
