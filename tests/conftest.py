"""Settings for the whole suite, and one compile of the catalogue's kernels before the workers start."""
import os
import sys
import time

# The suite runs on two pytest-xdist workers, one per core of the 2-core machine it is sized for (a third
# was tried: no faster, and the sweep tests' bit-for-bit comparisons of Dask-worker runs with in-process runs
# then failed now and then; docs/performance.md, "The test suite"). A second compile process per worker
# (skfem_flex.compiled.ahead) would only oversubscribe the cores.
# tests/test_compile_ahead.py sets it to 2 where it tests that path.
os.environ.setdefault("SKFEM_FLEX_COMPILE_PROCESSES", "1")


def pytest_configure(config):
    """With workers (``-n``), compile what the catalogue's scenes need under every scheme once, on two
    processes, before the workers start. From a cold cache both workers would otherwise compile the same
    kernels side by side (a family compiles in 2-20 s), each for the first test that needs it. Tests that
    compile on purpose use an empty cache of their own and are not affected."""
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None) \
            or config.option.collectonly:
        return
    from helpers import warm_compile_cache
    start = time.perf_counter()
    made = warm_compile_cache()
    if made:
        sys.stderr.write(f"compiled {made} kernels of the catalogue in {time.perf_counter() - start:.0f} s "
                         f"before the workers start\n")
