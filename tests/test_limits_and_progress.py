"""Limits the run must respect and what it shows while running (issue: nothing lost, nothing silent).

- memory: the least of the system's free memory, the cgroup limit and the address-space limit
  (``skfem_flex.numerics.resources.available_memory``), so that a container or ``ulimit -v`` refuses a
  request with a sentence instead of a MemoryError or a kill;
- checkpoints: the wait after a save grows with the time the save took (no quadratic cost);
- stability study: plain case names listed by ``study --help``; a cold Numba cache's compile is
  not counted against a case's wall-clock budget;
- progress bar: no rate measured over the compile;
- CLI: Python warnings are one line on stderr.
"""
import importlib
import keyword
import re
import resource
import subprocess
import sys
import time
import warnings

import pytest

import skfem_flex as sf
from skfem_flex.apps import cli
from skfem_flex.apps.cli import catalogue as cli_list
from skfem_flex.run import driver
from skfem_flex.numerics import resources
from skfem_flex.apps import studies
from skfem_flex.apps.studies import stability_study
from skfem_flex.numerics.resources import InsufficientMemoryError
from skfem_flex.io.result import Result

from helpers import package_env

simulate_module = importlib.import_module("skfem_flex.run.driver")      # the run's clock
budget_module = importlib.import_module("skfem_flex.apps.sweep.budget")
task_module = importlib.import_module("skfem_flex.apps.sweep.task")

SYSTEM = 64_000_000_000           # bytes the (fake) system reports available: more than any limit below


# ------------------------------------------------------------------ 1. memory limits
def _only(monkeypatch, system=SYSTEM, cgroup=None, rlimit=None):
    """available_memory() sees only these sources (None: that source sets no limit)."""
    monkeypatch.setattr(resources, "_system_available", lambda: system)
    if cgroup is not True:
        monkeypatch.setattr(resources, "_cgroup_available", lambda: cgroup)
    if rlimit is not True:
        monkeypatch.setattr(resources, "_rlimit_available", lambda: rlimit)


def _write(directory, **files):
    directory.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (directory / name.replace("_", ".", 1)).write_text(text)


def test_cgroup_v2_limit_wins(tmp_path, monkeypatch):
    """memory.max − (memory.current − inactive file cache) below MemAvailable is what a request gets."""
    _only(monkeypatch, cgroup=True)
    monkeypatch.setattr(resources, "CGROUP_ROOT", tmp_path)
    monkeypatch.setattr(resources, "_own_cgroups", lambda: {"": "/"})
    _write(tmp_path, memory_max="2000000000\n", memory_current="1500000000\n",
           memory_stat="anon 1400000000\ninactive_file 100000000\nactive_file 0\n")
    assert resources.available_memory() == 600_000_000
    with pytest.raises(InsufficientMemoryError, match=r"a mesh needs about 1 GB.*only 600 MB"):
        resources.check_fits(1e9, "a mesh")
    resources.check_fits(5e8, "a smaller mesh")              # fits: no error
    (tmp_path / "memory.max").write_text("max\n")             # no limit in this cgroup
    assert resources.available_memory() == SYSTEM


def test_cgroup_v1_limit_of_an_ancestor_counts(tmp_path, monkeypatch):
    """cgroup v1: the process's own group is unlimited (2⁶³ rounded to pages), its parent is not;
    unreadable or non-numeric files are no limit."""
    _only(monkeypatch, cgroup=True)
    monkeypatch.setattr(resources, "CGROUP_ROOT", tmp_path)
    monkeypatch.setattr(resources, "_own_cgroups", lambda: {"memory": "/batch/job7", "": "/"})
    unlimited = "9223372036854771712\n"
    _write(tmp_path / "memory", memory_limit_in_bytes=unlimited, memory_usage_in_bytes="20000000000\n")
    _write(tmp_path / "memory" / "batch", memory_limit_in_bytes="1000000000\n",
           memory_usage_in_bytes="700000000\n", memory_stat="total_inactive_file 0\n")
    _write(tmp_path / "memory" / "batch" / "job7", memory_limit_in_bytes=unlimited,
           memory_usage_in_bytes="650000000\n")
    assert resources.available_memory() == 300_000_000
    (tmp_path / "memory" / "batch" / "memory.limit_in_bytes").write_text("garbage\n")
    assert resources.available_memory() == SYSTEM


def test_no_cgroup_files_is_no_limit(tmp_path, monkeypatch):
    _only(monkeypatch, cgroup=True)
    monkeypatch.setattr(resources, "CGROUP_ROOT", tmp_path / "absent")
    assert resources._cgroup_available() is None
    assert resources.available_memory() == SYSTEM


