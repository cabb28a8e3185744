"""YAML files of lists whose items an error can name by line: world events
(:mod:`plan_bridge.robosim.events`) and orders (:mod:`plan_bridge.orders.order_file`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["read_yaml_with_lines"]


def read_yaml_with_lines(
    path: str | Path, kind: str, error: type[Exception]
) -> tuple[Any, dict[str, list[int]]]:
    """The data of the YAML file at ``path`` (parsed once), and each list item's line:
    a list at the top under ``""``, a list under a top-level key under that key.
    A file that cannot be read or is not YAML raises ``error`` naming the ``kind`` of
    file and why."""
    import yaml

    file = Path(path)
    try:
        text = file.read_text(encoding="utf-8")
    except OSError as exc:
        raise error(f"{file}: cannot read the {kind} file: {exc.strerror or exc}") from exc
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        data = loader.construct_document(node) if node is not None else None
    except yaml.YAMLError as exc:
        raise error(f"{file}: not valid YAML: {exc}") from exc
    finally:
        loader.dispose()
    lines: dict[str, list[int]] = {}
    if isinstance(node, yaml.SequenceNode):
        lines[""] = [item.start_mark.line + 1 for item in node.value]
    elif isinstance(node, yaml.MappingNode):
        for key, value in node.value:
            if isinstance(value, yaml.SequenceNode):
                lines[str(key.value)] = [item.start_mark.line + 1 for item in value.value]
    return data, lines
