"""The project's studies. The benchmark studies (``studies.tpv3``, ``studies.tpv5``,
``studies.tpv6``, ``studies.tpv101``) and their harness (``studies.benchmarks``) are
packages run from the repository's root as modules, e.g. ``python -m studies.tpv3.run``."""
