"""The browser client's app (python/gigascroll/web/, outside vt/) in headless chromium with WebGL2
on SwiftShader, served by `gigascroll serve PACK --room scroll`, against the C++ core:

- frames: the lit scroll room from fixed poses, both eyes of the side-by-side stereo mode, once
  the view is exact, against the CPU display of the same bake and pose (Gallery.render_display
  with the server's lighting options, then display_mapping's response that scene.json names);
- streaming from a cold cache: no black pixel in any frame, and the frames from the stop (and
  from the last tile's upload) to the exact view, measured on the pixels, are bounded;
- XR through a small fake navigator.xr: two eyes whose disparity matches the IPD, and the
  magnifier toggling on a controller's select.

Canvases stay small (320 x 240 an eye): SwiftShader is CPU emulation.
"""

import base64
import json
import math
from pathlib import Path

import numpy as np
import pytest

import gigascroll as g
from browser import browser, chromium_path, open_page, serve_pack  # noqa: F401 - fixtures
from gigascroll.gallery import Gallery, builtin_room
from gigascroll.display_mapping import to_srgb8

EYE_W, EYE_H = 320, 240
IPD = 0.064
# (eye, target, fov): the room's suggested view from 3 m, an oblique one, and a wide one down
# the room (floor, ceiling, walls and their seams); the close pose of the streaming test.
WIDE = ((10.0, 1.6, -3.8), (4.0, 1.2, 0.0), 75.0)
POSES = [((6.0, 1.6, -3.0), (6.0, 1.5, 0.0), 60.0),
         ((3.0, 1.55, -1.2), (4.5, 1.45, 0.0), 50.0), WIDE]
CLOSE = ((8.0, 1.5, -0.45), (8.0, 1.5, 0.0), 60.0)
FAKE_XR = (Path(__file__).parent / "fake_webxr.js").read_text()


@pytest.fixture(scope="module")
def room_pack(tmp_path_factory):
    """A 6000 x 240 ink landscape (level 0 is 50 x 2 tiles) packed with 128-px tiles."""
    img = g.render_ink_landscape(6000, 240, 0, 240)
    path = tmp_path_factory.mktemp("web_app") / "scroll.pack"
    g.build_pack(img, path, tile_size=128, border=4)
    return path


@pytest.fixture(scope="module")
def server(room_pack, tmp_path_factory):
    """`gigascroll serve PACK --room scroll`'s application (its bake cached in a temporary
    folder)."""
    with serve_pack(room_pack, room="scroll", cache_dir=tmp_path_factory.mktemp("cache")) as url:
        yield url


@pytest.fixture(scope="module")
def cpu_room(room_pack):
    """The CPU gallery lit and baked as the server bakes (the knob's default level for the
    room, ROOM_LIGHTING over it)."""
    from gigascroll.gallery.quality import light_settings
    from gigascroll.serve.room_bake import ROOM_LIGHTING

    pack = g.TilePack(str(room_pack))
    gallery = Gallery.from_room(builtin_room("scroll", pack), pack)
    vt = g.VirtualTexture(pack, (40, 40))
    settings = light_settings(gallery.spec)
    gallery.light(vt, **{**settings.light_options(), **ROOM_LIGHTING})
    gallery.bake(**settings.bake_options())
    return gallery, vt


def open_app(browser, url, query, init_script=None):  # noqa: F811
    page = browser.new_page(viewport={"width": 2 * EYE_W, "height": EYE_H})
    if init_script:
        page.add_init_script(init_script)
    page.errors = []
    page.on("pageerror", lambda e: page.errors.append(str(e)))
    page.goto(f"{url}/?{query}")
    page.wait_for_function("window.gigascroll && window.gigascroll.frame() > 0 || window.gigascroll?.error",
                           timeout=120_000)
    assert page.evaluate("window.gigascroll.error") is None, page.evaluate("window.gigascroll.error")
    return page


def camera_query(eye, target, fov):
    return "camera=" + ",".join(f"{x:g}" for x in (*eye, *target, fov))


def decode(capture) -> np.ndarray:
    """capture()'s canvas as (H, W, 3) uint8, rows from the top (GL's come from the bottom)."""
    a = np.frombuffer(base64.b64decode(capture["pixels"]), np.uint8)
    return a.reshape(capture["height"], capture["width"], 4)[::-1, :, :3]


