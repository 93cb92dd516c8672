// GLSL ES 3.00 of the app's feedback pass (tile determination): a painting's fragment writes
// the virtual texture's request for its (painting, uv) (vtFeedbackOut comes from vt.glsl, after
// HEADER); room surfaces draw with the colour mask off, so they only hide the paintings behind
// them, as the core's feedback rays stop at the first surface.

export const FEEDBACK_FS = `
uniform int uPainting;
in vec2 vUv;
out vec4 fragColor;
void main() {
  fragColor = vtFeedbackOut(uPainting, vUv);
}
`;
