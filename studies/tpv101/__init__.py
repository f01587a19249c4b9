"""SCEC TPV101 and TPV103 (docs/tpv101.md, docs/tpv103.md): ``python -m studies.tpv101.run``."""
