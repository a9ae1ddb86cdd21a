"""Settings for the whole suite."""
import os

# The suite runs on two pytest-xdist workers, one per core of the 2-core machine it is sized for: a
# second compile process per worker (skfem_flex.compiled.ahead) would only oversubscribe the cores.
# tests/test_compile_ahead.py sets it to 2 where it tests that path.
os.environ.setdefault("SKFEM_FLEX_COMPILE_PROCESSES", "1")
