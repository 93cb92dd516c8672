"""The browser client's figures over a walk of the scroll room (`gigascroll bench web`'s client
part): tiles uploaded a frame, bytes a second, hit rate, and frames from the stop to the exact
view, in headless chromium (WebGL2 on SwiftShader) against `gigascroll serve`'s application
(on a thread of this process).

The walk is VT-mobile-VR Table 2's: the main camera 40 cm from the scroll, the magnifier on, moving
left to right at 1 m/s, counted in frames of a 90 Hz headset (1/90 m a frame, whatever the
emulated frame rate), then a stop; the client's own stats panel gives the frames from the stop
to the exact view (stats.js). Frame times on SwiftShader are CPU emulation: they are reported
only relative to the same page's frames standing still (`frame_time_walk_to_still`). The
client's GPU frame time (stats().gpuMs, EXT_disjoint_timer_query_webgl2's median over the
last 30 frames, at the stop) is kept as `gpu_ms_emulated` and printed relative to the still
frame time: on SwiftShader that "GPU" is CPU emulation too; on a machine with a GPU it is the
GPU's own time."""

from __future__ import annotations

import json
import shutil
import statistics
import tempfile
import urllib.request
from pathlib import Path

HEADSET_HZ = 90.0
SPEED = 1.0            # m/s, the paper's
DISTANCE = 0.40        # m from the painting plane, the paper's main camera
CHROMIUM_ARGS = ["--headless=new", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                 "--no-sandbox", "--ignore-gpu-blocklist"]

# Runs in the page: walks `frames` frames from x0 at `step` metres a frame, stops, and resolves
# with the per-frame log once the stats panel confirms the stop's exact view (or `settle`
# frames after the stop).
WALK_JS = """(cfg) => new Promise((resolve) => {
  const app = window.gigascroll.app, log = [];
  app.magnifier.toggle(cfg.magnifier);
  let k = 0;
  const pose = (i) => { const x = cfg.x0 + i * cfg.step;
                        app.setCamera([x, cfg.y, cfg.z], [x, cfg.y, cfg.tz], cfg.fov); };
  pose(0);
  app.afterFrame = ({frame}) => {
    const s = app.vt.stats(), n = app.stats.numbers;
    log.push({frame, t: performance.now(), uploads: s.uploads, bytes: s.bytesReceived,
              requests: s.requests, commands: s.commands, hits: Math.round(s.hitRate * s.requests),
              inFlight: s.inFlight, readbacks: s.readbacks});
    k++;
    if (k < cfg.frames) pose(k);
    else if ((k > cfg.frames + 1 && n.exact && n.stopFrame >= log[cfg.frames - 1].frame) || k > cfg.frames + cfg.settle) {
      app.afterFrame = null;
      resolve({log, stats: n, walked: cfg.frames});
    }
  };
})"""


def _summary(result: dict, seconds_still: float) -> dict:
    """The walk's figures from the page's per-frame log."""
    log, walked = result["log"], result["walked"]
    walk = log[:walked]
    uploads = [f["uploads"] for f in walk]
    # The request figures are the last processed readback's: counted once, in the frame that
    # processed it (readbacks grew), not again in frames that processed none.
    fresh = [f for prev, f in zip([None] + walk, walk)
             if prev is None or f.get("readbacks", 0) != prev.get("readbacks", 0)]
    requests = sum(f["requests"] for f in fresh)
    wall = (walk[-1]["t"] - walk[0]["t"]) / 1000
    nbytes = walk[-1]["bytes"] - walk[0]["bytes"]
    frame_ms = statistics.median(b["t"] - a["t"] for a, b in zip(walk, walk[1:]))
    return {
        "frames": walked,
        "tiles_uploaded_per_frame": statistics.fmean(uploads),
        "tiles_uploaded_per_frame_max": max(uploads),
        "bytes_per_frame": nbytes / max(1, walked - 1),
        "bytes_per_s_at_90hz": nbytes / max(1, walked - 1) * HEADSET_HZ,
        "bytes_per_s_emulated": nbytes / wall if wall > 0 else 0.0,
        "hit_rate": sum(f["hits"] for f in fresh) / requests if requests else 1.0,
        "requests_per_readback": requests / len(fresh),
        "readbacks": len(fresh),
        "frames_stop_to_exact": result["stats"].get("framesStopToExact"),
        "frames_stop_to_confirmed": result["stats"].get("framesStopToConfirmed"),
        "exact_reached": bool(result["stats"].get("exact")),
        "frame_time_walk_to_still": frame_ms / seconds_still if seconds_still > 0 else None,
        "gpu_ms_emulated": result["stats"].get("gpuMs"),
    }


