"""SCEC TPV3 against MDSBI (docs/studies/tpv3.md): ``python -m studies.tpv3.run``."""
