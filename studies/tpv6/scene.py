"""The scene of the TPV6 study (studies/tpv6/run.py): ``scenes.tpv6`` with each side's
face motion recorded at its stations, the rupture time of the whole fault and the final
fields."""
from __future__ import annotations

FORMULATION = "product2"  # the builder's: rupture fronts at second order in dt (docs/stability.md)
ENGINE = "exponential"
THRESHOLD = 1e-3          # m/s: rupture = first time the slip rate exceeds 1 mm/s
FACES = tuple(f"{k}_{c}_{side}" for k in ("u", "v") for side in ("top", "bottom") for c in (1, 2, 3))


def build_scene(dx, t_end=12.0, beta=None, domain=None, normal=None):
    """``normal``: the regularised normal stress of the friction law, {"normal_slip_scale":
    L*, "normal_time": t*} (either or both; None: the law as the benchmark states it)."""
    import dataclasses

    from cracklab.model.record import Record
    from cracklab.model.scene import Numerics
    from cracklab.scenes import tpv6

    extra = {} if domain is None else {"domain": tuple(float(x) for x in domain)}
    base = tpv6(dx=dx, t_end=t_end, beta=beta,
                numerics=Numerics(formulation=FORMULATION, engine=ENGINE, rupture_threshold=THRESHOLD), **extra)
    rec = Record(fields=("delta_1", "delta_2", "tau_2") + FACES, times=(base.nsteps * base.dt,),
                 stations=dict(base.record.stations))
    law = base.law if not normal else dataclasses.replace(base.law, **normal)
    return base.replace(record=rec, law=law)
