"""The command line (``bragg-explorer``, ``python3 -m explorer``) and the app's entry point."""

import os

# One OpenBLAS thread unless the user asks for more: the host tables' matrix products are small, and idle
# OpenBLAS workers spin on the cores that llvmpipe renders on. On this project's 2-core machine two
# threads doubled the CPU time of a table rebuild and made a layer's tables 30 % slower
# (`bench --tables`, docs/performance.md). Set before numpy loads OpenBLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
