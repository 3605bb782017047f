"""Keep numba's on-disk cache honest.

numba keys a cached kernel on the timestamp of the file that defines it, but our kernels inline
functions from other modules (the tissue's constraint modules inline rotation.py, collision.py,
rigid.py and one another; sim/coupling.py inlines rotation.py). An edit to rotation.py alone would
leave contacts.py's stale machine code running. So at import we hash every source file that holds numba code and, when the hash
changed since the cache was written, drop the package's cached kernels (they recompile once).
"""

from __future__ import annotations

import hashlib
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