def cpu_eye(gallery, vt, eye, target, fov, offset):
    """The CPU display of the eye moved `offset` metres along the camera's right vector (the
    core's StereoCamera eyes are parallel): (tone-mapped uint8 frame, painting mask)."""
    centre = gallery.camera((EYE_W, EYE_H), fov=fov, eye=eye, target=target)
    shift = np.array(centre.right) * offset
    cam = gallery.camera((EYE_W, EYE_H), fov=fov, eye=tuple(np.array(eye) + shift),
                         target=tuple(np.array(target) + shift))
    gallery.stream(cam, vt)
    linear, hits = gallery.render_display(cam, vt, lighting="baked", hits=True)
    return linear, hits["slot"] >= 0


def psnr(a, b, mask=None) -> float:
    d = (a.astype(np.float64) - b.astype(np.float64)) ** 2
    mse = d[mask].mean() if mask is not None else d.mean()
    return math.inf if mse == 0 else 10 * math.log10(255 ** 2 / mse)


def wait_exact(page, timeout_s=180):
    """Until the stats panel confirms the view exact (stats.js); on a timeout the panel's
    numbers are in the message."""
    try:
        page.wait_for_function("window.gigascroll.stats().exact === true", timeout=timeout_s * 1000,
                               polling=100)
    except Exception as e:
        raise AssertionError(f"not exact after {timeout_s} s: {page.evaluate('window.gigascroll.stats()')}") from e


@pytest.mark.parametrize("pose", range(len(POSES)))
def test_frames_equal_cpu_display(browser, server, cpu_room, pose):  # noqa: F811
    """Both eyes of a fixed pose, once exact, against the CPU display of the same bake.

    Where they may differ: at silhouettes (a pixel centre within float rounding of a painting's
    or a wall's edge is rasterised on one side and ray cast on the other), in the level of
    detail (GPU derivatives over 2 x 2 quads against the core's ray differentials: the same
    value for a plane up to rounding), in the sRGB curve (GLSL pow against std::pow) and in
    the light's interpolation (the rasteriser's perspective-correct barycentrics against
    Embree's, both over the same lattice sub-triangle): each a few 1/255 at most."""
    eye, target, fov = POSES[pose]
    gallery, vt = cpu_room
    page = open_app(browser, server, f"{camera_query(eye, target, fov)}&stereo=1&ipd={IPD}"
                                     f"&size={2 * EYE_W}x{EYE_H}")
    try:
        wait_exact(page)
        frame = decode(page.evaluate("window.gigascroll.capture()"))
        display = page.evaluate("window.gigascroll.app.scene.display")
        drawn, meshes = page.evaluate("[window.gigascroll.app.room.drawn, window.gigascroll.app.room.meshes.length]")
    finally:
        page.close()
    if pose == 0:  # facing the scroll, the wall behind the eye is culled (room_draw.js)
        assert drawn < meshes, (drawn, meshes)
    for k, offset in enumerate((-IPD / 2, IPD / 2)):
        linear, mask = cpu_eye(gallery, vt, eye, target, fov, offset)
        cpu = to_srgb8(linear, display["exposure"], display["tone"].removesuffix("-srgb"))
        gpu = frame[:, k * EYE_W:(k + 1) * EYE_W]
        assert mask.sum() > 0.02 * mask.size, "the pose must show the painting"
        whole, paintings = psnr(gpu, cpu), psnr(gpu, cpu, mask)
        print(f"pose {pose} eye {k}: PSNR {whole:.1f} dB frame, {paintings:.1f} dB paintings")
        assert paintings >= 35 and whole >= 30, (pose, k, whole, paintings)


STREAM_PROBE = """() => {
  const app = window.gigascroll.app;
  window.streamLog = [];
  app.afterFrame = ({frame, gl, canvas}) => {
    const w = canvas.width, h = canvas.height, px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let black = 0, hash = 2166136261;
    for (let i = 0; i < px.length; i += 4) {
      if (px[i] === 0 && px[i + 1] === 0 && px[i + 2] === 0) ++black;
      hash = Math.imul(hash ^ (px[i] | px[i + 1] << 8 | px[i + 2] << 16), 16777619) >>> 0;
    }
    const s = app.vt.stats();
    window.streamLog.push({frame, black, hash, uploads: s.uploads, inFlight: s.inFlight});
  };
}"""


