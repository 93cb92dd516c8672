"""IIIF Presentation API 3.0 for an exhibition: one Manifest whose Canvases are the
paintings, each with its label, metadata (artist, date, physical size, accession number),
rights, required statement (the credit line) and one painting annotation whose Image body
carries the painting's IIIF Image API 3.0 service (an `export --format iiif` directory's
info.json id, or any other Image API server's base URI).

The exhibition builder (`gigascroll exhibit build`) calls `write_presentation_manifest`
with the exhibition's paintings; `painting_from_info` makes a painting's entry from an
exported info.json, so the canvas, the image body and the service agree with the tiles.

Rules applied here, from the Presentation 3.0 specification: every id an absolute http(s)
URI; label, summary and metadata values language maps ({"en": ["..."]}: the texts in the
given `language`, a BCP 47 tag or "none" where it is not known, as for titles and names;
the metadata's field names, which this module writes, in English); canvas width and
height positive integers; `rights` a single URI from Creative Commons or
RightsStatements.org (the only sources the specification allows without a registered
extension); annotations with motivation "painting" targeting their canvas."""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import quote, urlsplit

from .outputs import write_text

__all__ = ["PRESENTATION_CONTEXT", "PresentationPainting", "check_http_uri", "check_rights",
           "presentation_manifest", "write_presentation_manifest", "painting_from_info",
           "exhibition_painting"]

PRESENTATION_CONTEXT = "http://iiif.io/api/presentation/3/context.json"

# Creative Commons licence and public-domain tool URIs, RightsStatements.org's twelve
# statements (their URIs are /vocab/..., the /page/... addresses are for people).
_CC = re.compile(r"https?://creativecommons\.org/(?:licenses/(?:by|by-sa|by-nd|by-nc|by-nc-sa"
                 r"|by-nc-nd)/(?:1\.0|2\.0|2\.5|3\.0|4\.0)|publicdomain/(?:zero|mark)/1\.0)/")
_RS = re.compile(r"https?://rightsstatements\.org/vocab/(?:InC|InC-OW-EU|InC-EDU|InC-NC|InC-RUU"
                 r"|NoC-CR|NoC-NC|NoC-OKLR|NoC-US|CNE|UND|NKC)/1\.0/")


def check_http_uri(uri, what: str) -> str:
    """`uri` without a trailing slash, or ValueError naming `what` unless it is an absolute
    http or https URI with a host and no query or fragment (what IIIF ids need: a client
    appends "/info.json" or "/canvas/1" to them)."""
    if not isinstance(uri, str) or not uri:
        raise ValueError(f"{what} must be an absolute http(s) URI, got {uri!r}")
    if any(c.isspace() or ord(c) < 0x20 for c in uri):
        raise ValueError(f"{what} {uri!r} holds white space or a control character")
    try:
        parts = urlsplit(uri)
        parts.port  # noqa: B018 -- a bad port raises ValueError
    except ValueError as e:
        raise ValueError(f"{what} {uri!r} is not a URI: {e}") from None
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise ValueError(f"{what} {uri!r} must be an absolute http:// or https:// URI "
                         "(the IIIF APIs require absolute ids)")
    if parts.query or parts.fragment or "?" in uri or "#" in uri:
        raise ValueError(f"{what} {uri!r} must not have a query or a fragment")
    return uri.rstrip("/")


def check_rights(uri) -> str:
    """`uri` if it is a Creative Commons or RightsStatements.org URI (Presentation 3.0's
    `rights`), else ValueError listing what is accepted."""
    if isinstance(uri, str) and (_CC.fullmatch(uri) or _RS.fullmatch(uri)):
        return uri
    raise ValueError(
        f"rights {uri!r} is not a Creative Commons or RightsStatements.org URI (e.g. "
        "http://creativecommons.org/licenses/by/4.0/, "
        "http://creativecommons.org/publicdomain/mark/1.0/, "
        "http://rightsstatements.org/vocab/InC/1.0/; with the trailing slash)")