def _still_frame_ms(page, frames: int = 30) -> float:
    """Median frame time of the page standing still (the relative frame time's baseline)."""
    return page.evaluate("""(n) => new Promise((resolve) => {
      const app = window.gigascroll.app, t = [];
      app.afterFrame = () => { t.push(performance.now());
        if (t.length > n) { app.afterFrame = null;
          const d = t.slice(1).map((x, i) => x - t[i]).sort((a, b) => a - b);
          resolve(d[d.length >> 1]); } };
    })""", frames)


def walk_figures(width: int = 24000, height: int = 1000, size=(480, 270), metres: float = 2.0,
                 magnifier: bool = True, chromium: str | None = None) -> dict:
    """Packs the ink landscape (width x height), serves it in the scroll room, and walks
    `metres` of it in chromium at `size`; returns the figures (see the module docstring)."""
    from playwright.sync_api import sync_playwright

    from .. import build_pack, render_ink_landscape
    from ..serve import ServerThread, baked_room, make_app, pack_hash

    chromium = chromium or shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        raise RuntimeError("chromium not found (the Makefile installs Debian's chromium)")
    with tempfile.TemporaryDirectory(prefix="gigascroll-bench-web-walk-") as tmp:
        tmp = Path(tmp)
        pack = build_pack(render_ink_landscape(width, height, 0, height), tmp / "p.pack")
        content_hash = pack_hash(pack)
        room = baked_room("scroll", pack, content_hash, tmp / "cache")
        with ServerThread(make_app(pack, room, content_hash)) as url:
            url = url.rstrip("/")
            with urllib.request.urlopen(f"{url}/api/scene.json", timeout=60) as r:
                scene = json.loads(r.read())
            with sync_playwright() as p:
                browser = p.chromium.launch(executable_path=chromium, headless=True, args=CHROMIUM_ARGS)
                try:
                    result, still = _walk(browser, url, scene, size, metres, magnifier)
                finally:
                    browser.close()
    figures = _summary(result, still)
    figures.update({"painting": f"{width}x{height}", "canvas": f"{size[0]}x{size[1]}",
                    "metres": metres, "magnifier": magnifier, "still_frame_ms_emulated": still})
    return figures


def _walk(browser, url, scene, size, metres, magnifier):
    slot = scene["room"]["slots"][0]
    z = slot["origin"][2]
    y = slot["origin"][1] + 0.5 * slot["v_axis"][1] * slot["height_m"]
    page = browser.new_page(viewport={"width": size[0], "height": size[1]})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    eye = (1.0, y, z - DISTANCE)
    page.goto(f"{url}/?camera={eye[0]},{eye[1]},{eye[2]},{eye[0]},{eye[1]},{z},60&size={size[0]}x{size[1]}")
    try:
        page.wait_for_function("window.gigascroll && (window.gigascroll.frame() > 0 || window.gigascroll.error)",
                               timeout=300_000)
    except Exception as e:
        raise RuntimeError(f"the client did not start: {errors[:3]}") from e
    if page.evaluate("window.gigascroll.error"):
        raise RuntimeError(page.evaluate("window.gigascroll.error"))
    still = _still_frame_ms(page)
    cfg = {"x0": eye[0], "y": y, "z": eye[2], "tz": z, "fov": 60, "magnifier": magnifier,
           "step": SPEED / HEADSET_HZ, "frames": int(round(metres / SPEED * HEADSET_HZ)), "settle": 300}
    result = page.evaluate(WALK_JS, cfg)
    still = (still + _still_frame_ms(page)) / 2  # before and after the walk: the host's load drifts
    page.close()
    return result, still


def walk_text(f: dict) -> str:
    """The figures as one line."""
    return (f"client walk ({f['painting']}, {f['canvas']}, {f['metres']} m at 1 m/s in 90 Hz frames, "
            f"magnifier {'on' if f['magnifier'] else 'off'}): {f['tiles_uploaded_per_frame']:.2f} tiles "
            f"uploaded a frame (max {f['tiles_uploaded_per_frame_max']}), "
            f"{f['bytes_per_s_at_90hz'] / 1e6:.2f} MB/s at 90 Hz, hit rate {100 * f['hit_rate']:.1f} %, "
            f"stop -> exact {f['frames_stop_to_exact']} frames (confirmed after "
            f"{f['frames_stop_to_confirmed']}); SwiftShader walk / still frame time "
            f"{f['frame_time_walk_to_still']:.2f}; GPU time (timer query) / still frame time "
            f"{_gpu_share(f)} (SwiftShader's GPU is CPU emulation: relative only)")


def _gpu_share(f: dict) -> str:
    """gpuMs at the stop over the still frame's wall time, or '-' without a timer query."""
    gpu, still = f.get("gpu_ms_emulated"), f.get("still_frame_ms_emulated")
    return "-" if gpu is None or not still else f"{gpu / still:.2f}"
