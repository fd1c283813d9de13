"""Numba's cache checks only the compiled function's own file; towenv.core.jit drops the package's cached
kernels when any kernel module's source changed (a kernel compiled against an older callee must not load)."""
from towenv.core import jit


def _package(tmp_path):
    for folder in jit.KERNEL_FOLDERS:
        (tmp_path / folder / "__pycache__").mkdir(parents=True)
        (tmp_path / folder / "mod.py").write_text(f"# {folder}\n")
    return tmp_path


def test_stale_caches_are_dropped_when_a_callee_changes(tmp_path):
    root = _package(tmp_path)
    cached = root / "core" / "__pycache__" / "houbolt.advance-1.py311.nbi"
    cached.write_text("x")
    assert jit.drop_stale_caches(root)                 # no stamp yet: unknown provenance, dropped
    assert not cached.exists()
    cached.write_text("x")                             # numba writes its cache for these sources
    (root / "envs" / "__pycache__" / "stepper.f-1.py311.nbc").write_text("y")
    assert not jit.drop_stale_caches(root)             # same sources: the cache stays
    assert cached.exists()
    (root / "core" / "mod.py").write_text("# core, edited\n")    # a callee's module changes
    assert jit.drop_stale_caches(root)
    assert not cached.exists() and not (root / "envs" / "__pycache__" / "stepper.f-1.py311.nbc").exists()
    assert (root / "core" / "__pycache__" / jit.STAMP_NAME).read_text().strip() == jit.kernel_sources_digest(root)


def test_the_installed_package_has_a_current_stamp():
    """Importing towenv ran the guard: the stamp matches the installed kernel sources (or the install is
    read-only and there is no stamp)."""
    from pathlib import Path
    import towenv  # noqa: F401
    root = Path(jit.__file__).resolve().parent.parent
    stamp = root / "core" / "__pycache__" / jit.STAMP_NAME
    if stamp.exists():
        assert stamp.read_text().strip() == jit.kernel_sources_digest(root)
