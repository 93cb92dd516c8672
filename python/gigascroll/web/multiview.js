// Both eyes in one pass with OVR_multiview2 where the browser has it: the room's programs are
// rebuilt with `layout(num_views = 2)`, gl_ViewID_OVR picking each view's view-projection and
// eye position from uniform arrays, and draw into the two layers of an RGBA8 + DEPTH24 texture
// array at the eyes' viewport size; each layer is then blitted into its eye's viewport of the
// target framebuffer (the XR layer's, or the canvas). It saves the draw calls of the second
// eye (a CPU cost: the GPU still shades both). Views of different sizes, a browser without the
// extension, or ?multiview=0 keep the pass per eye.

const MULTIVIEW_HEADER = `#version 300 es
#extension GL_OVR_multiview2 : require
precision highp float;
precision highp int;
`;

// A shader source of display.glsl.js (written for one view, after HEADER) for two views:
// uViewProj and uEye become gl_ViewID_OVR's entries of uViewProjs[2] and uEyes[2]; the
// vertex shader also declares the view count.
export function multiviewSource(source, header, vertex) {
  if (!source.startsWith(header)) throw new Error('multiview: the shader does not start with HEADER');
  let body = source.slice(header.length);
  body = body.replace('uniform mat4 uViewProj;', 'uniform mat4 uViewProjs[2];\n#define uViewProj uViewProjs[gl_ViewID_OVR]')
             .replace('uniform vec3 uEye;', 'uniform vec3 uEyes[2];\n#define uEye uEyes[gl_ViewID_OVR]');
  return MULTIVIEW_HEADER + (vertex ? 'layout(num_views = 2) in;\n' : '') + body;
}

// Whether a frame's views can go through one multiview pass: two views of the same size.
export function multiviewViews(views) {
  return views.length === 2 && views[0].viewport[2] === views[1].viewport[2] &&
         views[0].viewport[3] === views[1].viewport[3];
}

export class MultiviewTarget {
  // gl: a WebGL2 context whose OVR_multiview2 extension is ext.
  constructor(gl, ext) {
    Object.assign(this, { gl, ext, width: 0, height: 0 });
    this.framebuffer = gl.createFramebuffer();
    this.read = gl.createFramebuffer();
    this.color = this.depth = null;
  }

  // Binds the two-layer target at width x height (made or remade at that size), viewport set.
  bind(width, height) {
    const gl = this.gl;
    if (width !== this.width || height !== this.height) this.#allocate(width, height);
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.framebuffer);
    gl.viewport(0, 0, width, height);
  }

  #allocate(width, height) {
    const gl = this.gl;
    if (this.color) gl.deleteTexture(this.color);
    if (this.depth) gl.deleteTexture(this.depth);
    this.color = layers(gl, gl.RGBA8, width, height);
    this.depth = layers(gl, gl.DEPTH_COMPONENT24, width, height);
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.framebuffer);
    this.ext.framebufferTextureMultiviewOVR(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, this.color, 0, 0, 2);
    this.ext.framebufferTextureMultiviewOVR(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, this.depth, 0, 0, 2);
    const status = gl.checkFramebufferStatus(gl.FRAMEBUFFER);
    if (status !== gl.FRAMEBUFFER_COMPLETE) throw new Error(`multiview target incomplete (0x${status.toString(16)})`);
    Object.assign(this, { width, height });
  }

  // Copies layer k into views[k]'s viewport of framebuffer (null: the canvas), pixel for pixel.
  blit(views, framebuffer) {
    const gl = this.gl, { width: w, height: h } = this;
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, this.read);
    gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, framebuffer);
    views.forEach((v, k) => {
      gl.framebufferTextureLayer(gl.READ_FRAMEBUFFER, gl.COLOR_ATTACHMENT0, this.color, 0, k);
      const [x, y] = v.viewport;
      gl.blitFramebuffer(0, 0, w, h, x, y, x + w, y + h, gl.COLOR_BUFFER_BIT, gl.NEAREST);
    });
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, null);
    gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
  }
}

function layers(gl, format, width, height) {
  const t = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D_ARRAY, t);
  gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, format, width, height, 2);
  for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D_ARRAY, p, gl.NEAREST);
  gl.bindTexture(gl.TEXTURE_2D_ARRAY, null);
  return t;
}
