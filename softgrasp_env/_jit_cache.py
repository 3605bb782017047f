"""Keep numba's on-disk cache honest, and say when numba compiles.

numba keys a cached kernel on the timestamp of the file that defines it, but our kernels inline
functions from other modules (the tissue's constraint modules inline rotation.py, collision.py,
rigid.py and one another; sim/coupling.py inlines rotation.py). An edit to rotation.py alone would
leave contacts.py's stale machine code running. So at import we hash every source file that holds numba code and, when the hash
changed since the cache was written, drop the package's cached kernels (they recompile once).
"""

from __future__ import annotations

import hashlib
import logging
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent
_JIT_DIRS = ("tissue", "sim")
_STAMP = _PACKAGE / "__pycache__" / "jit-sources.sha256"


def _sources_digest() -> str:
    h = hashlib.sha256()
    for sub in _JIT_DIRS:
        for path in sorted((_PACKAGE / sub).glob("*.py")):
            h.update(path.name.encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def invalidate_stale_kernels() -> bool:
    """Delete cached kernels if any jitted source changed; returns True if it deleted any.

    A read-only install (no writable __pycache__) is left alone: numba cannot write its cache
    there either, so there is nothing stale to find."""
    digest = _sources_digest()
    try:
        if _STAMP.exists() and _STAMP.read_text().strip() == digest:
            return False
        removed = False
        for sub in _JIT_DIRS:
            for cached in (_PACKAGE / sub / "__pycache__").glob("*.nb[ic]"):
                cached.unlink(missing_ok=True)
                removed = True
        _STAMP.parent.mkdir(exist_ok=True)
        _STAMP.write_text(digest + "\n")
        return removed
    except OSError:
        return False


# --- a first run that talks ----------------------------------------------------------------------
#
# numba compiles the solver's kernels on their first call after an install or an edit (about a
# minute, nearly all of it the tissue step) and caches them on disk. Without a word
# that looks like a hang, so a listener on numba's compile events says when a compile starts and
# how long it took. numba fires "numba:compile" only on a cache miss: a warm start says nothing.
#
# Where the words go: the logger "softgrasp_env" when the application has set up logging (its
# handlers and levels decide), else one line on stderr, as Python's own last-resort handler would
# do for a warning: a person at a terminal waiting a minute should see why without setting
# anything up, and stdout stays the program's (agents.evaluate prints its results there).
# `logging.getLogger("softgrasp_env").setLevel(logging.WARNING)` silences it either way.
# gymnasium's logger would not do: it is for warnings (warnings.warn, once per call site), and a
# compile is not one.

LOG = logging.getLogger("softgrasp_env")
_OURS = __name__.rsplit(".", 1)[0] + "."  # "softgrasp_env."
START_MESSAGE = ("numba is compiling the solver's kernels: the first run after an install or an update takes "
                 "about a minute (cached on disk for later runs; `python -m softgrasp_env.compile` does it ahead)")  # fmt: skip
"""Said once per process, when the first of the package's kernels starts compiling."""
REPORT_ALONE = 1.0
"""A kernel compiled outside :func:`reporting` is reported by itself if it took this long [s]."""


def say(message: str) -> None:
    """One line for the person waiting (see the note above on where it goes)."""
    if LOG.hasHandlers():
        LOG.info(message)
    elif LOG.level <= logging.INFO:  # NOTSET (0) unless silenced with setLevel
        print(f"softgrasp_env: {message}", file=sys.stderr, flush=True)


@dataclass
class Compiled:
    """One kernel numba compiled (a cache miss)."""

    name: str
    """``module.qualname`` of the Python function."""
    signature: str
    seconds: float
    """Wall time of its compile, nested compiles included."""
    depth: int
    """0: called from Python; > 0: compiled while compiling its caller (a callee that is not inlined)."""


@dataclass
class _State:
    compiled: list[Compiled] = field(default_factory=list)
    announced: bool = False
    blocks: int = 0
    starts: list[float] = field(default_factory=list)


_state = _State()
_lock = threading.Lock()
_installed = False


def _name(dispatcher) -> str:
    func = getattr(dispatcher, "py_func", None)
    return f"{getattr(func, '__module__', '?')}.{getattr(func, '__qualname__', repr(dispatcher))}"


def install_reporter() -> None:
    """Listen to numba's compile events from now on (idempotent). Imports numba, so it is called
    where the kernels are about to be used (the env, ``softgrasp_env.compile``), not at package
    import, which stays free of numba."""
    global _installed
    with _lock:
        if _installed:
            return
        from numba.core import event

        class Reporter(event.Listener):
            def on_start(self, ev) -> None:
                st = _state
                if not st.starts and not st.announced and _name(ev.data["dispatcher"]).startswith(_OURS):
                    st.announced = True
                    say(START_MESSAGE)
                st.starts.append(time.perf_counter())

            def on_end(self, ev) -> None:
                st = _state
                seconds = time.perf_counter() - st.starts.pop()
                name = _name(ev.data["dispatcher"])
                if not name.startswith(_OURS) and not st.starts:
                    return  # someone else's numba code
                st.compiled.append(Compiled(name, str(ev.data.get("args")), seconds, len(st.starts)))
                if not st.starts and not st.blocks and name.startswith(_OURS) and seconds >= REPORT_ALONE:
                    say(f"compiled {name.removeprefix(_OURS)} in {seconds:.1f} s")

        event.register("numba:compile", Reporter())
        _installed = True


def compiled() -> list[Compiled]:
    """Every compile this process has seen since :func:`install_reporter` (a copy)."""
    return list(_state.compiled)


@contextmanager
def reporting(what: str = "the solver's kernels") -> Iterator[list[Compiled]]:
    """Run a block that may compile; at its end, if it did, say how many kernels and how long (one
    line, instead of one per kernel). Yields the list of what it compiled, filled at the end."""
    install_reporter()
    before = len(_state.compiled)
    _state.blocks += 1
    tic = time.perf_counter()
    out: list[Compiled] = []
    try:
        yield out
    finally:
        _state.blocks -= 1
        out.extend(_state.compiled[before:])
        top = [c for c in out if c.depth == 0]
        if top:
            say(f"compiled {what} ({len(top)} kernels) in {time.perf_counter() - tic:.1f} s")


_warmed: set[str] = set()


def ensure_compiled(config) -> None:
    """Compile (or load from the cache) the kernels a scene of ``config`` (a SceneConfig) runs, once
    per finger kind and process: a throw-away scene is built and stepped once, inside
    :func:`reporting`. So a cold cache costs its half minute at ``gym.make``, with a line before and
    after, instead of silently inside the first reset and step; a warm one costs a scene build
    (about 30 ms). Every tissue setting and both couplings share one specialisation of each kernel
    (measured: ``python -m softgrasp_env.compile --report``), so the kind is the key."""
    kind = getattr(getattr(config, "fingers", None), "kind", None) or str(config.fingers)
    if kind in _warmed:
        return
    from .scene import GraspScene

    with reporting():
        scene = GraspScene(config)
        try:
            scene.step()  # the arm's path, the kind's hook and the world
            # the per-step queries with kernels of their own (the env calls them from its first step)
            scene.finger_forces()
            scene.world.tissue_deviation()
            if scene.fingers.no_tactile is None:
                scene.fingers.tactile(scene.fingers.taxel_grid(2, 2))
        finally:
            scene.close()
    _warmed.add(kind)
