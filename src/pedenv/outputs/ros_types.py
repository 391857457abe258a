"""ROS 2 message types for ``--ros-out``: Humble's standard types plus ``vision_msgs`` and
``autoware_perception_msgs``, registered from the ``.msg`` texts in ``ros_msgs/`` (Apache-2.0,
see ``ros_msgs/README.md``), and :func:`make`, which builds a message with every field not
given set to its default (zeros, empty strings and sequences), as ROS does.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any, TypeAlias

import numpy as np

MSG_ROOT = Path(__file__).with_name("ros_msgs")
#: The packages registered from ``ros_msgs/<package>/msg/*.msg``.
PACKAGES = ("vision_msgs", "autoware_perception_msgs")
_NUMPY = {"bool": np.bool_, "int8": np.int8, "uint8": np.uint8, "byte": np.uint8, "char": np.uint8,
          "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32, "int64": np.int64,
          "uint64": np.uint64, "float32": np.float32, "float64": np.float64}
#: A rosbags ``Typestore`` and a message built from it: rosbags ships no type information that mypy
#: follows (pyproject's overrides skip it), so both are ``Any`` here, named for the reader.
Typestore: TypeAlias = Any
Message: TypeAlias = Any


@cache
def ros2_typestore() -> Typestore:
    """A rosbags typestore (ROS 2 Humble) with the messages of :data:`PACKAGES` registered."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    types: dict[str, Any] = {}
    for package in PACKAGES:
        for path in sorted((MSG_ROOT / package / "msg").glob("*.msg")):
            types.update(get_types_from_msg(path.read_text(), f"{package}/msg/{path.stem}"))
    store.register(types)
    return store


def _default(store: Typestore, node: tuple[Any, Any]) -> Any:
    from rosbags.typesys.base import Nodetype

    kind, detail = node
    if kind == Nodetype.BASE:
        name = detail[0]
        return "" if name in ("string", "wstring") else (False if name == "bool" else 0)
    if kind == Nodetype.NAME:
        return make(store, detail)
    if kind == Nodetype.ARRAY:
        (sub_kind, sub), length = detail
        if sub_kind == Nodetype.BASE and sub[0] in _NUMPY:
            return np.zeros(length, _NUMPY[sub[0]])
        return [_default(store, (sub_kind, sub)) for _ in range(length)]
    (sub_kind, sub), _ = detail  # a sequence: empty
    return np.zeros(0, _NUMPY[sub[0]]) if sub_kind == Nodetype.BASE and sub[0] in _NUMPY else []


def make(store: Typestore, msgtype: str, **fields: Any) -> Message:
    """An instance of ``msgtype`` (``pkg/msg/Name``) with ``fields``; the rest get ROS's defaults.

    Numeric arrays given as lists become numpy arrays of the field's type (what rosbags expects).
    """
    from rosbags.typesys.base import Nodetype

    _, defs = store.fielddefs[msgtype]
    values: dict[str, Any] = {}
    for name, node in defs:
        if name in fields:
            value = fields.pop(name)
            kind, detail = node
            if kind in (Nodetype.ARRAY, Nodetype.SEQUENCE) and detail[0][0] == Nodetype.BASE \
                    and detail[0][1][0] in _NUMPY:
                value = np.asarray(value, _NUMPY[detail[0][1][0]])
            values[name] = value
        else:
            values[name] = _default(store, node)
    if fields:
        raise TypeError(f"{msgtype} has no field(s) {', '.join(fields)}")
    return store.types[msgtype](**values)
