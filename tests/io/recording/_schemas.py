"""Checks of a channel's JSON schema against what real viewers need and what the messages carry.

`foxglove_parse` follows the rules of Foxglove Studio's (and Lichtblick's) parseJsonSchema
(packages/mcap-support/src/parseJsonSchema.ts, as read in @foxglove/studio-base 1.48): every object needs
"properties", every field a type it knows (boolean, string, number, integer, object, array of those); anything
else is "Failed to parse channel schema" and the channel never shows.
"""

from __future__ import annotations

import json

import jsonschema

SCALARS = {"boolean", "string", "number", "integer"}


def foxglove_parse(schema: dict, where: str = "schema") -> None:
    """Raise AssertionError where Foxglove's JSON schema parser would fail."""
    assert schema.get("type") == "object", f"{where}: expected type object, got {schema.get('type')!r}"
    props = schema.get("properties")
    assert isinstance(props, dict) and props, f"{where}: an object without properties"
    for name, field in props.items():
        at = f"{where}.{name}"
        tp = field.get("type")
        if tp == "object":
            foxglove_parse(field, at)
        elif tp == "array":
            items = field.get("items") or {}
            if items.get("type") == "object":
                foxglove_parse(items, at + "[]")
            else:
                assert items.get("type") in SCALARS, f"{at}: array items of type {items.get('type')!r}"
        else:
            assert tp in SCALARS, f"{at}: type {tp!r}"
            assert field.get("contentEncoding") in (None, "base64"), at


def keys_covered(schema: dict, msg, where: str = "message") -> None:
    """Every key of `msg` (recursively) has a property in `schema`."""
    if isinstance(msg, dict):
        props = schema.get("properties") or {}
        for k, v in msg.items():
            assert k in props, f"{where}: key {k!r} has no property in the schema"
            keys_covered(props[k], v, f"{where}.{k}")
    elif isinstance(msg, list):
        for v in msg:
            keys_covered(schema.get("items") or {}, v, f"{where}[]")


def check_channel(schema_bytes: bytes, payloads, topic: str) -> int:
    """The schema parses in Foxglove, and every payload validates against it with every key covered."""
    schema = json.loads(schema_bytes)
    foxglove_parse(schema, topic)
    validator = jsonschema.Draft202012Validator(schema)
    n = 0
    for p in payloads:
        msg = json.loads(p)
        validator.validate(msg)
        keys_covered(schema, msg, topic)
        n += 1
    return n