def test_address_space_limit_wins(monkeypatch):
    """A finite RLIMIT_AS soft limit minus the process's size caps what is available."""
    _only(monkeypatch, rlimit=True)
    monkeypatch.setattr(resources, "_process_size", lambda: 1_000_000_000)
    monkeypatch.setattr(resource, "getrlimit", lambda which: (3_000_000_000, resource.RLIM_INFINITY))
    assert resources.available_memory() == 2_000_000_000
    with pytest.raises(InsufficientMemoryError, match="only 2 GB"):
        resources.check_fits(2.5e9, "a run")
    monkeypatch.setattr(resource, "getrlimit", lambda which: (resource.RLIM_INFINITY, resource.RLIM_INFINITY))
    assert resources.available_memory() == SYSTEM
    # all limits at once: the least wins
    _only(monkeypatch, system=5_000_000_000, cgroup=4_000_000_000, rlimit=3_000_000_000)
    assert resources.available_memory() == 3_000_000_000


def test_process_size_without_proc_is_the_peak_rss(monkeypatch):
    """Without /proc/self/statm the size used against RLIMIT_AS is the peak resident size (an estimate)."""
    assert resources._process_size() > 0
    read = resources._read_text
    monkeypatch.setattr(resources, "_read_text", lambda path: None if "statm" in str(path) else read(path))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * (1 if sys.platform == "darwin" else 1024)
    assert resources._process_size() >= peak > 0


def test_address_space_limit_refuses_cleanly_in_a_subprocess(tmp_path):
    """Under ``ulimit -v`` 1.5 GB (RLIMIT_AS set before importing skfem_flex) a beam of 10⁵ elements
    is refused with one line naming it and the memory left, exit status 2 — not a MemoryError after
    half a minute of allocating (exit 1) or a kill."""
    code = ("import resource, sys\n"
            "resource.setrlimit(resource.RLIMIT_AS, (int(1.5 * 2**30), resource.RLIM_INFINITY))\n"
            "from skfem_flex.apps import cli\n"
            f"sys.exit(cli.main(['run', 'spin_up_beam', '--set', 'n_elements=100000', '--out', {str(tmp_path)!r}, "
            "'--quiet', '--no-vtk']))\n")
    env = package_env()
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("skfem-flex: error:"), proc.stderr
    assert "100000 elements" in lines[0] and "memory" in lines[0], proc.stderr
    left = re.search(r"only ([0-9.e+]+) (B|kB|MB|GB)", lines[0])
    assert left, proc.stderr
    units = {"B": 1, "kB": 1e3, "MB": 1e6, "GB": 1e9}
    assert float(left[1]) * units[left[2]] < 1.5 * 2 ** 30       # the address-space limit was counted


# ------------------------------------------------------------------ 2. checkpoint interval
class _FakeClock:
    """time for skfem_flex.run.driver: perf_counter is a counter the test advances."""

    def __init__(self):
        self.now = 0.0

    def perf_counter(self):
        return self.now

    def __getattr__(self, name):
        return getattr(time, name)


def test_checkpoint_waits_twenty_times_the_save(tmp_path, monkeypatch):
    """Saves that take longer as the history grows (here 10 ms per recorded step) are spaced by at
    least max(checkpoint_every, 20 × the last save's time), so they cost under 5 % of the run;
    with a fixed 1 s interval they would be nearly every step once a save takes a second."""
    clock = _FakeClock()
    monkeypatch.setattr(simulate_module, "time", clock)
    saves = []

    def slow_save(self, path):
        begin = clock.now
        clock.now += 0.01 * len(self.t)
        saves.append((begin, clock.now))

    class OneSecondPerStep:
        def write(self, scene, t, q, v):
            clock.now += 1.0

        def close(self):
            pass

    monkeypatch.setattr(Result, "save", slow_save)
    # the Python path checks for a checkpoint after every step (the compiled one after every chunk of
    # steps): a clock that advances per step shows the rule step by step
    res = sf.simulate(sf.scenes.pendulum(), 6.0, 0.01, output=[OneSecondPerStep()], checkpoint=tmp_path / "c.npz",
                      checkpoint_every=1.0, compiled=False)
    assert res.steps == 600 and len(saves) >= 5
    assert saves[0][0] >= 1.0
    # the last save is the run's end (a checkpoint always holds the end of a run); the scheduled ones before it
    assert saves[-1][0] >= 600.0
    saves = saves[:-1]
    for (b0, e0), (b1, _) in zip(saves, saves[1:]):
        assert b1 - e0 >= max(1.0, 20 * (e0 - b0)) - 1e-9, saves
    # every save but the last (the run may end before its wait is over) was paid for by 20 times its time
    spent = sum(e - b for b, e in saves[:-1])
    assert spent <= clock.now / 20, (spent, clock.now)


