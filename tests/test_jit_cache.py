"""The numba cache guard: an edit to any jitted source drops every cached kernel."""

from __future__ import annotations

from softgrasp_env import _jit_cache


def test_changed_source_drops_cached_kernels(tmp_path, monkeypatch):
    pkg = tmp_path / "pkg"
    for sub in ("tissue", "sim"):
        (pkg / sub / "__pycache__").mkdir(parents=True)
    (pkg / "tissue" / "rotation.py").write_text("x = 1\n")
    (pkg / "sim" / "coupling.py").write_text("y = 2\n")
    kernel = pkg / "tissue" / "__pycache__" / "solver._step-1.py311.nbi"
    monkeypatch.setattr(_jit_cache, "_PACKAGE", pkg)
    monkeypatch.setattr(_jit_cache, "_STAMP", pkg / "__pycache__" / "jit-sources.sha256")

    kernel.write_text("cached")
    _jit_cache.invalidate_stale_kernels()  # first run: no stamp yet, so nothing is trusted
    assert not kernel.exists()

    kernel.write_text("cached")
    assert _jit_cache.invalidate_stale_kernels() is False  # unchanged sources keep the cache
    assert kernel.exists()

    (pkg / "tissue" / "rotation.py").write_text("x = 3\n")  # edit a file the kernel inlines
    assert _jit_cache.invalidate_stale_kernels() is True
    assert not kernel.exists()
