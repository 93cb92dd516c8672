"""`gigascroll view` as a person uses it: under a virtual X server (Xvfb, started here), the
window opens, key presses (xdotool, real XTEST events) walk and toggle, and the frames read
back from the window show that the view moved and the painting sharpened."""

import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest

pytestmark = pytest.mark.skipif(shutil.which("Xvfb") is None or shutil.which("xdotool") is None,
                                reason="Xvfb and xdotool (Debian xvfb, xdotool) are not installed")


@pytest.fixture
def display():
    for n in range(140, 200):
        if not os.path.exists(f"/tmp/.X11-unix/X{n}") and not os.path.exists(f"/tmp/.X{n}-lock"):
            break
    server = subprocess.Popen(["Xvfb", f":{n}", "-screen", "0", "800x600x24", "-nolisten", "tcp"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    env = dict(os.environ, DISPLAY=f":{n}")
    for _ in range(100):
        if subprocess.run(["xdotool", "getdisplaygeometry"], env=env,
                          capture_output=True).returncode == 0:
            break
        time.sleep(0.1)
    else:
        server.kill()
        pytest.skip("Xvfb did not start")
    yield env
    server.kill()
    server.wait()


def sharpness(img):
    """Mean absolute Laplacian of the luminance: grows as finer tiles arrive."""
    g = img[..., :3].astype(np.float64).mean(axis=2)
    lap = 4 * g[1:-1, 1:-1] - g[:-2, 1:-1] - g[2:, 1:-1] - g[1:-1, :-2] - g[1:-1, 2:]
    return float(np.abs(lap).mean())


def read(path):
    import OpenImageIO as oiio
    for _ in range(200):
        if path.exists() and path.stat().st_size > 0:
            time.sleep(0.2)
            return oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8)[..., :3]
        time.sleep(0.1)
    raise AssertionError(f"no screenshot {path}")


def run_view(env, pack, tmp_path, options, actions):
    """Runs `gigascroll view PACK` in a 384 x 256 window with `options`, focuses it and calls
    actions(key, shot): key(*xdotool args) sends input, shot() saves the window's frame (P)
    and returns it as uint8 RGB. Then Esc; returns (what actions returned, stdout)."""
    app = subprocess.Popen(
        [sys.executable, "-m", "gigascroll", "view", str(pack.path), "--window", "384x256",
         "--lighting", "unlit", *options, "--screenshot", str(tmp_path / "shot-{n}.png"),
         "--quit-after", "120"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    shots = []
    try:
        # --onlyvisible: the window is mapped, else XSetInputFocus fails (BadMatch) and the
        # keys go nowhere; focusing is retried until it succeeds (a loaded machine maps late).
        wid = subprocess.run(["xdotool", "search", "--sync", "--onlyvisible", "--name", "gigascroll view"],
                             env=env, capture_output=True, text=True, timeout=120).stdout.split()[0]
        for _ in range(60):
            if subprocess.run(["xdotool", "windowfocus", "--sync", wid], env=env, timeout=30,
                              capture_output=True).returncode == 0:
                break
            time.sleep(0.5)

        def key(*args):
            subprocess.run(["xdotool", *args], env=env, check=True, timeout=30)

        def shot():
            key("key", "p")
            shots.append(read(tmp_path / f"shot-{len(shots)}.png"))
            return shots[-1]
        def settled(limit=90.0):
            """Frames until two in a row are equal below the overlay (every tile the view asks
            for resident), at most `limit` seconds: waits as long as a loaded machine needs
            instead of a fixed sleep."""
            below_overlay = slice(96, None)  # the overlay (rows 10-88) changes every frame
            last, t0 = shot(), time.monotonic()
            while time.monotonic() - t0 < limit:
                time.sleep(1.0)
                now = shot()
                if np.array_equal(now[below_overlay], last[below_overlay]):
                    return now
                last = now
            return last
        key.settled = settled
        result = actions(key, shot)
        key("key", "Escape")
        out, err = app.communicate(timeout=60)
    finally:
        if app.poll() is None:
            app.kill()
    assert app.returncode == 0, err
    return result, out


def test_window_walks_and_sharpens(display, tmp_path, small_scroll_pack):
    def walk(key, shot):
        first = shot()
        # Step back from the painting for half a second: the view moves.
        key("keydown", "s")
        time.sleep(0.5)
        key("keyup", "s")
        moved = shot()
        later = key.settled()  # standing still: the loader streams the finer tiles in
        key("key", "m")        # the magnifier off
        time.sleep(1)
        return first, moved, later, shot()
    (first, moved, later, no_lens), out = run_view(
        display, small_scroll_pack, tmp_path, ["--per-frame", "1", "--target-fps", "2"], walk)
    assert first.shape == moved.shape == (256, 384, 3)
    assert np.abs(first.astype(int) - moved).mean() > 2       # the view moved
    # The first frame shows the pinned coarse tiles; one tile a frame later it is sharp. The
    # region: the left eye's lower left, away from the overlay, the lens and the inset.
    region = (slice(150, 256), slice(0, 110))
    assert sharpness(later[region]) > 1.3 * sharpness(first[region])
    assert np.abs(later.astype(int) - no_lens).mean() > 1      # M toggled the magnifier
    assert "frames" in out


def test_view_without_a_display_says_so(gigascroll_cli, small_scroll_pack, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    r = gigascroll_cli("view", small_scroll_pack.path)
    assert r.returncode == 2
    assert "display" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_window_toggles_the_foveation(display, tmp_path, small_scroll_pack):
    """--fovea starts the window foveated; V switches it off. Standing still with every tile
    resident, the fovea's pixels are the unfoveated eye's (a centred crop of the same pinhole
    image) while the periphery, traced at 1/4 density and requested two levels coarser,
    differs; the rays traced per frame drop to the layout's count."""
    from gigascroll import views as v
    from gigascroll.walk.foveation import Foveation
    from gigascroll.views.exhibition import Headset

    def toggle(key, shot):
        key("key", "m")        # the magnifier off: its lens would cover the fovea
        foveated = key.settled()  # standing still: every tile the frame asks for streams in
        key("key", "v")        # the foveation off: the periphery's finer tiles stream in
        return foveated, key.settled()
    (foveated, full), out = run_view(
        display, small_scroll_pack, tmp_path,
        ["--target-fps", "0.1", "--fovea", "40", "--fovea-factor", "4"], toggle)
    # The left eye (192 x 256): its fovea's inner pixels (the fovea alone) and its periphery
    # outside the fovea's rectangle, below the overlay.
    hs = Headset(width=192, height=256)
    lay = Foveation(40.0, 4).layout(v.Camera((0, 0, 0), (0, 0, -1), (0, 1, 0), hs.tan_half_x,
                                             hs.tan_half_y, 192, 256))
    band = int(np.ceil(0.25 * min(lay.fovea_width, lay.fovea_height) / 2))
    ys = slice(lay.y0 + band, lay.y0 + lay.fovea_height - band)  # centred: either way up
    xs = slice(lay.x0 + band, lay.x0 + lay.fovea_width - band)
    centre_f, centre_u = foveated[ys, xs].astype(int), full[ys, xs].astype(int)
    assert centre_f.size > 30 * 30 * 3
    assert np.abs(centre_f - centre_u).max() <= 1, "the fovea is the unfoveated eye's image"
    periphery = (slice(60, 256), slice(0, lay.x0 - 2))
    assert np.abs(foveated[periphery].astype(int) - full[periphery]).mean() > 2
    # The rays: the first frame foveated, then off after V. The foveated left eye traces
    # the fovea's and the periphery's pixels, the right eye at most as many.
    lines = [ln for ln in out.splitlines() if ln.startswith("foveation")]
    assert lines[0].startswith("foveation on") and lines[1].startswith("foveation off"), out
    on_rays, off_rays = (int(ln.split(", ")[1].split()[0]) for ln in lines[:2])
    foveated_left = lay.fovea_width * lay.fovea_height + (192 // 4) * (256 // 4)
    assert foveated_left <= on_rays <= 2 * foveated_left
    assert 192 * 256 <= off_rays <= 2 * 192 * 256
    assert "foveation off" in out.splitlines()[-1]
