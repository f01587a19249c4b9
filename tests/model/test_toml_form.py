"""What a person reads in a scene's TOML, and the errors a misplaced key gives."""
from __future__ import annotations

import pytest

import cracklab
from cracklab import InputError, Record, Scene
from cracklab.model.scene_io import scenes_equal


def test_a_station_is_one_line_and_a_field_one_line_a_row():
    rec = Record(fields=("delta_2", "v_2"), stations={"A": (0.5, 0.5), "B": (0.25, 0.5)})
    scene = cracklab.scenes.lamb(n=4, t_end=0.1, record=rec)
    text = scene.to_toml()
    lines = text.splitlines()
    assert "A = [0.5, 0.5]" in lines and "B = [0.25, 0.5]" in lines
    assert 'fields = ["delta_2", "v_2"]' in lines
    assert "    [0.0, 0.0, 16.0, 0.0]," in lines          # the point load of 1/(dx1 dx3) = 16
    assert scenes_equal(Scene.from_toml(text), scene)


def test_a_string_with_brackets_and_commas_survives():
    rec = Record(stations={"a, [b]": (0.5, 0.5)})
    scene = cracklab.scenes.lamb(n=4, t_end=0.1, record=rec).replace(name='x = [1,\n 2]')
    assert scenes_equal(Scene.from_toml(scene.to_toml()), scene)


def test_t_end_under_units_is_named_as_a_stray_key():
    scene = cracklab.scenes.lamb(n=4, t_end=0.1)
    text = scene.to_toml().replace("\nt_end = 0.1\n", "\n")
    text = text.replace('stress = "1"\n', 'stress = "1"\nt_end = 0.1\n')
    with pytest.raises(InputError) as err:
        Scene.from_toml(text)
    assert err.value.field == "units.t_end" and "unknown key" in str(err.value)
