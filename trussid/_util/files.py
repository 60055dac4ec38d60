"""Writing files so that a failure never leaves a partial output behind."""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import stat
from pathlib import Path

__all__ = ["atomic_path", "check_parent"]


def check_parent(path: str | os.PathLike, what: str = "output") -> Path:
    """Return ``path`` as a Path if its directory exists; ``FileNotFoundError`` otherwise.

    A mistyped directory in an output path must not silently create directories the user
    did not ask for, so the error names the missing directory and the path given.
    """
    path = Path(path)
    parent = path.parent
    if not parent.is_dir():
        kind = "is not a directory" if parent.exists() else "does not exist"
        raise FileNotFoundError(errno.ENOENT, f"{what}: directory {parent} {kind} (create it "
                                "first: trussid makes no directory it was not asked for)",
                                str(path))
    return path


def _create_temp(path: Path, suffix: str) -> Path:
    """Create an empty hidden temporary file beside ``path`` and return its name.

    ``tempfile.mkstemp`` creates files with mode 0600 whatever the umask, and a rename keeps
    that mode, so every output would be private. Opening with ``O_CREAT | O_EXCL`` and mode
    0666 lets the kernel apply the user's umask, as the shell does for ``>``, without reading
    or changing the process-wide umask.
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0)
    for _ in range(100):
        tmp = path.with_name(f".{path.stem}.{secrets.token_hex(4)}{suffix}")
        try:
            fd = os.open(tmp, flags, 0o666)
        except FileExistsError:
            continue
        except OSError as exc:
            # The user gave `path`; a message naming the hidden temporary would mislead.
            raise type(exc)(exc.errno, exc.strerror, str(path)) from None
        os.close(fd)
        return tmp
    raise FileExistsError(errno.EEXIST, "cannot create a temporary file beside it", str(path))


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None):
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    Parameters
    ----------
    path : path-like
        The final output file. Its directory must exist (none is created).
    suffix : str, optional
        Suffix of the temporary file (default: that of ``path``), for writers that pick the
        format from the extension (matplotlib, pyvista, numpy).

    Raises
    ------
    FileNotFoundError
        If the directory of ``path`` does not exist.
    OSError
        Any failure to create, write or rename, naming ``path`` (never the temporary).

    Notes
    -----
    The temporary file lives in the same directory so that the rename is atomic. On any
    exception the temporary file is removed and ``path`` is left as it was. The result gets
    the permissions the umask gives to a new file; an existing ``path`` keeps its own mode
    (as the shell's ``>`` does).
    """
    path = check_parent(path)
    tmp = _create_temp(path, suffix if suffix is not None else path.suffix)
    try:
        with contextlib.suppress(FileNotFoundError):
            os.chmod(tmp, stat.S_IMODE(os.stat(path).st_mode))
        try:
            yield tmp
            os.replace(tmp, path)
        except OSError as exc:
            if exc.filename is not None and os.fspath(exc.filename) == os.fspath(tmp):
                raise type(exc)(exc.errno, exc.strerror, str(path)) from None
            raise
    except BaseException:  # any failure, Ctrl-C included: remove the temporary file, re-raise
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
