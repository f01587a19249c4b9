"""SCEC TPV6 against MDSBI (docs/studies/tpv6.md): ``python -m studies.tpv6.run``; its surface study
``python -m studies.tpv6.surface``."""
