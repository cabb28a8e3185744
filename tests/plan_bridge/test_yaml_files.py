"""A YAML file of lists read once, with each item's line for errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from plan_bridge.yaml_files import read_yaml_with_lines


class FileError(Exception):
    pass


def test_items_of_a_top_level_list_and_of_lists_under_keys_have_their_lines(
    tmp_path: Path,
) -> None:
    listed = tmp_path / "events.yaml"
    listed.write_text("# events\n- at: 1\n  close: hall\n- at: 5\n  open: hall\n")
    assert read_yaml_with_lines(listed, "events", FileError) == (
        [{"at": 1, "close": "hall"}, {"at": 5, "open": "hall"}],
        {"": [2, 4]},
    )
    keyed = tmp_path / "orders.yaml"
    keyed.write_text("orders:\n  - id: a\n  - id: b\nstreams:\n  - rate: 2\nname: x\n")
    data, lines = read_yaml_with_lines(keyed, "orders", FileError)
    assert data["name"] == "x" and lines == {"orders": [2, 3], "streams": [5]}


def test_an_empty_file_is_no_data(tmp_path: Path) -> None:
    empty = tmp_path / "empty.yaml"
    empty.write_text("# nothing yet\n")
    assert read_yaml_with_lines(empty, "orders", FileError) == (None, {})


def test_a_missing_file_and_bad_yaml_raise_the_given_error_naming_the_file(
    tmp_path: Path,
) -> None:
    with pytest.raises(FileError, match=r"missing\.yaml: cannot read the events file"):
        read_yaml_with_lines(tmp_path / "missing.yaml", "events", FileError)
    bad = tmp_path / "bad.yaml"
    bad.write_text("- at: [1, 2\n")
    with pytest.raises(FileError, match=r"bad\.yaml: not valid YAML"):
        read_yaml_with_lines(bad, "events", FileError)
