"""Tile packs: reading images in bands, the built-in painting, building packs and opening
them. A pack is a directory (format described in README.md) built by :func:`build_pack`
and read by :class:`TilePack`.

- :mod:`.images`: images read in bands and converted to 8-bit RGB (`open_image`, `to_rgb8`)
- :mod:`.synth`: the built-in ink landscape (`synth_painting`, `render_ink_landscape`)
- :mod:`.build`: the page-table layout and the build (`plan_layout`, `build_pack`)
- :mod:`.inspect`: reading back (`pack_manifest`, `read_level`, `verify_pack`, `pack_summary`)
- :mod:`.merge`: paintings of existing packs gathered into a new pack, their tiles copied as
  stored, never re-encoded (`merge_packs`; an exhibition of images and packs)
"""

from .._core import PackPainting, TilePack, painting_geometry
from .build import MANIFEST, build_pack, plan_layout
from .images import (ArraySource, FileSource, ImageSource, describe_conversion, open_image,
                     to_rgb8)
from .inspect import pack_manifest, pack_summary, read_level, verify_pack
from .synth import render_ink_landscape, synth_painting

__all__ = ["TilePack", "PackPainting", "build_pack", "open_image", "painting_geometry",
           "to_rgb8", "plan_layout", "synth_painting", "render_ink_landscape", "read_level",
           "pack_summary", "pack_manifest", "verify_pack"]

# Also reachable as gigascroll.pack.X, outside __all__ (not re-exported by gigascroll):
# ImageSource, ArraySource, FileSource (image sources for build_pack), describe_conversion,
# MANIFEST.
