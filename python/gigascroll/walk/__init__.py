"""The walk: frames through the virtual-texturing stack, one after another.

`loop` is the frame loop (`run_frames`) and the stages every frame shares; two kinds of
frames run through it: `frame_loop.FrameLoop`, the views' experiment (processing methods,
loading strategies, a display at the feedback's resolution), and
`gallery_walk.GalleryWalk`, the headset's walk (the display pass at full resolution, lit or
unlit, each frame checked against its oracle);
`record` writes a walk's frames, figures and video (`video`), `foveation` is the foveated
display, `frame_rates` what a frame rate means.
"""
