"""Input groups, each declared once: a frozen dataclass whose fields carry their type,
default, unit and help (:func:`option`). The command line's options
(:func:`facemech.cli.command`), a batch manifest's keys (:func:`manifest_kinds`,
:func:`from_manifest`) and the Python signature (the dataclass itself) are all made from it.

A field's *key* is the command's parameter (``--jaw-chin`` is the key ``jaw_chin`` of the field
``JawSource.markers``); its *flags* are the option's names (default ``--the-key``); its
*manifest key* is the last flag without dashes (``--map`` -> ``map``); its *kind* the manifest's
value kind (:data:`facemech.batch.job.OPTION_KINDS`; default from the type). Pure Python.
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from collections.abc import Mapping
from pathlib import Path

__all__ = ["Input", "REQUIRED", "from_keys", "from_manifest", "inputs_of", "manifest_kinds",
           "option"]

#: the default of an input that must be given
REQUIRED = dataclasses.MISSING
_KINDS = {Path: "path", bool: "bool", int: "int", float: "float", str: "str"}


@dataclasses.dataclass(frozen=True)
class Input:
    """One declared input: a field of an input group, as every front end sees it.

    Attributes
    ----------
    name : the dataclass field
    key : the command's parameter (and the keyword of a flat Python signature)
    type : the command line's type (``Path | None``, ``int``, ...)
    default : the default (:data:`REQUIRED`: none)
    help, unit : one line of help; the unit of a number (SI unless the help says)
    flags : the option's names on the command line
    kind : the manifest's value kind
    """

    name: str
    key: str
    type: object
    default: object
    help: str
    unit: str | None
    flags: tuple[str, ...]
    kind: str

    @property
    def manifest_key(self) -> str:
        """The key of a batch manifest: the last flag without its dashes."""
        return self.flags[-1].lstrip("-").replace("-", "_")


def option(default=REQUIRED, help: str = "", *, unit: str | None = None, key: str | None = None,
           flags: tuple[str, ...] = (), kind: str | None = None, cli: object = None):
    """A dataclass field declared as an input (see the module); ``cli``: the command line's
    type where the field's own is wider (``str`` for a field that also takes a pair)."""
    meta = {"input": {"help": help, "unit": unit, "key": key, "flags": tuple(flags),
                      "kind": kind, "cli": cli}}
    return dataclasses.field(default=default, metadata=meta)


def _kind(typ) -> str:
    args = [a for a in typing.get_args(typ) if a is not type(None)] if isinstance(
        typ, types.UnionType) or typing.get_origin(typ) is typing.Union else [typ]
    for a in args:
        if a in _KINDS:
            return _KINDS[a]
    raise TypeError(f"no manifest kind for {typ!r}: give option(kind=...)")


@functools.cache
def inputs_of(cls: type) -> tuple[Input, ...]:
    """The inputs of an input group (a dataclass), in its fields' order."""
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        m = f.metadata.get("input", {})
        key = m.get("key") or f.name
        typ = m.get("cli") or hints[f.name]
        out.append(Input(f.name, key, typ, f.default, m.get("help", ""), m.get("unit"),
                         m.get("flags") or ("--" + key.replace("_", "-"),),
                         m.get("kind") or _kind(typ)))
    return tuple(out)


def from_keys(cls: type, values: Mapping):
    """An input group from values by key (the command's parameters); a key not given takes the
    field's default."""
    return cls(**{i.name: values[i.key] for i in inputs_of(cls) if i.key in values})


def from_manifest(cls: type, options: Mapping):
    """An input group from a manifest item's options (by manifest key)."""
    return cls(**{i.name: options[i.manifest_key] for i in inputs_of(cls)
                  if i.manifest_key in options})


def manifest_kinds(*groups: type) -> dict[str, str]:
    """Manifest key -> value kind of the inputs of ``groups``."""
    return {i.manifest_key: i.kind for g in groups for i in inputs_of(g)}
