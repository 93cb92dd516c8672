"""The exported pyramidal TIFF behind a real IIIF server: Debian's iipimage-server (FastCGI)
behind lighttpd on 127.0.0.1, started and stopped by the test. The tiles and regions it
serves over HTTP (IIIF Image API 3.0) match the pack's levels within JPEG's tolerance."""

import io
import json
import shutil
import socket
import subprocess
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from gigascroll import build_pack
from gigascroll.export import export_pack
from gigascroll.pack import read_level

IIPSRV = Path("/usr/lib/iipimage-server/iipsrv.fcgi")
LIGHTTPD = shutil.which("lighttpd") or "/usr/sbin/lighttpd"

pytestmark = pytest.mark.skipif(
    not IIPSRV.is_file() or not Path(LIGHTTPD).is_file(),
    reason="Debian packages iipimage-server and lighttpd are not installed (make deps installs them)")

W, H = 700, 420


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """(base URL, pack): lighttpd + iipsrv serving the exported TIFF as /iiif/scroll.tif."""
    root = tmp_path_factory.mktemp("iiif-server")
    y, x = np.mgrid[0:H, 0:W]
    img = np.stack([x * 255 / (W - 1), y * 255 / (H - 1),
                    128 + 50 * np.sin(x / 41.0) * np.cos(y / 29.0)], -1).astype(np.uint8)
    pack = build_pack(img, root / "p", tile_size=64, border=4)
    (root / "images").mkdir()
    (root / "www").mkdir()
    export_pack(pack.path, root / "images" / "scroll.tif", "tiff", compression="deflate")
    port = free_port()
    conf = root / "lighttpd.conf"
    conf.write_text(f'''
server.modules = ("mod_rewrite", "mod_fastcgi")
server.document-root = "{root / 'www'}"
server.bind = "127.0.0.1"
server.port = {port}
server.errorlog = "{root / 'lighttpd.log'}"
url.rewrite-once = ("^/iiif/(.*)$" => "/fcgi-bin/iipsrv.fcgi?IIIF=$1")
fastcgi.server = ("/fcgi-bin/iipsrv.fcgi" => ((
  "socket" => "{root / 'iipsrv.sock'}",
  "bin-path" => "{IIPSRV}",
  "check-local" => "disable", "min-procs" => 1, "max-procs" => 1,
  "bin-environment" => ("FILESYSTEM_PREFIX" => "{root / 'images'}/", "JPEG_QUALITY" => "95",
                        "LOGFILE" => "{root / 'iipsrv.log'}", "VERBOSITY" => "1",
                        "MAX_CVT" => "5000"))))
''')
    proc = subprocess.Popen([LIGHTTPD, "-D", "-f", str(conf)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    base = f"http://127.0.0.1:{port}/iiif/scroll.tif"
    try:
        deadline = time.monotonic() + 15
        while True:  # bounded: up to 15 s for lighttpd and iipsrv to come up
            if proc.poll() is not None:
                pytest.fail(f"lighttpd exited: {proc.stderr.read().decode()}")
            try:
                with urllib.request.urlopen(base + "/info.json", timeout=2) as r:
                    if r.status == 200:
                        break
            except (urllib.error.URLError, ConnectionError, socket.timeout):
                pass
            if time.monotonic() > deadline:
                log = (root / "lighttpd.log").read_text() if (root / "lighttpd.log").exists() else ""
                pytest.fail(f"the IIIF server did not answer within 15 s: {log[-2000:]}")
            time.sleep(0.2)
        yield base, pack
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def get(url: str) -> bytes:
    with urllib.request.urlopen(url, timeout=10) as r:
        assert r.status == 200, url
        return r.read()


def image(url: str) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(get(url))).convert("RGB"))


def psnr(a, b) -> float:
    e = a.astype(float) - b.astype(float)
    return 10 * np.log10(255.0 ** 2 / max(np.mean(e ** 2), 1e-12))


def test_info_json_describes_the_pyramid(server):
    base, pack = server
    info = json.loads(get(base + "/info.json"))
    # Debian 12's iipsrv 1.1 speaks Image API 2 (version 3 came with iipsrv 1.2); the request
    # syntax used below is common to both.
    assert info["@context"] in ("http://iiif.io/api/image/3/context.json",
                                "http://iiif.io/api/image/2/context.json")
    assert info["protocol"] == "http://iiif.io/api/image"
    assert (info["width"], info["height"]) == (W, H)
    sizes = {(s["width"], s["height"]) for s in info.get("sizes", [])}
    assert set(map(tuple, pack.paintings[0].level_sizes[1:])) <= sizes | {(W, H)}


def test_tiles_and_regions_match_the_pack(server):
    base, pack = server
    level0 = read_level(pack, 0, 0)
    requests = 0
    for (x, y, w, h) in [(0, 0, 256, 256), (256, 0, 256, 256), (512, 256, 188, 164),
                         (100, 50, 333, 222)]:  # tiles of the TIFF and an arbitrary region
        got = image(f"{base}/{x},{y},{w},{h}/max/0/default.jpg")
        requests += 1
        want = level0[y:y + h, x:x + w]
        assert got.shape == want.shape
        assert psnr(got, want) >= 35, (x, y, w, h, psnr(got, want))
    for level in range(1, pack.paintings[0].levels):  # whole reduced levels: the TIFF's IFDs
        w, h = pack.paintings[0].level_sizes[level]
        got = image(f"{base}/full/{w},{h}/0/default.jpg")
        requests += 1
        want = read_level(pack, 0, level)
        assert got.shape == want.shape
        # iipsrv encodes 4:2:0: on the small levels the picture's colour ramps are steep per
        # texel, so chroma subsampling costs a few dB there (luma stays above 40 dB).
        assert psnr(got, want) >= 30, (level, psnr(got, want))
    assert requests <= 16
