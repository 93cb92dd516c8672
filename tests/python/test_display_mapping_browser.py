"""The browser client's camera response (web/display.glsl.js's DISPLAY_MAPPINGS) against its
Python twin (gigascroll.display_mapping): a ramp of linear radiance and random colours drawn
through the client's GLSL in headless chromium (WebGL2 on SwiftShader) into an 8-bit canvas,
compared code for code with to_srgb8 (within 1 / 255: GLSL float against numpy float32)."""

import base64

import numpy as np
import pytest

import gigascroll as g
from browser import browser, chromium_path, serve_pack  # noqa: F401 - fixtures
from gigascroll.display_mapping import exposure_for_white, to_srgb8

SIDE = 32  # a SIDE x SIDE float texture of radiance, one texel a pixel

DRAW = """async ([values, exposure, tone, side]) => {
  const m = await import('/client/display.glsl.js');
  const canvas = document.createElement('canvas');
  canvas.width = side; canvas.height = side;
  const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true });
  const compile = (type, src) => {
    const s = gl.createShader(type);
    gl.shaderSource(s, src); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  };
  const prog = gl.createProgram();
  gl.attachShader(prog, compile(gl.VERTEX_SHADER, m.HEADER +
    'void main() { vec2 c = vec2(gl_VertexID & 1, gl_VertexID >> 1); gl_Position = vec4(4.0 * c - 1.0, 0.0, 1.0); }'));
  gl.attachShader(prog, compile(gl.FRAGMENT_SHADER, m.HEADER +
    m.displayMapping({ exposure, tone }) +
    'uniform sampler2D uRadiance; out vec4 fragColor;\\n' +
    'void main() { fragColor = vec4(displayMap(texelFetch(uRadiance, ivec2(gl_FragCoord.xy), 0).rgb), 1.0); }'));
  gl.linkProgram(prog);
  if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(prog));
  gl.useProgram(prog);
  const tex = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, tex);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGB32F, side, side, 0, gl.RGB, gl.FLOAT, new Float32Array(values));
  gl.uniform1f(gl.getUniformLocation(prog, 'uExposure'), exposure);
  gl.viewport(0, 0, side, side);
  gl.drawArrays(gl.TRIANGLE_STRIP, 0, 3);
  const px = new Uint8Array(side * side * 4);
  gl.readPixels(0, 0, side, side, gl.RGBA, gl.UNSIGNED_BYTE, px);
  let s = '';
  for (let i = 0; i < px.length; i += 8192) s += String.fromCharCode(...px.subarray(i, i + 8192));
  return btoa(s);
}"""


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    path = tmp_path_factory.mktemp("display_browser") / "p.pack"
    g.build_pack(np.full((64, 64, 3), 128, np.uint8), path, tile_size=32, border=2)
    with serve_pack(path) as url:
        yield url


def radiance_ramp(exposure: float) -> np.ndarray:
    """(SIDE, SIDE, 3) radiance: a grey ramp exposed to 0..8 (the curve's toe, its identity
    range, its knee and its shoulder), then random colours exposed to 0..3 and a few edge
    values (zero, negative)."""
    n = SIDE * SIDE
    grey = np.repeat(np.linspace(0, 8, n // 2)[:, None], 3, axis=1)
    rng = np.random.default_rng(7)
    colours = rng.uniform(0, 3, (n - n // 2, 3)) * rng.uniform(0, 1, (n - n // 2, 1))
    colours[:4] = [[0, 0, 0], [-0.5, 0.2, 0.4], [0.0, 0.0, 5.0], [0.08, 0.8, 0.79]]
    return (np.concatenate([grey, colours]) / exposure).astype(np.float32).reshape(SIDE, SIDE, 3)


@pytest.mark.parametrize("tone", ["neutral", "clip"])
def test_client_glsl_equals_python_curve(browser, server, tone):  # noqa: F811
    exposure = exposure_for_white(200.0)
    radiance = radiance_ramp(exposure)
    page = browser.new_page()
    try:
        page.goto(f"{server}/client/display.glsl.js")
        b64 = page.evaluate(DRAW, [radiance.ravel().tolist(), exposure, f"{tone}-srgb", SIDE])
    finally:
        page.close()
    gpu = np.frombuffer(base64.b64decode(b64), np.uint8).reshape(SIDE, SIDE, 4)[..., :3]
    cpu = to_srgb8(radiance, exposure, tone)
    diff = np.abs(gpu.astype(int) - cpu)
    print(f"{tone}: max {diff.max()} codes, {(diff > 0).mean():.3%} of channels differ")
    assert diff.max() <= 1
    assert len(np.unique(cpu)) > 200  # the ramp spans the codes: the test can tell curves apart
    if tone == "neutral":  # and the two curves differ on it by far more than the tolerance
        assert np.abs(to_srgb8(radiance, exposure, "clip").astype(int) - gpu).max() > 20
