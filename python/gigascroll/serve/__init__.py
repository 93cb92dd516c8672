"""`gigascroll serve`: one pack and one lit room served to browsers (the WebXR client in
python/gigascroll/web/), over the protocol of docs/serve-protocol.md.

    import gigascroll
    from gigascroll.serve import ServerThread, baked_room, make_app, pack_hash

    pack = gigascroll.TilePack("gallery.pack")
    h = pack_hash(pack)
    room = baked_room("scroll", pack, h)            # baked, or read from the cache
    with ServerThread(make_app(pack, room, h)) as url:
        ...                                         # http://127.0.0.1:PORT/
"""

from .app import MAX_BODY, make_app
from .pack_info import pack_description, pack_hash
from .room_bake import ROOM_LIGHTING, BakedRoom, baked_room, default_cache_dir, room_key
from .run import ServerThread, serve_forever, tls_context
from .scene import MAX_BATCH, scene_document

__all__ = ["MAX_BATCH", "MAX_BODY", "ROOM_LIGHTING", "BakedRoom", "ServerThread", "baked_room",
           "default_cache_dir", "make_app", "pack_description", "pack_hash", "room_key",
           "scene_document", "serve_forever", "tls_context"]