@dataclass(frozen=True)
class PresentationPainting:
    """One painting's canvas. `service`: the base URI of its IIIF Image API 3.0 service (the
    id in its info.json); `width`, `height`: its pixels (the canvas's size); `image`: the
    image body's URL (default: the service's full/max image) and `image_size` its size
    (default the canvas's); `size_cm`: physical (width, height) in centimetres."""

    title: str
    width: int
    height: int
    service: str
    artist: str = ""
    date: str = ""
    credit: str = ""
    rights: str | None = None
    size_cm: tuple[float, float] | None = None
    accession: str = ""
    image: str | None = None
    image_size: tuple[int, int] | None = None
    service_profile: str = "level0"
    extra: dict = field(default_factory=dict)  # more metadata: label -> value strings


FIELD_LANGUAGE = "en"  # the metadata's field names ("Artist", "Credit"): English words


def _lang(text: str, language: str) -> dict:
    return {language: [str(text)]}


def _positive_int(v, what: str) -> int:
    if isinstance(v, bool) or not isinstance(v, int) or v <= 0:
        raise ValueError(f"{what} must be a positive integer, got {v!r}")
    return v


def _metadata(p: PresentationPainting, language: str) -> list[dict]:
    rows = [("Artist", p.artist), ("Date", p.date)]
    if p.size_cm is not None:
        size = p.size_cm
        if not (isinstance(size, (tuple, list)) and len(size) == 2 and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                and x > 0 for x in size)):
            raise ValueError(f"painting '{p.title}': size_cm must be two positive numbers "
                             f"(width, height), got {size!r}")
        w, h = size
        rows.append(("Dimensions", f"{h:g} x {w:g} cm (height x width)"))
    rows += [("Accession number", p.accession), *p.extra.items()]
    return [{"label": _lang(k, FIELD_LANGUAGE), "value": _lang(v, language)}
            for k, v in rows if v]


def _canvas(base: str, i: int, p: PresentationPainting, language: str) -> dict:
    if not isinstance(p.title, str) or not p.title.strip():
        raise ValueError(f"painting {i}: the title must be a non-empty string")
    w = _positive_int(p.width, f"painting {i} ('{p.title}'): width")
    h = _positive_int(p.height, f"painting {i} ('{p.title}'): height")
    service = check_http_uri(p.service, f"painting {i} ('{p.title}'): image service")
    image = check_http_uri(p.image or f"{service}/full/max/0/default.jpg",
                           f"painting {i} ('{p.title}'): image")
    iw, ih = p.image_size or (w, h)
    canvas_id = f"{base}/canvas/{i + 1}"
    body = {"id": image, "type": "Image", "format": "image/jpeg",
            "width": _positive_int(iw, "image width"), "height": _positive_int(ih, "image height"),
            "service": [{"id": service, "type": "ImageService3", "profile": p.service_profile}]}
    canvas = {"id": canvas_id, "type": "Canvas", "label": _lang(p.title, language),
              "width": w, "height": h,
              "items": [{"id": f"{canvas_id}/page/1", "type": "AnnotationPage",
                         "items": [{"id": f"{canvas_id}/page/1/painting", "type": "Annotation",
                                    "motivation": "painting", "body": body,
                                    "target": canvas_id}]}]}
    metadata = _metadata(p, language)
    if metadata:
        canvas["metadata"] = metadata
    if p.rights is not None:
        canvas["rights"] = check_rights(p.rights)
    if p.credit:
        canvas["requiredStatement"] = {"label": _lang("Credit", FIELD_LANGUAGE),
                                       "value": _lang(p.credit, language)}
    return canvas