def test_cheap_checkpoints_keep_the_interval(tmp_path, monkeypatch):
    """Saves that take no time come every checkpoint_every seconds, as before."""
    clock = _FakeClock()
    monkeypatch.setattr(simulate_module, "time", clock)
    saves = []
    monkeypatch.setattr(Result, "save", lambda self, path: saves.append(clock.now))

    class OneSecondPerStep:
        def write(self, scene, t, q, v):
            clock.now += 1.0

        def close(self):
            pass

    sf.simulate(sf.scenes.pendulum(), 0.5, 0.01, output=[OneSecondPerStep()], checkpoint=tmp_path / "c.npz",
                checkpoint_every=3.0, compiled=False)
    # the scheduled saves, then the one at the run's end (a checkpoint always holds the end of a run)
    assert saves[-1] == clock.now
    saves = saves[:-1]
    gaps = [b - a for a, b in zip(saves, saves[1:])]
    assert len(saves) >= 10 and all(g == 3.0 for g in gaps), saves


# ------------------------------------------------------------------ 3. stability study
def test_stability_case_names_are_plain_and_listed_in_help(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    with pytest.raises(SystemExit) as stop:
        cli.main(["study", "--help"])
    assert stop.value.code == 0
    out = capsys.readouterr().out
    assert studies.STABILITY_CASES
    for name in studies.STABILITY_CASES:
        assert name.isascii() and name.isidentifier() and not keyword.iskeyword(name), name
        assert re.search(rf"(?<![\w.]){re.escape(name)}(?![\w.])", out), (name, out)


def test_stability_budget_does_not_count_the_compile(monkeypatch):
    """A cold cache: the first use of the compiled loop "compiles" for 1000 s of (fake) wall clock.
    The case still completes under a 30 s budget: the study compiles before the case's clock starts."""
    offset = [0.0]
    cold = [True]

    class Clock:
        def perf_counter(self):
            return time.perf_counter() + offset[0]

        def __getattr__(self, name):
            return getattr(time, name)

    real_stepper = driver.Stepper

    def stepper(*args, **kw):
        if cold[0]:                       # the compile happens while the run builds its stepper
            offset[0] += 1000.0
            cold[0] = False
        return real_stepper(*args, **kw)

    monkeypatch.setattr(budget_module, "time", Clock())      # the budget's clock
    monkeypatch.setattr(task_module, "time", Clock())        # the case's run time
    monkeypatch.setattr(driver, "Stepper", stepper)
    monkeypatch.setattr(stability_study, "QUICK_BUDGET", 30.0)
    rows = studies.stability(cases=["spin_up_omega4_dt5ms"], schemes=["energy-momentum"], quick=True, budget=30.0)
    assert not cold[0]                    # it did compile
    (row,) = rows
    assert row.completed and row.bounded and "budget" not in row.message, row
    assert row.wall_time < 1000.0, row


# ------------------------------------------------------------------ 4. progress bar
class _Bar:
    """A tqdm stand-in that logs what is done to it."""

    events = None

    def __init__(self, total=None, initial=0, **kw):
        self.events.append(("open", initial, total))

    def update(self, n=1):
        self.events.append(("update", n))

    def reset(self, total=None):
        self.events.append(("reset", total))

    def set_postfix_str(self, s="", refresh=True):
        pass

    def refresh(self, *a, **kw):
        pass

    def close(self):
        self.events.append(("close",))


def _logged_run(monkeypatch):
    import tqdm

    events = []
    monkeypatch.setattr(_Bar, "events", events)
    monkeypatch.setattr(tqdm, "tqdm", _Bar)
    real_chunk = driver.Run._chunk

    def chunk(self, k):
        events.append(("chunk", k))
        return real_chunk(self, k)

    monkeypatch.setattr(driver.Run, "_chunk", chunk)
    res = sf.simulate(sf.scenes.get("spin_up_beam")(), 0.2, 0.02, progress=True)
    return res, events


def test_bar_opens_after_the_compile_and_before_the_loop(monkeypatch):
    """The bar opens once the stepper is built (the compile is over), so no rate is measured over it."""
    res, events = _logged_run(monkeypatch)
    assert events[0] == ("open", 0, 10) and events[-1] == ("close",)
    assert sum(e[1] for e in events if e[0] == "update") == res.steps == 10
    assert [e[0] for e in events[:2]] == ["open", "chunk"]


# ------------------------------------------------------------------ 5. CLI warnings
def test_cli_warnings_are_one_line(capsys, monkeypatch):
    """A Python warning raised while the CLI works is one ``skfem-flex: warning:`` line on stderr (no
    file name, no source line), and main leaves warnings.showwarning as it found it."""
    def noisy(args):
        warnings.warn("a plot could not be drawn:\n  the axis is empty")
        warnings.warn("overflow encountered in multiply", RuntimeWarning)
        return 0

    monkeypatch.setattr(cli_list, "_cmd_list", noisy)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        before = warnings.showwarning
        assert cli.main(["list"]) == 0
        assert warnings.showwarning is before
    err = capsys.readouterr().err
    assert err.splitlines() == ["skfem-flex: warning: a plot could not be drawn: the axis is empty",
                                "skfem-flex: warning: RuntimeWarning: overflow encountered in multiply"], err
