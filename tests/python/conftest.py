"""Fixtures several test files share: a seeded random generator, the small packs they read
(built once per session), the rooms they look at and the command line as a subprocess."""

import shutil
import subprocess
import sys

import numpy as np
import pytest

from gigascroll import build_pack
from gigascroll import views as v
from gigascroll.experiments import pattern_image

SEED = 7

# The small wall painting of the frame-loop and baseline tests: 0.95 m x 12.6 cm at the
# scroll's texel size.
SMALL_W, SMALL_H = 12000, 1600


@pytest.fixture
def rng():
    """A fresh generator with the suite's fixed seed for each test."""
    return np.random.default_rng(SEED)


@pytest.fixture(scope="session")
def _reader_pack(tmp_path_factory):
    img = np.random.default_rng(4).integers(0, 256, (50, 70, 3), dtype=np.uint8)
    path = tmp_path_factory.mktemp("reader") / "p"
    build_pack(img, path, tile_size=16, border=2)
    return path, img


@pytest.fixture
def small_pack(tmp_path, _reader_pack):
    """(path, image): a fresh copy of a 70 x 50 pack with 16-texel tiles (border 2), for tests
    that damage its files."""
    path, img = _reader_pack
    shutil.copytree(path, tmp_path / "p")
    return tmp_path / "p", img


@pytest.fixture(scope="session")
def small_scroll():
    """The SMALL_W x SMALL_H painting on the wall (views.single_scroll)."""
    spec = v.PaintingSpec("small", SMALL_W, SMALL_H, SMALL_W * 12 / 152089,
                          SMALL_H * 12 / 152089)
    return v.single_scroll(spec)


@pytest.fixture(scope="session")
def small_scroll_pack(tmp_path_factory):
    """A pack of the small painting (a synthetic pattern: the loop tests look at tiles, not
    at the picture)."""
    return build_pack(pattern_image(SMALL_W, SMALL_H), tmp_path_factory.mktemp("loop") / "p.pack")


@pytest.fixture(scope="session")
def scroll():
    """The full 12 m scroll on the wall (no pack: for the views' tests)."""
    return v.single_scroll()


@pytest.fixture
def gigascroll_cli():
    """Runs `python -m gigascroll ARGS...` in a subprocess: run(*args, cwd=None)."""
    def run(*args, cwd=None):
        return subprocess.run([sys.executable, "-m", "gigascroll", *map(str, args)],
                              capture_output=True, text=True, cwd=cwd, timeout=300)
    return run
