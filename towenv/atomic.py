"""Atomic file writing: every output of towenv is written to a temporary name in the destination folder
and then renamed (``os.replace``), so an interrupt (SIGINT, a full disk, a crash) never leaves a truncated
file at the final path — either the previous file or the complete new one is there."""
from __future__ import annotations

import os
from pathlib import Path

__all__ = ["atomic_write", "atomic_savez", "check_output_dir"]


def _tmp_name(path: Path) -> Path:
    return path.with_name(f".{path.name}.tmp-{os.getpid()}")


def atomic_write(path, write, mode: str | None = "w", **open_kw) -> Path:
    """Write ``path`` atomically.

    ``write`` is a ``str``/``bytes`` (written with ``mode`` "w"/"wb"), a function of the open temporary
    file (``mode`` "w" or "wb"), or — with ``mode=None`` — a function of the temporary *path* (e.g. a
    figure's ``savefig``; the temporary name keeps the final suffix so format inference still works).
    On any exception (including ``KeyboardInterrupt``) the temporary file is removed and an existing
    ``path`` is left as it was."""
    path = Path(path)
    tmp = _tmp_name(path)
    if mode is None:
        tmp = tmp.with_name(tmp.name + path.suffix)
    try:
        if mode is None:
            write(tmp)
        else:
            with open(tmp, mode, **open_kw) as f:
                if isinstance(write, (str, bytes)):
                    f.write(write)
                else:
                    write(f)
                f.flush()
                os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            tmp.unlink()
        except FileNotFoundError:
            pass
        raise
    return path


def atomic_savez(path, arrays: dict) -> Path:
    """``numpy.savez_compressed(path, **arrays)`` written atomically."""
    import numpy as np
    return atomic_write(path, lambda f: np.savez_compressed(f, **arrays), mode="wb")


def check_output_dir(path) -> str | None:
    """Make sure ``path`` can be used as an output folder *before* a long run: create it (with its
    parents) and write and remove a probe file. Returns None when it works, else one line saying why not
    (a file in the way, no permission, a read-only file system …)."""
    import tempfile
    p = Path(path)
    if p.exists() and not p.is_dir():
        return "exists and is a file, not a folder"
    for parent in p.parents:
        if parent.exists():
            if not parent.is_dir():
                return f"{parent} is a file, not a folder"
            break
    try:
        p.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=p, prefix=".towenv-probe-"):
            pass
    except OSError as exc:
        return f"cannot write there ({exc.strerror or type(exc).__name__})"
    return None
