"""What the benchmark studies share: ``harness`` (reference folders, runs and stores, the
command line, the page's and figures' common pieces) and ``measures`` (the slip-weakening
benchmarks' series measures and acceptance check)."""
