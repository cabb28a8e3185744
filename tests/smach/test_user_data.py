"""smach.UserData, smach.Remapper and smach.user_data.Const."""

from __future__ import annotations

import pickle

import pytest

import smach
from smach.user_data import Const, get_const


class Obj:
    def __init__(self) -> None:
        self.field = 1
        self.inner = Inner()


class Inner:
    def __init__(self) -> None:
        self.value = 2


# -- UserData ----------------------------------------------------------------------------


def test_userdata_attribute_and_item_access_share_storage() -> None:
    ud = smach.UserData()
    ud.a = 1
    ud["b"] = 2
    assert ud["a"] == 1
    assert ud.b == 2
    assert ud.keys() == ["a", "b"]


def test_userdata_missing_key_is_keyerror_and_attributeerror_listing_keys() -> None:
    ud = smach.UserData()
    ud.present = 1
    with pytest.raises(KeyError) as by_item:
        ud["missing"]
    with pytest.raises(AttributeError) as by_attr:
        ud.missing  # noqa: B018
    for info in (by_item, by_attr):
        assert "missing" in str(info.value)
        assert "present" in str(info.value)


def test_userdata_hasattr_and_getattr_default_work() -> None:
    ud = smach.UserData()
    ud.x = 0
    assert hasattr(ud, "x")
    assert not hasattr(ud, "y")
    assert getattr(ud, "y", "default") == "default"


def test_userdata_contains_len_iter_get_items() -> None:
    ud = smach.UserData()
    ud.a = 1
    ud.b = None
    assert "a" in ud
    assert "b" in ud
    assert "c" not in ud
    assert len(ud) == 2
    assert list(ud) == ["a", "b"]
    assert getattr(ud, "a", 5) == 1
    assert getattr(ud, "c", 5) == 5
    assert dict(ud) == {"a": 1, "b": None}


@pytest.mark.parametrize("key", ["items", "get", "to_dict"])
def test_userdata_keys_named_like_new_helper_methods_are_readable_as_attributes(key: str) -> None:
    # The original UserData only had keys/update/extract/merge, so ``ud.items`` (a
    # natural key name, e.g. a list of items to pick) worked as a userdata key.
    ud = smach.UserData()
    setattr(ud, key, [1, 2])
    assert getattr(ud, key) == [1, 2]
    r = smach.Remapper(ud, [key], [key])
    assert getattr(r, key) == [1, 2]


def test_userdata_delete_item() -> None:
    ud = smach.UserData()
    ud.a = 1
    del ud["a"]
    assert "a" not in ud
    with pytest.raises(KeyError):
        del ud["a"]


def test_userdata_update_from_userdata_and_mapping_overwrites() -> None:
    ud = smach.UserData()
    ud.a = 1
    other = smach.UserData()
    other.a = 2
    other.b = 3
    ud.update(other)
    ud.update({"c": 4})
    assert dict(ud) == {"a": 2, "b": 3, "c": 4}


def test_userdata_constructor_copies_mapping() -> None:
    data = {"a": 1}
    ud = smach.UserData(data)
    ud.b = 2
    assert data == {"a": 1}


def test_userdata_values_are_shared_by_reference() -> None:
    ud = smach.UserData()
    value: list[int] = []
    ud.v = value
    ud.v.append(1)
    assert ud.v is value
    assert value == [1]


def test_userdata_underscore_data_is_the_live_dict() -> None:
    ud = smach.UserData()
    ud._data["a"] = 1
    assert ud.a == 1
    ud.b = 2
    assert ud._data == {"a": 1, "b": 2}


def test_userdata_pickles_round_trip() -> None:
    ud = smach.UserData()
    ud.a = [1, 2]
    copy = pickle.loads(pickle.dumps(ud))
    assert copy.a == [1, 2]
    assert isinstance(copy, smach.UserData)


def test_userdata_extract_and_merge_use_remapping() -> None:
    ud = smach.UserData()
    ud.x = [1]
    extracted = ud.extract(["x"], {"local": "x"})
    assert extracted.local == [1]
    target = smach.UserData()
    target.merge(extracted, ["local"], {"local": "y"})
    assert target.y == [1]


# -- Remapper ----------------------------------------------------------------------------


def test_remapper_reads_declared_input_through_remapping() -> None:
    ud = smach.UserData()
    ud.container_key = 5
    r = smach.Remapper(ud, ["local"], [], {"local": "container_key"})
    assert r.local == 5
    assert r["local"] == 5


def test_remapper_writes_declared_output_through_remapping() -> None:
    ud = smach.UserData()
    r = smach.Remapper(ud, [], ["out"], {"out": "target"})
    r.out = 1
    assert ud.target == 1
    r["out"] = 2
    assert ud.target == 2
    assert "out" not in ud


def test_remapper_undeclared_read_raises_invalid_user_code_error() -> None:
    ud = smach.UserData()
    ud.secret = 1
    r = smach.Remapper(ud, ["declared_in"], ["secret"])
    with pytest.raises(smach.InvalidUserCodeError) as info:
        r.secret  # noqa: B018
    assert "secret" in str(info.value)
    assert "declared_in" in str(info.value)
    assert isinstance(info.value, KeyError)
    assert not hasattr(r, "secret")
    with pytest.raises(smach.InvalidUserCodeError):
        r["secret"]


def test_remapper_undeclared_write_raises_naming_key_and_declared_keys() -> None:
    ud = smach.UserData()
    r = smach.Remapper(ud, ["a"], ["declared_out"])
    with pytest.raises(smach.InvalidUserCodeError) as info:
        r.other = 1
    message = str(info.value)
    assert "other" in message
    assert "declared_out" in message
    assert "other" not in ud


