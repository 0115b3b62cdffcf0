"""Editing study files in place, keeping the user's comments and layout (tomlkit).

``sensfw augment`` adds an effect to a study: the effect goes into ``[model].options.effects``,
its calibrated parameters into ``[parameters.NAME]`` tables and a note into the description.
The edit is made on the parsed document (:func:`tomlkit.parse`), so every comment, blank line
and the order of the user's keys survive; only the added lines are new.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import tomlkit
from tomlkit.items import AoT, Array, InlineTable


def _table(parent, key: str, inline: bool = False):
    """``parent[key]`` as a table, created (at the end of ``parent``) if missing."""
    if key not in parent:
        parent[key] = tomlkit.inline_table() if inline else tomlkit.table()
    return parent[key]


def _parameter_table(doc, name: str) -> tuple[Any, bool]:
    """``doc``'s ``[parameters.NAME]`` table and whether it is new (created, with the
    ``[parameters]`` super-table, at the end of the file)."""
    params = doc.get("parameters")
    if params is None:
        params = doc["parameters"] = tomlkit.table(is_super_table=True)
    entry = params.get(name)
    if entry is None:
        entry = params[name] = tomlkit.table()
        return entry, True
    return entry, False


def _effects_entry(name: str, attach: str | None,
                   options: Mapping[str, object] | None = None) -> InlineTable:
    entry = tomlkit.inline_table()
    entry["name"] = name
    if attach:
        entry["attach"] = attach
    entry.update(dict(options or {}))
    return entry


def add_effect(text: str, name: str, attach: str | None,
               parameters: Mapping[str, Mapping[str, float]], note: str = "",
               options: Mapping[str, object] | None = None) -> str:
    """``text`` (a study file) with effect ``name`` at ``attach`` added to the model.

    Parameters
    ----------
    text : str
        The study file as written by the user.
    name, attach : str
        The effect and its attach point (``attach=None``: the effect's default).
    parameters : mapping
        ``{parameter: {"min": ..., "nominal": ..., "max": ...}}`` written as
        ``[parameters.<parameter>]`` tables (existing keys of such a table are replaced,
        others kept).
    note : str
        Appended to ``[study].description``.
    options : mapping, optional
        The effect's own options beside ``name`` and ``attach`` (``{"elements": 6}`` for
        ``micro_slip``), written into its entry as given.

    Returns
    -------
    str
        The edited file; every line of ``text`` that is a comment is still in it.
    """
    doc = tomlkit.parse(text)
    model = _table(doc, "model")
    model_options = model.get("options")
    if model_options is None:
        model_options = model["options"] = tomlkit.inline_table()
    effects = model_options.get("effects")
    if effects is None:
        effects = model_options["effects"] = tomlkit.array()
    if isinstance(effects, AoT):  # [[model.options.effects]] tables
        entry = tomlkit.table()
        entry.update(_effects_entry(name, attach, options))
        effects.append(entry)
    elif isinstance(effects, Array):
        effects.append(_effects_entry(name, attach, options))
    else:
        raise TypeError("[model].options.effects must be an array")
    for pname, values in parameters.items():
        entry, _ = _parameter_table(doc, pname)
        for k, v in values.items():
            entry[k] = float(v)
    if note:
        study = _table(doc, "study")
        old = str(study.get("description", ""))
        study["description"] = f"{old} {note}".strip()
    return tomlkit.dumps(doc)


def set_calibration(text: str, variables: list[str]) -> str:
    """``text`` with ``[calibration] parameters = variables`` (created, or its list
    replaced), keeping everything else."""
    doc = tomlkit.parse(text)
    cal = _table(doc, "calibration")
    arr = tomlkit.array()
    arr.extend(variables)
    cal["parameters"] = arr
    return tomlkit.dumps(doc)


def set_nominals(text: str, values: Mapping[str, float],
                 bounds: Mapping[str, tuple[float, float]]) -> str:
    """``text`` with ``[parameters.NAME] nominal = value`` for each of ``values`` (a table's
    other keys kept; a new table gets ``min``/``max`` from ``bounds``)."""
    doc = tomlkit.parse(text)
    for name, value in values.items():
        entry, new = _parameter_table(doc, name)
        if new:
            lo, hi = bounds[name]
            entry["min"], entry["max"] = float(lo), float(hi)
        entry["nominal"] = float(value)
    return tomlkit.dumps(doc)


def set_calibration_result(text: str, result: Mapping) -> str:
    """``text`` with ``[calibration.result]`` = ``result`` (:class:`~sensfw.study.schema.
    CalibrationResult`'s fields: what a calibration found), replacing an older one."""
    doc = tomlkit.parse(text)
    cal = _table(doc, "calibration")
    table = tomlkit.table()
    for key in ("parameters", "scales"):
        table[key] = list(result[key])
    table["coded"] = [float(x) for x in result["coded"]]
    rows = tomlkit.array()
    for row in result["covariance"]:
        rows.append([float(x) for x in row])
    rows.multiline(True)
    table["covariance"] = rows
    recs = tomlkit.array()
    for r in result.get("records", []):
        item = tomlkit.inline_table()
        item.update({k: (float(v) if isinstance(v, (int, float)) else str(v))
                     for k, v in r.items()})
        recs.append(item)
    recs.multiline(True)
    table["records"] = recs
    cal["result"] = table
    return tomlkit.dumps(doc)


__all__ = ["add_effect", "set_calibration", "set_calibration_result", "set_nominals"]