def presentation_manifest(paintings, manifest_id: str, label: str, *, summary: str = "",
                          language: str = "en") -> dict:
    """The Presentation 3.0 Manifest (a JSON-ready dict) of `paintings` (PresentationPainting,
    in hanging order) at `manifest_id` (the URL it will be served at). Canvas ids are
    MANIFEST_BASE/canvas/N (N from 1), MANIFEST_BASE being manifest_id without its file name
    when it ends in .json. ValueError for a bad id, rights URI, size or an empty list."""
    manifest_id = check_http_uri(manifest_id, "the manifest's id")
    paintings = list(paintings)
    if not paintings:
        raise ValueError("an exhibition's manifest needs at least one painting")
    if not isinstance(label, str) or not label.strip():
        raise ValueError("the manifest's label must be a non-empty string")
    if not re.fullmatch(r"[a-z]{2,3}(-[A-Za-z0-9]{1,8})*|none", language):
        raise ValueError(f"language {language!r} is not a BCP 47 tag")
    base = manifest_id.rsplit("/", 1)[0] if manifest_id.endswith(".json") else manifest_id
    for i, p in enumerate(paintings):
        if not isinstance(p, PresentationPainting):
            raise TypeError(f"painting {i} must be a PresentationPainting, "
                            f"not {type(p).__name__}")
    manifest = {"@context": PRESENTATION_CONTEXT, "id": manifest_id, "type": "Manifest",
                "label": _lang(label, language)}
    if summary:
        manifest["summary"] = _lang(summary, language)
    manifest["items"] = [_canvas(base, i, p, language) for i, p in enumerate(paintings)]
    return manifest


def write_presentation_manifest(path, paintings, manifest_id: str, label: str, **kw) -> Path:
    """Writes presentation_manifest(...) to `path` (atomically) and returns the path."""
    manifest = presentation_manifest(paintings, manifest_id, label, **kw)
    path = Path(path)
    write_text(path, json.dumps(manifest, indent=2, ensure_ascii=False) + "\n")
    return path


def painting_from_info(info_path, title: str, **meta) -> PresentationPainting:
    """A painting's canvas entry from an Image API 3.0 info.json (an `export --format iiif`
    output's): its id as the service, its size as the canvas's, and its largest listed
    `sizes` entry as the image body (a level-0 export holds exactly those full images).
    `meta`: the other PresentationPainting fields. ValueError for an info.json that is not
    an ImageService3's."""
    info_path = Path(info_path)
    try:
        info = json.loads(info_path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"{info_path}: not a JSON file: {e}") from None
    if not isinstance(info, dict) or info.get("type") != "ImageService3":
        raise ValueError(f"{info_path}: not an IIIF Image API 3.0 info.json (type "
                         "ImageService3)")
    service = check_http_uri(info.get("id"), f"{info_path}: id")
    sizes = [s for s in info.get("sizes") or [] if isinstance(s, dict)]
    image, image_size = None, None
    if sizes:
        big = max(sizes, key=lambda s: s.get("width", 0) * s.get("height", 0))
        image_size = (big["width"], big["height"])
        image = f"{service}/full/{quote(str(big['width']))},{quote(str(big['height']))}/0/default.jpg"
    return PresentationPainting(title=title, width=info.get("width"), height=info.get("height"),
                                service=service, image=image, image_size=image_size,
                                service_profile=str(info.get("profile", "level0")), **meta)


def exhibition_painting(painting, service: str, *, info=None, width: int | None = None,
                        height: int | None = None) -> PresentationPainting:
    """The canvas entry of an exhibition's painting (any object with `title`, `width_cm`,
    `height_cm` and optional `artist`, `date`, `credit`, `rights`, `accession`, as
    gigascroll.exhibit's Painting) whose Image API service is at `service`: its pixel size
    from `info` (the path of the service's exported info.json, whose id must be `service`)
    or `width` and `height`. ValueError when the two disagree or a size is missing."""
    meta = {k: getattr(painting, k, None) or "" for k in ("artist", "date", "credit",
                                                          "accession")}
    meta["rights"] = getattr(painting, "rights", None) or None
    meta["size_cm"] = (painting.width_cm, painting.height_cm)
    if info is not None:
        entry = painting_from_info(info, painting.title, **meta)
        if entry.service != check_http_uri(service, "the image service"):
            raise ValueError(f"{info}: its id {entry.service} is not the service {service}")
        return entry
    if width is None or height is None:
        raise ValueError(f"painting '{painting.title}': give its info.json or its pixel size")
    return PresentationPainting(painting.title, width, height, service, **meta)
