"""The Python examples of the README and of docs/*.md run as written.

Each fenced ```python block right after a `<!-- test: NAME -->` comment (in README.md or any
page of docs/) runs in a fresh
namespace, in a directory holding what the examples open: `a.tif` (a random RGB image) and
`scroll.pack` (a pack of one random 1500 x 480 painting). After a block has run, its names are
checked against independent references where the example computes something checkable (the
pack example's tile against the source image's texels). Every ```python block of these pages
must be marked, and no indented block may look like runnable gigascroll code, so an example
cannot silently fall out of this test."""

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import gigascroll

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
MARKED = re.compile(r"<!-- test: (\w+) -->\n```python\n(.*?)\n```", re.S)
FENCED = re.compile(r"^```python$", re.M)
EXPECTED = {"pack", "runtime", "views", "photon", "rooms", "gallery"}


def readme_blocks() -> dict[str, tuple[str, str]]:
    """NAME -> ("page:line", code) over the README and docs/*.md."""
    blocks = {}
    for page in PAGES:
        text = page.read_text()
        for m in MARKED.finditer(text):
            line = text.count("\n", 0, m.start(2)) + 1
            assert m.group(1) not in blocks, f"two blocks named {m.group(1)}"
            blocks[m.group(1)] = (f"{page.relative_to(ROOT)}:{line}", m.group(2))
    return blocks


def test_every_python_block_is_marked():
    assert set(readme_blocks()) == EXPECTED
    for page in PAGES:
        text = page.read_text()
        assert len(FENCED.findall(text)) == len(MARKED.findall(text)), page.name
        # An indented (unfenced) block starting with a gigascroll import would be an example
        # that this test does not run.
        for m in re.finditer(r"(?:\A|\n\n)((?: {4}.*\n)+)", text):
            first = m.group(1).lstrip().splitlines()[0]
            assert not re.match(r"(import|from) gigascroll", first), (page.name, first)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """a.tif and scroll.pack, made once; each test copies them into its own directory."""
    import OpenImageIO as oiio
    d = tmp_path_factory.mktemp("readme-inputs")
    rng = np.random.default_rng(2024)
    a = rng.integers(0, 256, (300, 400, 3), np.uint8)
    out = oiio.ImageOutput.create(str(d / "a.tif"))
    out.open(str(d / "a.tif"), oiio.ImageSpec(400, 300, 3, oiio.UINT8))
    out.write_image(a)
    out.close()
    gigascroll.build_pack([rng.integers(0, 256, (480, 1500, 3), np.uint8)], d / "scroll.pack")
    return d, a


@pytest.fixture
def workdir(inputs, tmp_path, monkeypatch):
    src, _ = inputs
    shutil.copy(src / "a.tif", tmp_path / "a.tif")
    shutil.copytree(src / "scroll.pack", tmp_path / "scroll.pack")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def run_block(name: str) -> dict:
    where, code = readme_blocks()[name]
    ns = {"__name__": f"readme_{name}"}
    exec(compile(code, where, "exec"), ns)  # noqa: S102 (the docs' own code)
    return ns


def expected_tile(img: np.ndarray, level0_tile: tuple[int, int], tile: int, border: int):
    """Level-0 tile (tx, ty) of img by the README's geometry: texels [tx P - border, tx P + P +
    border) per axis, clamped to the nearest real texel."""
    payload = tile - 2 * border
    tx, ty = level0_tile
    xs = np.clip(np.arange(tx * payload - border, tx * payload - border + tile), 0, img.shape[1] - 1)
    ys = np.clip(np.arange(ty * payload - border, ty * payload - border + tile), 0, img.shape[0] - 1)
    return img[np.ix_(ys, xs)]


def test_pack_example(workdir, inputs):
    ns = run_block("pack")
    pack, p, tile, out = ns["pack"], ns["p"], ns["tile"], ns["out"]
    assert p.name == pack.paintings[0].name and (p.width, p.height) == (400, 300)
    np.testing.assert_array_equal(tile, expected_tile(inputs[1], (ns["tx"], ns["ty"]), 128, 4))
    np.testing.assert_array_equal(out, tile)
    assert pack.has_tile(p, ns["level"], ns["tx"], ns["ty"])
    assert (workdir / "gallery.pack" / "manifest.json").is_file()


def test_runtime_example(workdir, capsys):
    ns = run_block("runtime")
    assert ns["rgb"].shape == (5, 3) and ns["rgb"].dtype == np.float32
    assert np.isfinite(ns["rgb"]).all() and ns["rgb"].min() >= 0 and ns["rgb"].max() <= 255
    assert ns["level"].shape == (5,) and (ns["level"] >= 0).all()
    assert "resident" in capsys.readouterr().out


def test_views_example(workdir):
    ns = run_block("views")
    sets = ns["sets"]
    assert len(ns["buffers"]) == 3
    for key in ("requests", "responses", "commands"):
        assert sets[key].dtype == np.uint64
    assert sets["requests"].size > 0


def test_photon_example(workdir):
    ns = run_block("photon")
    img = ns["img"]
    assert img.shape == (256, 256, 3) and np.isfinite(img).all() and img.mean() > 0
    assert (workdir / "cornell.exr").stat().st_size > 0


def test_rooms_example(workdir):
    ns = run_block("rooms")
    assert len(ns["spec"].paintings) == 5  # five copies of scroll.pack's one painting


def test_gallery_example(workdir):
    ns = run_block("gallery")
    image, hits = ns["image"], ns["hits"]
    assert image.shape == (240, 320, 3) and np.isfinite(image).all()
    # The suggested view shows the painting, and both baked paths agree (the oracle).
    assert (hits["slot"] == 0).mean() > 0.05
    baked = ns["gallery"].render_display(ns["camera"], ns["vt"], lighting="baked")
    np.testing.assert_allclose(baked, ns["ref"], rtol=1e-3, atol=1e-5)