def test_streaming_cold_cache(browser, server):  # noqa: F811
    """From a cold cache (only the coarse tails resident) the page draws a wide view of the room
    (its surfaces' seams: crack_fill.js), then
    the camera stops close to the scroll (level-0 tiles), then at another close pose with the
    magnifier on. Every frame is read back: no pixel is black (the tail answers every lookup);
    after each stop the image becomes final within a bounded number of frames of the stop and
    of the last tile's upload (VT-mobile-VR Table 2: 4-5 frames from stop to exact on the
    headset), and the stats panel's figure agrees with the pixels'."""
    page = open_app(browser, server, f"{camera_query(*WIDE)}&size={EYE_W}x{EYE_H}")
    try:
        page.evaluate(STREAM_PROBE)
        for k, (x, magnifier) in enumerate(((CLOSE[0][0], False), (CLOSE[0][0] - 2.5, True))):
            eye, target = (x, *CLOSE[0][1:]), (x, *CLOSE[1][1:])
            stop = page.evaluate("""([eye, target, fov, lens]) => {
              const app = window.gigascroll.app;
              app.setCamera(eye, target, fov);
              app.magnifier.toggle(lens);
              return app.frame; }""", [eye, target, CLOSE[2], magnifier])
            wait_exact(page)
            page.wait_for_function(f"window.gigascroll.frame() > {stop} + 3 + "
                                   "window.gigascroll.stats().framesStopToConfirmed")
            log = [f for f in page.evaluate("window.streamLog") if f["frame"] >= stop]
            panel = page.evaluate("window.gigascroll.stats()")
            check_stop(log, stop, panel, f"stop {k} (magnifier {'on' if magnifier else 'off'})")
        everything = page.evaluate("window.streamLog")
    finally:
        page.close()
    assert all(f["black"] == 0 for f in everything), [(f["frame"], f["black"]) for f in everything if f["black"]]


def check_stop(log, stop, panel, what):
    """The frames after a stop: the first frame from which the image stays final, against the
    stop and the last upload, and the panel's stop-to-exact count."""
    final = log[-1]["hash"]
    exact = next(f["frame"] for k, f in enumerate(log) if all(x["hash"] == final for x in log[k:]))
    uploads = [f for f in log if f["uploads"] > 0]
    assert uploads, f"{what}: the close view must stream level-0 tiles"
    last_upload = uploads[-1]["frame"]
    tiles = sum(f["uploads"] for f in uploads)
    print(f"{what}: {tiles} tiles uploaded in {len(uploads)} frames, the last {last_upload - stop} "
          f"frames after the stop; exact {exact - stop} frames after the stop, {exact - last_upload} "
          f"after the last upload; panel {panel['framesStopToExact']} (confirmed after "
          f"{panel['framesStopToConfirmed']})")
    assert exact - last_upload <= 8, what
    # At most 16 requests a frame: the stop's readback (a few frames), the fetches and the
    # uploads of `tiles` tiles bound the latency.
    assert exact - stop <= 8 + math.ceil(tiles / 16), what
    # The panel counts to the last upload (the frame whose draw has every tile); the pixels may
    # settle a frame earlier when the last upload changed no visible pixel.
    assert 0 <= panel["framesStopToExact"] - (exact - stop) <= 1 or exact == stop, what


