"""SCEC TPV5 against MDSBI (docs/studies/tpv5.md): ``python -m studies.tpv5.run``."""
