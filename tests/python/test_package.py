"""The package gigascroll: the compiled core loads, and every subsystem's names reach the
package, each once."""

import gigascroll
from gigascroll import views as v


def test_core_module_loads():
    assert gigascroll.hardware_threads() >= 1


def test_subsystems_export_distinct_names():
    # gigascroll/__init__ re-exports every subsystem's public names: a name exported twice
    # would silently shadow another subsystem's class.
    from collections import Counter

    from gigascroll import pack, photon, runtime, views
    counts = Counter(n for m in (pack, runtime, views, photon) for n in m.__all__)
    assert [n for n, k in counts.items() if k > 1] == []
    for name in counts:
        assert hasattr(gigascroll, name), name
    # The package lists its names one by one: each listed name is there.
    assert len(set(gigascroll.__all__)) == len(gigascroll.__all__)
    for name in gigascroll.__all__:
        assert hasattr(gigascroll, name), name


def test_exports_reach_package():
    from gigascroll.walk import frame_loop
    assert gigascroll.HashProcessor is v.HashProcessor
    assert "multi_exhibition" in gigascroll.__all__
    assert gigascroll.FrameLoop is frame_loop.FrameLoop
