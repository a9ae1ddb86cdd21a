"""Compiled code is cached across processes and never goes stale (skfem_flex.numerics.jit_cache).

Each test works on a copy of the package in a temporary folder and runs fresh
Python processes, as a user's successive runs would.
"""
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import skfem_flex

CALLEE = textwrap.dedent('''
    import numba


    @numba.njit(cache=True)
    def factor():
        return {value}
''')
CALLER = textwrap.dedent('''
    import numba

    from .kernel_callee import factor


    @numba.njit(cache=True)
    def scaled(x):
        return factor() * x
''')
REPORT = ("import json, {package}.kernel_caller as m; v = m.scaled(1.0); "
          "print(json.dumps([v, sum(m.scaled.stats.cache_hits.values()), m.scaled.stats.cache_path]))")


def copy_package(tmp_path):
    """The package copied without caches, plus a two-file kernel: ``scaled`` (caller) calls ``factor``."""
    root = tmp_path / "site"
    shutil.copytree(Path(skfem_flex.__file__).parent, root / "skfem_flex",
                    ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    write_kernel(root / "skfem_flex", 2.0)
    return root


def write_kernel(folder, value):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "kernel_callee.py").write_text(CALLEE.format(value=value))
    (folder / "kernel_caller.py").write_text(CALLER)


def run(root, package="skfem_flex", env=None):
    """(scaled(1.0), cache hits of ``scaled``, its cache folder) in a fresh process."""
    env = dict(os.environ, PYTHONPATH=str(root), **(env or {}))
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", REPORT.format(package=package)], env=env, cwd=str(root),
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_edited_kernel_is_used_by_the_next_process(tmp_path):
    root = copy_package(tmp_path)
    assert run(root)[:2] == [2.0, 0]                  # compiled and cached
    assert run(root)[:2] == [2.0, 1]                  # the next process loads it from the cache
    write_kernel(root / "skfem_flex", 3.0)            # edit the callee only; the caller's file is unchanged
    value, hits, _ = run(root)
    assert value == 3.0 and hits == 0                 # recompiled, no stale machine code
    assert run(root)[:2] == [3.0, 1]


def test_plain_numba_would_keep_the_stale_caller(tmp_path):
    """The reason for the package's rule: outside it, numba keys the caller's cache to the caller's
    file alone and keeps returning the old callee's result after the callee is edited."""
    root = tmp_path / "site"
    write_kernel(root / "plain", 2.0)
    (root / "plain" / "__init__.py").write_text("")
    assert run(root, "plain")[:2] == [2.0, 0]
    write_kernel(root / "plain", 3.0)
    assert run(root, "plain")[0] == 2.0


def test_read_only_install_caches_in_the_user_folder(tmp_path):
    """Where the package's folder takes no cache (here a file blocks ``__pycache__``), compiled code goes
    to the user's cache folder and the next process loads it from there instead of compiling again."""
    root = copy_package(tmp_path)
    (root / "skfem_flex" / "__pycache__").write_text("not a folder")
    user = tmp_path / "user-cache"
    env = {"XDG_CACHE_HOME": str(user)}
    value, hits, path = run(root, env=env)
    assert value == 2.0 and hits == 0
    assert Path(path).is_relative_to(user) and any(Path(path).glob("*.nbi"))
    assert run(root, env=env)[:2] == [2.0, 1]
