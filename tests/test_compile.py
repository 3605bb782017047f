"""A first run that talks: numba's compiles of the package's kernels are announced once and timed,
on stderr (no logging set up) or through the "softgrasp_env" logger (logging set up); the env warms
its finger kind's kernels once per process at gym.make; ``python -m softgrasp_env.compile`` warms
the cache. The real half-minute compile on a cold cache is in tests/test_packaging.py (slow)."""

from __future__ import annotations

import logging
import types

import numba
import pytest

from softgrasp_env import _jit_cache
from softgrasp_env import compile as sg_compile


@pytest.fixture
def fresh_state(monkeypatch):
    """The reporter's per-process state as in a new process (nothing announced or compiled yet)."""
    monkeypatch.setattr(_jit_cache, "_state", _jit_cache._State())
    _jit_cache.install_reporter()
    return _jit_cache._state


def _kernel(module: str, name: str):
    """A new, never compiled numba function that claims to live in ``module`` (not cached)."""
    def f(x):
        return x * 2.0 + 1.0

    f.__module__, f.__qualname__, f.__name__ = module, name, name
    return numba.njit(cache=False)(f)


def test_the_first_compile_is_announced_once_and_a_block_reports_its_time(fresh_state, capsys, monkeypatch):
    monkeypatch.setattr(logging.getLogger(), "handlers", [])  # no logging set up: stderr
    with _jit_cache.reporting() as done:
        _kernel("softgrasp_env.tissue.fake", "k1")(1.0)
        _kernel("softgrasp_env.tissue.fake", "k2")(1.0)
    err = capsys.readouterr().err.splitlines()
    assert err[0] == f"softgrasp_env: {_jit_cache.START_MESSAGE}"
    assert len(err) == 2 and err[1].startswith("softgrasp_env: compiled the solver's kernels (2 kernels) in ")
    assert [c.name for c in done if c.depth == 0] == ["softgrasp_env.tissue.fake.k1", "softgrasp_env.tissue.fake.k2"]
    with _jit_cache.reporting():
        _kernel("softgrasp_env.tissue.fake", "k3")(1.0)
    assert "numba is compiling" not in capsys.readouterr().err  # announced once per process
    with _jit_cache.reporting():
        pass
    assert capsys.readouterr().err == ""  # nothing compiled, nothing said


def test_other_packages_kernels_are_not_reported(fresh_state, capsys, monkeypatch):
    monkeypatch.setattr(logging.getLogger(), "handlers", [])
    with _jit_cache.reporting():
        _kernel("someone_else", "k")(1.0)
    assert capsys.readouterr().err == "" and not fresh_state.announced


def test_a_slow_kernel_outside_a_block_is_reported_alone(fresh_state, capsys, monkeypatch):
    monkeypatch.setattr(logging.getLogger(), "handlers", [])
    monkeypatch.setattr(_jit_cache, "REPORT_ALONE", 0.0)
    _kernel("softgrasp_env.sim.fake", "alone")(1.0)
    err = capsys.readouterr().err.splitlines()
    assert err[0].endswith(_jit_cache.START_MESSAGE) and err[1].startswith("softgrasp_env: compiled sim.fake.alone in ")


def test_with_logging_set_up_the_logger_decides(fresh_state, capsys, caplog):
    with caplog.at_level(logging.INFO, logger="softgrasp_env"):
        with _jit_cache.reporting():
            _kernel("softgrasp_env.tissue.fake", "logged")(1.0)
    assert capsys.readouterr().err == ""
    assert [r.name for r in caplog.records] == ["softgrasp_env", "softgrasp_env"]
    assert "numba is compiling" in caplog.records[0].getMessage()


def test_set_level_warning_silences_it(fresh_state, capsys, monkeypatch):
    monkeypatch.setattr(logging.getLogger(), "handlers", [])
    monkeypatch.setattr(_jit_cache.LOG, "level", logging.WARNING)
    with _jit_cache.reporting():
        _kernel("softgrasp_env.tissue.fake", "quiet")(1.0)
    assert capsys.readouterr().err == ""


def test_the_env_warms_its_finger_kind_once_per_process(monkeypatch):
    import gymnasium as gym

    import softgrasp_env.scene as scene_pkg

    built = []
    real = scene_pkg.GraspScene

    def counting(*args, **kwargs):
        built.append(args[0].fingers.kind if args else None)
        return real(*args, **kwargs)

    monkeypatch.setattr(_jit_cache, "_warmed", set())
    monkeypatch.setattr(scene_pkg, "GraspScene", counting)
    for env_id in ("SoftGraspRigid-v3", "SoftGraspGripRigid-v5", "SoftGraspEasyRigid-v3"):
        gym.make(env_id).close()
    assert built == ["rigid"]  # the first rigid env warmed the kind; the others found it warm


def test_the_compile_command_warms_every_kind_and_says_so(capsys, monkeypatch):
    monkeypatch.setattr(_jit_cache, "_state", _jit_cache._State())
    assert sg_compile.main([]) == 0  # compiles what is not cached yet (nothing, after the setup)
    capsys.readouterr()
    assert sg_compile.main(["--report"]) == 0
    out = capsys.readouterr().out
    assert "loaded from numba's cache" in out and "nothing was compiled in this run" in out
    table = sg_compile.report([_jit_cache.Compiled("softgrasp_env.tissue.solver._step", "(a)", 2.0, 0),
                               _jit_cache.Compiled("softgrasp_env.tissue.contacts.c", "(a)", 1.0, 1),
                               _jit_cache.Compiled("numba.np.arrayobj.ol_np_empty", "(a)", 0.1, 2),
                               _jit_cache.Compiled("numba.np.arrayobj.ol_np_empty", "(b)", 0.1, 2)])  # fmt: skip
    lines = table.splitlines()
    assert "softgrasp_env.tissue.solver._step" in lines[1] and lines[-1].split()[0] == "2.00"
    assert any(line.split()[:2] == ["0.20", "2"] for line in lines)  # two signatures of one kernel


def test_the_compile_command_checks_its_thread_count(capsys):
    with pytest.raises(SystemExit) as e:
        sg_compile.main(["--threads", "0"])
    assert e.value.code == 2 and "SimConfig.threads must be in [1, 64], got 0" in capsys.readouterr().err


def test_the_compile_command_compiles_the_step_on_threads():
    """In a fresh process: the threaded step starts numba's thread pool, which must not happen in a
    test worker that later sets NUMBA_NUM_THREADS (the training tests do)."""
    import subprocess
    import sys

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("numba has one thread here")
    code = ("import numba; from numba.np.ufunc import parallel; from softgrasp_env import compile as c; "
            "assert c.main(['--threads', '2']) == 0; assert parallel._is_initialized, 'no threaded step ran'")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]


def test_compile_module_is_a_module_not_the_builtin():
    assert isinstance(sg_compile, types.ModuleType) and callable(sg_compile.warm)
