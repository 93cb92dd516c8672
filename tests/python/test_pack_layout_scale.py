"""The merged page-table layout at gallery scale (gigascroll.pack.plan_layout): 2000
paintings' tables laid out by both packers, checked against a brute-force occupancy grid;
the shelf layout does not run the BRKGA. (Its time is measured by `gigascroll bench layout`.)"""

import numpy as np
import pytest

from gigascroll.pack import plan_layout


def occupancy_fill(sizes, w, h, offsets):
    grid = np.zeros((h, w), np.uint8)
    for (mw, mh), (x, y) in zip(sizes, offsets):
        assert x % mw == 0 and y % mh == 0 and x + mw <= w and y + mh <= h
        assert not grid[y:y + mh, x:x + mw].any()  # overlap
        grid[y:y + mh, x:x + mw] = 1
    return grid.mean()


@pytest.mark.parametrize("dist", ["mixed", "paintings"])
def test_two_thousand_tables_valid_and_brkga_not_worse(dist):
    rng = np.random.default_rng(3)
    if dist == "mixed":
        sizes = [(1 << int(a), 1 << int(b)) for a, b in rng.integers(0, 6, (2000, 2))]
    else:  # mostly small paintings, a few large
        sizes = [(1 << int(a), 1 << int(a + d)) for a, d in
                 zip(rng.integers(0, 5, 2000), rng.integers(-1, 2, 2000)) if a + d >= 0]
    shelf = plan_layout(sizes, "shelf", 1)
    brkga = plan_layout(sizes, "brkga", 1)
    f_shelf = occupancy_fill(sizes, *shelf[:3])
    f_brkga = occupancy_fill(sizes, *brkga[:3])
    assert shelf[3]["fill_ratio"] == pytest.approx(f_shelf)
    assert brkga[3]["fill_ratio"] == pytest.approx(f_brkga)
    assert f_brkga >= f_shelf
    area = sum(w * h for w, h in sizes)
    assert brkga[0] * brkga[1] >= area  # cannot beat the total area
    assert "brkga_fill_ratio" not in shelf[3] and brkga[3]["brkga_fill_ratio"] == pytest.approx(f_brkga)
    assert plan_layout(sizes, "brkga", 1)[:3] == brkga[:3]  # deterministic
