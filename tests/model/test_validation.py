"""Bad input ends with one clear error naming the field (issue: bad input)."""
import numpy as np
import pytest

from cracklab import Grid, InputError, Loading, Material, Record, Scene, TractionFree
from cracklab import LinearCohesive, scenes
from cracklab.model.scene_io import scene_from_data, scene_to_data


def small_scene(**changes):
    grid = Grid(n1=16, n3=16, L1=1.0, L3=1.0)
    base = dict(material=Material(mu=1, cs=1, nu=0.25), grid=grid, law=TractionFree(),
                loading=Loading(tau0_2=1.0), t_end=0.1)
    base.update(changes)
    return Scene(**base)


def test_valid_scene_roundtrip_through_data():
    scene = scenes.elliptical_crack(n=32, a=0.2, b=0.1, t_end=0.1)
    data, arrays = scene_to_data(scene)
    again = scene_from_data(data, arrays)
    assert again.grid == scene.grid and again.material == scene.material
    assert np.array_equal(again.law.bonded, scene.law.bonded)
    assert np.array_equal(again.loading.tau0_2, scene.loading.tau0_2)


@pytest.mark.parametrize("mutate, field", [
    (lambda d: d.update(colour="red"), "colour"),
    (lambda d: d["grid"].update(spacing=2), "grid.spacing"),
    (lambda d: d["law"].update(tau_c=1), "law.tau_c"),
    (lambda d: d["grid"].update(n1=-16), "grid.n1"),
    (lambda d: d["grid"].update(L3=-1.0), "grid.L3"),
    (lambda d: d["grid"].update(n1=17), "grid.n1"),
    (lambda d: d.update(t_end=-1.0), "t_end"),
    (lambda d: d.update(beta=0.9), "beta"),
    (lambda d: d["law"].update(kind="glue"), "law.kind"),
    (lambda d: d["record"].update(fields=["opening"]), "record.fields"),
])
def test_bad_scene_data(mutate, field):
    data, arrays = scene_to_data(small_scene())
    mutate(data)
    with pytest.raises(InputError) as err:
        scene_from_data(data, arrays)
    assert str(err.value).startswith(field + ":")


def test_wrong_field_shape_is_named():
    with pytest.raises(InputError, match=r"loading.tau0_2: field shape must be \(n1, n3\) = \(16, 16\)"):
        small_scene(loading=Loading(tau0_2=np.ones((8, 8))))
    with pytest.raises(InputError, match="law.tau_c: field shape"):
        small_scene(law=LinearCohesive(tau_c=np.ones((4, 4)), delta_c=1.0))


def test_negative_law_parameter_is_named():
    with pytest.raises(InputError, match="law.tau_c: must be > 0, got -1"):
        LinearCohesive(tau_c=-1, delta_c=1.0)


def test_unstable_beta_names_range():
    with pytest.raises(InputError) as err:
        small_scene(beta=0.8)
    assert str(err.value).startswith("beta: must be in (0, 0.5")


def test_load_on_component_law_cannot_carry():
    with pytest.raises(InputError, match="loading.tau0_1"):
        small_scene(law=LinearCohesive(tau_c=1.0, delta_c=1.0), loading=Loading(tau0_1=1.0, tau0_2=1.0))


def test_record_outside_grid():
    with pytest.raises(InputError, match="record.stations.far"):
        small_scene(record=Record(stations={"far": (2.0, 0.5)}))


def test_constant_K_needs_a_length():
    with pytest.raises(InputError, match="loading.l0"):
        small_scene(law=LinearCohesive(tau_c=1.0, delta_c=1.0), loading=Loading(tau0_2=1.0, constant_K=True))
