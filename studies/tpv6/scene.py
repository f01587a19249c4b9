"""The scene of the TPV6 study (studies/tpv6/run.py): ``scenes.tpv6`` with each side's
face motion recorded at its stations, the rupture time of the whole fault and the final
fields."""
from __future__ import annotations

from studies.benchmarks import harness as H

FORMULATION = "product2"  # the builder's: rupture fronts at second order in dt (docs/reference/stability.md)
ENGINE = "exponential"
#: the cell of the runs on docs/studies/tpv6.md (the builder's default until issue 34 point 15
#: made it 80 km x 40 km; docs/studies/tpv7_contrast.md gives the images' effect at this one)
DOMAIN = (48000.0, 24000.0)
FACES = tuple(f"{k}_{c}_{side}" for k in ("u", "v") for side in ("top", "bottom") for c in (1, 2, 3))


def build_scene(dx, t_end=12.0, beta=None, domain=None, normal=None):
    """``normal``: the regularised normal stress of the friction law, {"normal_slip_scale":
    L*, "normal_time": t*} (either or both; None: the law as the benchmark states it)."""
    import dataclasses

    from cracklab.scenes import tpv6

    base = H.build(tpv6, dx, t_end=t_end, domain=domain or DOMAIN, fields=("delta_1", "delta_2", "tau_2") + FACES, beta=beta,
                   numerics=H.numerics(FORMULATION, ENGINE))
    return base if not normal else base.replace(law=dataclasses.replace(base.law, **normal))
