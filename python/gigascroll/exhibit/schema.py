"""The exhibition file's and the tour file's published JSON Schemas (exhibition.schema.json,
tour.schema.json beside this module), and validation whose errors name the file, the key
(`paintings[2].width_cm`) and what was expected, in one line."""

from __future__ import annotations

import json
import math
from functools import lru_cache
from pathlib import Path

__all__ = ["ExhibitionError", "schema", "validate", "key_name", "check_finite"]

HERE = Path(__file__).resolve().parent


class ExhibitionError(ValueError):
    """A bad exhibition or tour file: 'FILE: KEY: what was expected' on one line."""


def schema(name: str = "exhibition") -> dict:
    """The published schema `name` ("exhibition" or "tour") as a dict."""
    return json.loads((HERE / f"{name}.schema.json").read_text(encoding="utf-8"))


@lru_cache(maxsize=None)
def _validator(name: str):
    from jsonschema import Draft202012Validator
    from referencing import Registry, Resource
    tour = schema("tour")
    registry = Registry().with_resource(tour["$id"], Resource.from_contents(tour))
    return Draft202012Validator(schema(name), registry=registry)


# The schemas' patterns in words, for the errors.
PATTERN_WORDS = {
    "^([a-z]{2,3}(-[A-Za-z0-9]{1,8})*|none)$":
        "a BCP 47 language tag such as en, zh-Hant or ja, or none",
    "^[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}$":
        "1 to 100 letters, digits, '_', '.' or '-', not starting with '.' or '-'",
}


def key_name(path) -> str:
    """A JSON path (keys and indices) as `paintings[2].width_cm` ('(top level)' when empty)."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "(top level)"


def _expected(error) -> str:
    """What the schema wanted where `error` points, in words."""
    v, s = error.validator, error.validator_value
    if v == "oneOf" and isinstance(s, list) and all("required" in alt for alt in s):
        options = [" and ".join(alt["required"]) for alt in s]
        return f"expected exactly one of: {'; '.join(options)}"
    if v == "additionalProperties":
        allowed = sorted(error.schema.get("properties", {}))
        return f"unknown key (expected one of: {', '.join(allowed)})"
    if v == "required":
        return error.message.replace("is a required property", "is required")
    if v == "type":
        return f"expected {s if isinstance(s, str) else ' or '.join(s)}, got " \
               f"{type(error.instance).__name__} {_short(error.instance)}"
    if v in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        words = {"minimum": ">=", "maximum": "<=", "exclusiveMinimum": ">", "exclusiveMaximum": "<"}
        return f"expected a number {words[v]} {s}, got {_short(error.instance)}"
    if v == "enum":
        return f"expected one of {', '.join(map(str, s))}, got {_short(error.instance)}"
    if v == "pattern":
        return f"expected {PATTERN_WORDS.get(s, 'text matching ' + s)}, got " \
               f"{_short(error.instance)}"
    if v in ("minItems", "maxItems", "minLength", "maxLength"):
        return f"expected {'at least' if v.startswith('min') else 'at most'} {s} " \
               f"{'items' if v.endswith('Items') else 'characters'}, got {len(error.instance)}"
    return " ".join(error.message.split())[:200]


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def check_finite(data, where: str, path=()) -> None:
    """ExhibitionError for a NaN or infinite number anywhere in `data` (TOML allows nan and
    inf; the schema's bounds let NaN through)."""
    if isinstance(data, float) and not math.isfinite(data):
        raise ExhibitionError(f"{where}: {key_name(path)}: expected a finite number, got {data}")
    if isinstance(data, dict):
        for k, v in data.items():
            check_finite(v, where, path + (k,))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            check_finite(v, where, path + (i,))


def validate(data, where: str, name: str = "exhibition") -> None:
    """ExhibitionError 'WHERE: KEY: expected ...' for the first (deepest, best) schema error."""
    from jsonschema.exceptions import best_match
    check_finite(data, where)
    error = best_match(_validator(name).iter_errors(data))
    if error is not None:
        path = list(error.absolute_path)
        if error.validator == "additionalProperties" and isinstance(error.instance, dict):
            known = error.schema.get("properties", {})
            path.append(sorted(str(k) for k in error.instance if k not in known)[0])
        raise ExhibitionError(f"{where}: {key_name(path)}: {_expected(error)}")
