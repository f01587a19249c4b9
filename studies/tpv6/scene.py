"""The scene of the TPV6 study (studies/tpv6/run.py): ``scenes.tpv6`` with each side's
face motion recorded at its stations, the rupture time of the whole fault and the final
fields."""
from __future__ import annotations

FORMULATION = "auto"      # tpv6's own choice: the product scheme (the only one for two materials)
ENGINE = "exponential"
THRESHOLD = 1e-3          # m/s: rupture = first time the slip rate exceeds 1 mm/s
FACES = tuple(f"{k}_{c}_{side}" for k in ("u", "v") for side in ("top", "bottom") for c in (1, 2, 3))


def build_scene(dx, t_end=12.0, beta=None, domain=None):
    from cracklab.model.record import Record
    from cracklab.model.scene import Numerics
    from cracklab.scenes import tpv6

    extra = {} if domain is None else {"domain": tuple(float(x) for x in domain)}
    base = tpv6(dx=dx, t_end=t_end, beta=beta,
                numerics=Numerics(formulation=FORMULATION, engine=ENGINE, rupture_threshold=THRESHOLD), **extra)
    rec = Record(fields=("delta_1", "delta_2", "tau_2") + FACES, times=(base.nsteps * base.dt,),
                 stations=dict(base.record.stations))
    return base.replace(record=rec)
