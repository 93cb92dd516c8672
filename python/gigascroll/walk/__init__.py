"""The walk: frames through the virtual-texturing stack, one after another.

`frame_loop` runs the loop over an exhibition's views (request, load, cache, sample) and
`gallery_walk` over a lit gallery's (the same steps, then the display pass and its light);
`record` writes a walk's frames, figures and video (`video`), `foveation` is the foveated
display, `frame_rates` what a frame rate means.
"""