def test_remapper_input_only_key_write_raises() -> None:
    ud = smach.UserData()
    ud.a = 1
    r = smach.Remapper(ud, ["a"], [])
    with pytest.raises(smach.InvalidUserCodeError):
        r.a = 2
    assert ud.a == 1


def test_remapper_declared_but_missing_key_lists_available_keys() -> None:
    ud = smach.UserData()
    ud.there = 1
    r = smach.Remapper(ud, ["k"], [], {"k": "remote"})
    with pytest.raises(KeyError) as info:
        r.k  # noqa: B018
    assert isinstance(info.value, AttributeError)
    assert "there" in str(info.value)
    assert not hasattr(r, "k")


def test_remapper_contains_only_declared_inputs_that_exist() -> None:
    ud = smach.UserData()
    ud.x = 1
    ud.y = 2
    r = smach.Remapper(ud, ["a", "missing"], [], {"a": "x"})
    assert "a" in r
    assert "y" not in r
    assert "missing" not in r


def test_remapper_keys_are_state_local_names() -> None:
    ud = smach.UserData()
    ud.x = 1
    ud.unrelated = 2
    r = smach.Remapper(ud, ["a", "b"], [], {"a": "x"})
    assert r.keys() == ["a"]
    assert dict(r) == {"a": 1}


def test_remapper_update_forwards_to_userdata() -> None:
    ud = smach.UserData()
    r = smach.Remapper(ud, [], [])
    r.update({"z": 1})
    assert ud.z == 1


def test_remapper_getattr_default_works_for_missing_declared_key_only() -> None:
    r = smach.Remapper(smach.UserData(), ["a"], [])
    assert getattr(r, "a", 7) == 7
    assert getattr(r, "undeclared", 7) == 7  # also an AttributeError, so hasattr() works
    with pytest.raises(smach.InvalidUserCodeError):
        r.undeclared  # noqa: B018


def test_userdata_keys_named_like_dict_methods_are_plain_keys() -> None:
    ud = smach.UserData()
    ud.items = [1, 2]
    ud.get = "fetch"
    assert ud.items == [1, 2]
    assert ud.get == "fetch"
    r = smach.Remapper(ud, ["items"], [])
    assert r.items == [1, 2]


def test_remapper_is_a_live_view() -> None:
    ud = smach.UserData()
    r = smach.Remapper(ud, ["a"], ["a"])
    ud.a = 1
    assert r.a == 1
    r.a = 2
    assert ud.a == 2


def test_remapper_cannot_be_pickled() -> None:
    r = smach.Remapper(smach.UserData(), [], [])
    with pytest.raises(TypeError):
        pickle.dumps(r)


def test_remapper_underscore_data_is_underlying_dict() -> None:
    ud = smach.UserData()
    ud.a = 1
    assert smach.Remapper(ud, [], [])._data is ud._data


def test_nested_remappers_compose_reads_and_writes() -> None:
    # smach_ros states wrap the Remapper they receive in another one for their
    # callbacks; both levels of remapping and key checks must apply.
    ud = smach.UserData()
    ud.outer = 3
    r1 = smach.Remapper(ud, ["mid"], ["mid"], {"mid": "outer"})
    r2 = smach.Remapper(r1, ["inner"], ["inner"], {"inner": "mid"})
    assert "inner" in r2
    assert r2.inner == 3
    r2.inner = 4
    assert ud.outer == 4
    assert "mid" not in ud._data


def test_nested_remapper_cannot_bypass_outer_declarations() -> None:
    ud = smach.UserData()
    ud.hidden = 1
    r1 = smach.Remapper(ud, ["visible"], ["visible"])
    r2 = smach.Remapper(r1, ["hidden"], ["hidden"])
    with pytest.raises(smach.InvalidUserCodeError):
        r2.hidden  # noqa: B018
    with pytest.raises(smach.InvalidUserCodeError):
        r2.hidden = 2
    assert ud.hidden == 1


# -- Const: input-only keys are read-only ----------------------------------------------------


def test_input_only_key_returns_read_only_view_of_objects() -> None:
    ud = smach.UserData()
    obj = Obj()
    ud.o = obj
    r = smach.Remapper(ud, ["o"], [])
    view = r.o
    assert view.field == 1
    assert view.inner.value == 2
    with pytest.raises(smach.InvalidUserCodeError):
        view.field = 5
    with pytest.raises(smach.InvalidUserCodeError):
        view.inner.value = 5
    with pytest.raises(smach.InvalidUserCodeError):
        del view.field
    assert obj.field == 1
    assert obj.inner.value == 2


def test_io_key_returns_the_object_itself() -> None:
    ud = smach.UserData()
    obj = Obj()
    ud.o = obj
    r = smach.Remapper(ud, ["o"], ["o"])
    assert r.o is obj
    r.o.field = 5
    assert obj.field == 5


def test_input_only_plain_values_are_returned_as_is() -> None:
    ud = smach.UserData()
    lst = [1]
    ud.lst = lst
    ud.n = 3
    r = smach.Remapper(ud, ["lst", "n"], [])
    assert r.lst is lst
    assert r.n == 3
    # Mutating methods pass through, as in the original.
    r.lst.append(2)
    assert lst == [1, 2]


def test_const_equality_and_hash_follow_the_object() -> None:
    obj = Inner()
    view = get_const(obj)
    assert isinstance(view, Const)
    assert view == obj
    assert view == get_const(obj)
    assert hash(view) == hash(obj)


def test_get_const_does_not_wrap_plain_values_or_callables() -> None:
    for value in (1, "s", None, (1,), [1], {"a": 1}, len):
        assert get_const(value) is value
