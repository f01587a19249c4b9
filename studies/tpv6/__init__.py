"""SCEC TPV6 against MDSBI (docs/tpv6.md): ``python -m studies.tpv6.run``; the surface study ``python -m studies.tpv6.surface``."""
