"""SCEC TPV3 against MDSBI (docs/tpv3.md): ``python -m studies.tpv3.run``."""
