"""SCEC TPV101 and TPV103 (docs/studies/tpv101.md, docs/studies/tpv103.md): ``python -m studies.tpv101.run``."""
