"""Schemes and interface types carry their own facts and register themselves
(solver/schemes/base.py, solver/interfaces/base.py): what the rest of the code asks of them."""
from dataclasses import fields

import numpy as np
import pytest

import cracklab
from cracklab import Grid, InputError, Loading, Material, Numerics, Scene, TractionFree
from cracklab.model.scene import FORMULATIONS
from cracklab.solver import stability
from cracklab.solver.budget import run_memory
from cracklab.solver.interfaces import TYPES, Bimaterial, Identical, interface_type
from cracklab.solver.schemes import SCHEMES, Run, Scheme, register, scheme_of
from cracklab.solver.stepper import Stepper

M = Material(mu=1.0, cs=1.0, nu=0.25)
SOFT = Material(mu=0.6, cs=0.8, nu=0.3)


def test_every_scheme_file_registers_its_scheme_in_the_order_of_the_formulations():
    assert list(SCHEMES) == ["displacement", "velocity", "product", "product2"]
    assert list(FORMULATIONS) == list(SCHEMES)
    for name, scheme in SCHEMES.items():
        assert scheme.name == name and scheme_of(name) is scheme and scheme_of(scheme) is scheme
        assert stability.LIMITS[name] is scheme.limits
        Numerics(formulation=name)      # a value of Numerics.formulation


def test_a_second_scheme_of_a_name_is_refused():
    class Again(Scheme):
        name = "product"

    with pytest.raises(ValueError, match="two schemes are named 'product'"):
        register(Again)
    assert type(SCHEMES["product"]).__name__ == "Product"


def test_schemes_say_what_they_need_of_the_run():
    # the product schemes step the law on trial slips (where it reads the slip); product2 also
    # at the step's mean velocity; only the displacement scheme takes another convolution rule
    assert {n for n, s in SCHEMES.items() if s.needs_trial_slips} == {"product", "product2"}
    assert {n for n, s in SCHEMES.items() if s.mean_velocity} == {"product2"}
    assert {n for n, s in SCHEMES.items() if s.any_rule} == {"displacement"}
    # product2 has the product scheme's linear recurrence: its limits
    assert stability.gamma_max("product2", "II", 0.25) == stability.gamma_max("product", "II", 0.25)


def test_the_stepper_hands_a_scheme_its_declared_run_not_itself(monkeypatch):
    sc = cracklab.scenes.lamb(n=8, t_end=0.05, numerics=Numerics(formulation="product"))
    scheme = SCHEMES["product"]
    seen = []
    estimate = type(scheme).estimate

    def spy(self, run, n, t):
        seen.append(run)
        return estimate(self, run, n, t)

    monkeypatch.setattr(type(scheme), "estimate", spy)
    stepper = Stepper(sc)
    for _ in stepper:
        pass
    assert seen and all(run is stepper.run for run in seen) and isinstance(seen[0], Run)
    assert not hasattr(seen[0], "__dict__") and not hasattr(seen[0], "scene")   # slots: its fields only
    assert {f.name for f in fields(Run)} >= {"delta", "v", "tau", "lstate", "load", "response", "dt"}
    assert stepper.delta is stepper.run.delta and stepper.lstate is stepper.run.lstate


def test_exactly_one_interface_type_takes_a_pair_of_materials():
    assert set(TYPES) == {Identical, Bimaterial}
    assert interface_type(M) is Identical and interface_type((M, M)) is Identical
    assert interface_type((M, SOFT)) is Bimaterial and interface_type([SOFT, M]) is Bimaterial


def test_interface_types_carry_the_schemes_margin_and_budget_they_accept():
    assert all(Identical.accepts_scheme(s) for s in SCHEMES.values())
    assert [n for n, s in SCHEMES.items() if Bimaterial.accepts_scheme(s)] == ["product", "product2"]
    assert (Identical.margin, Bimaterial.margin) == (1.0, 0.9)
    assert Identical.energy_refusal is None and "two" in Bimaterial.energy_refusal
    assert (Identical.holds_faces, Bimaterial.holds_faces) == (False, True)
    with pytest.raises(InputError, match=r"numerics.formulation: a pair of different materials runs the product "
                                         r"scheme \('product' or 'product2'\); got 'velocity'"):
        Scene(materials=(M, SOFT), grid=Grid(n1=8, n3=1, L1=1.0, L3=1.0), law=TractionFree(),
              loading=Loading(tau0_1=1.0), t_end=0.1, numerics=Numerics(formulation="velocity"))


def test_the_memory_estimate_counts_each_faces_engines_of_two_materials():
    """The identical pair: one engine per channel (II and III in 3D shear); two materials:
    each face's L, N, LN, NL and T channels of its own material, ten engines."""
    g = Grid(n1=16, n3=16, L1=1.0, L3=1.0)
    one = Scene(material=M, grid=g, law=TractionFree(), loading=Loading(tau0_1=1.0), t_end=0.2,
                beta=0.25, numerics=Numerics(formulation="product", engine="direct"))
    two = one.replace(materials=(M, SOFT))
    assert [k for k, _ in Identical.engine_channels(one)] == ["II", "III"]
    assert [k for k, m in Bimaterial.engine_channels(two)] == ["H11", "H22", "H12", "H12", "III"] * 2
    assert [m for _, m in Bimaterial.engine_channels(two)] == [M] * 5 + [SOFT] * 5
    # the direct engine's history is the same per engine of the same length: five times as much
    assert run_memory(two).history == pytest.approx(5 * run_memory(one).history, rel=0.01)
    assert np.isfinite(run_memory(two).total)


def test_the_run_holds_no_reference_back_to_its_stepper():
    """A finished Stepper, its interface and engines are freed when the last reference goes,
    without waiting for the cycle collector (sweeps run members one after the other)."""
    import gc
    import weakref

    sc = cracklab.scenes.lamb(n=8, t_end=0.05)
    stepper = Stepper(sc)
    for _ in stepper:
        pass
    refs = weakref.ref(stepper), weakref.ref(stepper.response)
    gc.disable()
    try:
        del stepper, _
        assert all(r() is None for r in refs)
    finally:
        gc.enable()
