"""Scene builders: Lamb's problem, the suddenly loaded elliptical crack, SCEC TPV3 and TPV5
(a free surface by mirror symmetry), SCEC TPV6 (a bimaterial fault under a free surface),
SCEC TPV101-TPV104 (rate-and-state friction; TPV102 and TPV104 below a free surface), SEAS
BP1 and BP5 (sequences of earthquakes, ``seas``), the plane test problems used in verification,
and the crack-growth problems of section 4 (a row of tough asperities, random toughness;
see docs/reference/scenes.md).

Modules: ``paper`` (the paper's problems), ``scec`` (the SCEC benchmarks), ``seas`` (the
SEAS benchmarks), ``fronts`` (the crack-growth problems), ``registry`` (``BUILDERS``, the
builders a study file may name, and the builders registered with
``cracklab.register_builder``), ``common``.
"""
from .common import UNIT, BuilderWarning
from .fronts import (COVARIANCES, DISTRIBUTIONS, asperity_mask, asperity_row, cohesive_zone_size, random_field,
                     random_toughness)
from .paper import ellipse_mask, elliptical_crack, kostrov, lamb, periodic_cracks
from .registry import BUILDERS
from .seas import BP1_DEPTHS, BP5_STATIONS, YEAR, bp1, bp1_station_name, bp5, bp5_station_name
from .scec import (TPV3_STATIONS, TPV5_PATCHES, TPV5_REFERENCE_STATIONS, TPV5_STATIONS, TPV6_FAR, TPV6_NEAR,
                   TPV6_REFERENCE_STATIONS, TPV6_STATIONS, TPV101_STATIONS, TPV_HYPO_DEPTH, taper,
                   tpv3, tpv3_station_name, tpv5, tpv6, tpv101, tpv102, tpv103, tpv104)

__all__ = ["BUILDERS", "UNIT", "BuilderWarning",
           "lamb", "ellipse_mask", "elliptical_crack", "periodic_cracks", "kostrov",
           "tpv3", "tpv5", "tpv6", "tpv101", "tpv102", "tpv103", "tpv104", "tpv3_station_name", "taper",
           "bp1", "bp1_station_name", "BP1_DEPTHS", "bp5", "bp5_station_name", "BP5_STATIONS", "YEAR",
           "TPV3_STATIONS", "TPV5_REFERENCE_STATIONS", "TPV5_STATIONS", "TPV5_PATCHES",
           "TPV6_REFERENCE_STATIONS", "TPV6_STATIONS", "TPV6_NEAR", "TPV6_FAR", "TPV101_STATIONS",
           "TPV_HYPO_DEPTH",
           "asperity_row", "random_toughness", "asperity_mask", "random_field", "cohesive_zone_size",
           "COVARIANCES", "DISTRIBUTIONS"]
