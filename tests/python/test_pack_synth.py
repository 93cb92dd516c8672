"""The built-in painting (gigascroll.pack.synth): deterministic, detailed, written as a
tiled BigTIFF."""

import numpy as np
import OpenImageIO as oiio
from pack_reference import ref_level

import gigascroll


def test_synth_is_deterministic_and_detailed(tmp_path):
    a = gigascroll.render_ink_landscape(3000, 300, 0, 300, seed=1)
    b = gigascroll.render_ink_landscape(3000, 300, 120, 40, seed=1)
    assert np.array_equal(a[120:160], b)
    assert not np.array_equal(a, gigascroll.render_ink_landscape(3000, 300, 0, 300, seed=2))
    # Fine detail: level 0 differs from level 1 upsampled (single-pixel strokes and grain).
    lvl1 = ref_level(a, 1)
    up = np.repeat(np.repeat(lvl1, 2, axis=0), 2, axis=1)[:300, :3000]
    assert np.abs(a - up).mean() > 2.0
    assert a.std() > 20  # mountains against paper, not a flat field
    path = gigascroll.synth_painting(tmp_path / "s.tif", 700, 90, seed=1)
    buf = oiio.ImageBuf(str(path))
    spec = buf.spec()
    assert (spec.width, spec.height, spec.nchannels) == (700, 90, 3) and spec.tile_width > 0
    assert np.array_equal(buf.get_pixels(oiio.UINT8),
                          gigascroll.render_ink_landscape(700, 90, 0, 90, seed=1))
    assert sorted(f.name for f in tmp_path.iterdir()) == ["s.tif"]
