"""What every law gets from the protocol (laws/base.py) without writing it: the check of
its values' nesting, its registration and export, its example scene."""
from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass

import pytest

import cracklab
from cracklab import InputError, Scene
from cracklab.errors import MAX_NESTING
from cracklab.laws import LAWS
from cracklab.laws.base import Law, parameter


def _deep(levels):
    value = 1.0
    for _ in range(levels):
        value = [value]
    return value


@dataclass(frozen=True)
class _Plain(Law):
    """A law with no checks of its own."""

    x: object = parameter(kind="option", default=None)


@dataclass(frozen=True)
class _Checked(_Plain):
    """A law whose own check calls its base's, and refuses x = "no"."""

    calls = []

    def __post_init__(self):
        super().__post_init__()
        type(self).calls.append(self.x)
        if self.x == "no":
            raise InputError("law.x", "must not be 'no'")


@pytest.mark.parametrize("cls", [_Plain, _Checked] + sorted(LAWS.values(), key=lambda c: c.__name__))
def test_every_law_refuses_values_nested_too_deep_without_checking_it_itself(cls):
    # the required parameters 1.0 (the nesting is checked before any value), the mask too deep
    required = {f.name: 1.0 for f in dataclasses.fields(cls) if f.default is dataclasses.MISSING}
    name = "bonded" if "bonded" in cls.parameters() else "x"
    with pytest.raises(InputError) as err:
        cls(**required, **{name: _deep(MAX_NESTING + 1)})
    assert err.value.field == f"law.{name}" and "nest" in str(err.value)


def test_a_laws_own_checks_run_after_the_nesting_check_once():
    _Checked.calls.clear()
    with pytest.raises(InputError, match="law.x"):
        _Checked(x=_deep(MAX_NESTING + 1))
    assert _Checked.calls == []          # refused before the law's own check
    _Checked(x=[1.0])
    assert _Checked.calls == [[1.0]]     # its own check once (the base's too: no second nesting pass)
    with pytest.raises(InputError, match="must not be 'no'"):
        _Checked(x="no")


def test_the_package_root_exports_every_law():
    for kind, cls in LAWS.items():
        assert getattr(cracklab, cls.__name__) is cls, kind
        assert cls.__name__ in cracklab.__all__


@pytest.mark.parametrize("kind", sorted(LAWS))
def test_every_law_gives_an_example_scene_of_itself(kind):
    text = LAWS[kind].example
    assert tomllib.loads(text)["law"]["kind"] == kind
    assert type(Scene.from_toml(text).law) is LAWS[kind]
