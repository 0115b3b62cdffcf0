"""A small TOML writer for study files (tables, arrays of tables, inline tables, scalars).

The standard library reads TOML (``tomllib``) but does not write it; study files only need
this subset.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from typing import Any

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(k: str) -> str:
    return k if _BARE.match(k) else json.dumps(k)


def _value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, Mapping):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _is_table_array(v: Any) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, Mapping) for x in v) \
        and any(any(isinstance(y, Mapping) for y in x.values()) or len(x) > 3 for x in v)


def dumps(data: Mapping[str, Any]) -> str:
    """TOML text of ``data`` (nested mappings become tables; lists of rich mappings become
    arrays of tables; everything else is written inline)."""
    lines: list[str] = []

    def table(d: Mapping[str, Any], path: list[str], header: str | None) -> None:
        scalars = {k: v for k, v in d.items()
                   if not isinstance(v, Mapping) and not _is_table_array(v)}
        if header is not None and (scalars or not d):
            lines.append("")
            lines.append(header)
        for k, v in scalars.items():
            lines.append(f"{_key(k)} = {_value(v)}")
        for k, v in d.items():
            if isinstance(v, Mapping):
                p = [*path, _key(k)]
                table(v, p, f"[{'.'.join(p)}]")
            elif _is_table_array(v):
                p = [*path, _key(k)]
                for item in v:
                    lines.append("")
                    lines.append(f"[[{'.'.join(p)}]]")
                    table(item, p, None)

    table(data, [], None)
    return "\n".join(lines).lstrip("\n") + "\n"