def test_xr_eyes_disparity_and_magnifier(browser, server):  # noqa: F811
    """An immersive session through the fake device: the XR loop draws both eyes (the desktop
    loop stops), a painting's features shift between the eyes by the IPD's projection at the
    painting's depth (within a pixel), and a controller's select toggles the magnifier's inset
    in both eyes and back."""
    page = open_app(browser, server, f"size={2 * EYE_W}x{EYE_H}", init_script=FAKE_XR)
    try:
        page.wait_for_selector("#enter-vr:not([hidden])", timeout=30_000)
        page.click("#enter-vr")
        page.wait_for_function("window.fakeXr.framesServed > 2 && window.gigascroll.app.xr.frames > 2")
        wait_exact(page)
        counts = page.evaluate("""async () => {
          // Three XR frames (however slow the emulation), then both counts at one instant.
          const app = window.gigascroll.app, f0 = app.frame, x0 = app.xr.frames;
          const t0 = performance.now();
          while (app.xr.frames - x0 < 3 && performance.now() - t0 < 25000) {
            await new Promise((r) => setTimeout(r, 20));
          }
          return [app.frame - f0, app.xr.frames - x0];
        }""")
        plain = decode(page.evaluate("window.gigascroll.capture()"))
        page.evaluate("window.fakeXr.select()")
        page.wait_for_function("window.gigascroll.app.magnifier.on === true")
        lens = decode(page.evaluate("window.gigascroll.capture()"))  # exact or not: the inset is there
        page.evaluate("window.fakeXr.select()")
        page.wait_for_function("window.gigascroll.app.magnifier.on === false")
        again = decode(page.evaluate("window.gigascroll.capture()"))
        scene = page.evaluate("window.gigascroll.app.scene")
        page.evaluate("window.fakeXr.session.end()")  # the headset's own exit
        page.wait_for_function("document.getElementById('enter-vr').textContent === 'Enter VR'"
                               " && window.gigascroll.app.xr.session === null")
        resumed = page.evaluate("window.gigascroll.frame()")
        page.wait_for_function(f"window.gigascroll.frame() > {resumed} + 2")  # the desktop loop again
    finally:
        page.close()
    assert counts[0] == counts[1] > 0, f"frames drawn {counts[0]}, XR frames {counts[1]}: only the XR loop draws"
    left, right = plain[:, :EYE_W].astype(float), plain[:, EYE_W:].astype(float)
    # The fake's head is at the XR origin 1.5 m above the floor, placed at the room's suggested
    # eye, facing its target (+z): the painting plane's depth is its z minus the eye's.
    depth = scene["room"]["slots"][0]["origin"][2] - scene["room"]["camera"]["eye"][2]
    tan_half_x = math.tan(math.radians(30)) * EYE_W / EYE_H
    expected = IPD / depth * (EYE_W / 2) / tan_half_x
    rows = painting_rows(left)
    shift = horizontal_shift(left[rows].mean(axis=2), right[rows].mean(axis=2))
    print(f"disparity {shift:.2f} px, IPD at {depth:.3f} m projects to {expected:.2f} px")
    assert abs(shift - expected) <= 1.0
    # The inset: the lower-right square of each eye changed, the rest did not; off again
    # restores the frame.
    changed = np.any(lens != plain, axis=2)
    for k in range(2):
        eye = changed[:, k * EYE_W:(k + 1) * EYE_W]
        assert eye[EYE_H // 2:, EYE_W // 2:].mean() > 0.3 and eye[:EYE_H // 3, :EYE_W // 3].mean() == 0
    assert np.array_equal(again, plain)
    # The inset sits at INSET_DISTANCE (0.5 m) in stereo: its dark rim's left edge is further
    # right in the left eye by the IPD's projection at that distance.
    rims = [inset_left_edge(lens[:, k * EYE_W:(k + 1) * EYE_W]) for k in range(2)]
    assert abs((rims[0] - rims[1]) - IPD / 0.5 * (EYE_W / 2) / tan_half_x) <= 1.0, rims


def inset_left_edge(eye: np.ndarray) -> int:
    """The column of the magnifier inset's left rim (blit shader: grey 0.08, code 20): the
    first column holding a long vertical run of it."""
    rim = np.all(eye == 20, axis=2)
    return int(np.flatnonzero(rim.sum(axis=0) > eye.shape[0] // 4)[0])


def painting_rows(eye: np.ndarray) -> slice:
    """The rows of an eye image that hold the scroll: the band of highest column-wise detail."""
    detail = np.abs(np.diff(eye.mean(axis=2), axis=1)).mean(axis=1)
    rows = np.flatnonzero(detail > 0.5 * detail.max())
    return slice(rows.min(), rows.max() + 1)


def horizontal_shift(a: np.ndarray, b: np.ndarray, max_shift: int = 20) -> float:
    """The x shift s (pixels, sub-pixel by a parabola through the peak) with a(x) ~ b(x - s),
    by normalised cross-correlation of the two bands' high-passed rows."""
    a = a - a.mean(axis=1, keepdims=True)
    b = b - b.mean(axis=1, keepdims=True)
    w = a.shape[1]
    scores = []
    for s in range(-max_shift, max_shift + 1):
        x0, x1 = max(0, s), min(w, w + s)
        pa, pb = a[:, x0:x1], b[:, x0 - s:x1 - s]
        scores.append((pa * pb).sum() / math.sqrt((pa * pa).sum() * (pb * pb).sum()))
    k = int(np.argmax(scores))
    if 0 < k < len(scores) - 1:
        y0, y1, y2 = scores[k - 1:k + 2]
        return k - max_shift + 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
    return float(k - max_shift)
