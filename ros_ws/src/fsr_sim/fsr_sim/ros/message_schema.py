"""ROS 2 message definitions as rosbag2 writes them into MCAP schemas (encoding ``ros2msg``).

The schema text is the root type's ``.msg`` file, then every nested type once, depth-first in field
order, each introduced by a line of 80 ``=`` and ``MSG: pkg/Type``. The ``.msg`` files live under an
install prefix (``$PREFIX/share/<pkg>/msg``): the Python environment's, where the ROS wheels install them,
or one on ``AMENT_PREFIX_PATH`` or above the message package's module.
"""

from __future__ import annotations

import importlib
import os
import sys
from functools import cache
from pathlib import Path

from rosidl_parser.definition import AbstractNestedType, NamespacedType

SEPARATOR = "=" * 80


def type_name(msg_class: type) -> str:
    """``nav_msgs/msg/Odometry`` for the class ``nav_msgs.msg.Odometry``."""
    package = msg_class.__module__.split(".")[0]
    return f"{package}/msg/{msg_class.__name__}"


# Types fsr records although the pip wheels have no Python package for them: their .msg text (nested types
# are the wheels' own). tf2_msgs/msg/TFMessage is the Jazzy definition.
DEFINITIONS_WITHOUT_PACKAGE = {
    "tf2_msgs/msg/TFMessage": ("geometry_msgs/TransformStamped[] transforms\n",
                               [("geometry_msgs", "TransformStamped")]),
}


def message_class(name: str) -> type:
    """The Python class of ``pkg/msg/Type`` (or ``pkg/Type``)."""
    parts = name.split("/")
    if len(parts) == 2:
        parts = [parts[0], "msg", parts[1]]
    if len(parts) != 3:
        raise ValueError(f"Expected a message type like 'pkg/msg/Type', got '{name}'")
    return getattr(importlib.import_module(f"{parts[0]}.{parts[1]}"), parts[2])


def _share_prefixes(package: str) -> list[Path]:
    """Install prefixes that may hold ``share/<package>/msg``: this environment's, ``AMENT_PREFIX_PATH``
    (a ROS install or a colcon workspace), and every folder above the message package's Python module (an
    environment that takes its ROS packages from another one, e.g. through a ``.pth`` file)."""
    prefixes = [Path(sys.prefix), Path(sys.base_prefix)]
    prefixes += [Path(p) for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    try:
        module_file = importlib.import_module(package).__file__
    except ImportError:
        module_file = None
    if module_file:
        prefixes += list(Path(module_file).resolve().parents)
    return prefixes


@cache
def _msg_text(package: str, name: str) -> str:
    prefixes = _share_prefixes(package)
    for prefix in prefixes:
        path = prefix / "share" / package / "msg" / f"{name}.msg"
        if path.is_file():
            return path.read_text(encoding="utf-8")
    raise FileNotFoundError(
        f"No definition for {package}/msg/{name}: no share/{package}/msg/{name}.msg under "
        f"{', '.join(str(p) for p in dict.fromkeys(prefixes))}"
    )


def _nested_types(msg_class: type) -> list[tuple[str, str]]:
    found: list[tuple[str, str]] = []
    for slot_type in msg_class.SLOT_TYPES:
        while isinstance(slot_type, AbstractNestedType):
            slot_type = slot_type.value_type
        if isinstance(slot_type, NamespacedType):
            found.append((slot_type.namespaces[0], slot_type.name))
    return found


def type_definition(type_name: str) -> str:
    """The full ``ros2msg`` schema text of ``pkg/msg/Type``: :func:`message_definition` of its class, or for a type
    of :data:`DEFINITIONS_WITHOUT_PACKAGE` its text with its nested types."""
    if type_name in DEFINITIONS_WITHOUT_PACKAGE:
        text, nested = DEFINITIONS_WITHOUT_PACKAGE[type_name]
        return _with_nested(text, nested)
    return message_definition(message_class(type_name))


@cache
def message_definition(msg_class: type) -> str:
    """The full ``ros2msg`` schema text of a message class, as rosbag2 records it."""
    package = msg_class.__module__.split(".")[0]
    return _with_nested(_msg_text(package, msg_class.__name__), _nested_types(msg_class))


def _with_nested(text: str, nested_types: list[tuple[str, str]]) -> str:
    """``text`` followed by every type nested in ``nested_types`` once, depth-first in field order."""
    seen: set[tuple[str, str]] = set()

    def append_nested(types: list[tuple[str, str]]) -> None:
        nonlocal text
        for nested in types:
            if nested in seen:
                continue
            seen.add(nested)
            text += f"\n{SEPARATOR}\nMSG: {nested[0]}/{nested[1]}\n{_msg_text(*nested)}"
            append_nested(_nested_types(message_class(f"{nested[0]}/msg/{nested[1]}")))

    append_nested(nested_types)
    return text
