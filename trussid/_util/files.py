"""Writing files so that a failure never leaves a partial output behind."""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import stat
from pathlib import Path

__all__ = ["atomic_path", "atomic_directory", "check_parent"]


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


def _make_temp_dir(path: Path, suffix: str) -> Path:
    """Create an empty hidden directory beside ``path`` with the mode the umask gives
    (``tempfile.mkdtemp`` makes it 0700, and the rename would keep that)."""
    for _ in range(100):
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}{suffix}")
        try:
            os.mkdir(tmp, 0o777)
        except FileExistsError:
            continue
        return tmp
    raise FileExistsError(errno.EEXIST, "cannot create a temporary directory beside it",
                          str(path))


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


@contextlib.contextmanager
def atomic_directory(path: str | os.PathLike, force: bool = False):
    """Yield a temporary directory beside ``path``; it becomes ``path`` only on success.

    A report directory is written as a whole: an interruption (Ctrl-C is a
    KeyboardInterrupt) or an error leaves either the previous ``path`` untouched or no
    ``path`` at all, never a mixture of an old ``report.md`` and new model files.

    Parameters
    ----------
    path : path-like
        The final directory. Its parent must exist.
    force : bool
        Replace an existing ``path``; without it an existing one is refused (FileExistsError
        naming it) before anything is written.

    Notes
    -----
    Replacing needs two renames (old away, new in); between them ``path`` is briefly absent,
    and the old directory is deleted only after the new one is in place. Both renames stay
    on one file system (siblings), so each is atomic.
    """
    import shutil

    path = Path(path)
    if path.exists() and not force:
        raise FileExistsError(17, "exists (give --force to replace it)", str(path))
    if path.exists() and not path.is_dir():
        raise NotADirectoryError(20, "exists and is not a directory", str(path))
    if not path.parent.is_dir():
        raise FileNotFoundError(2, "No such directory", str(path.parent))
    tmp = _make_temp_dir(path, ".partial")
    old = None
    try:
        yield tmp
        if path.exists():
            old = _make_temp_dir(path, ".old")
            os.replace(path, old / "previous")
        try:
            os.replace(tmp, path)
        except BaseException:  # Ctrl-C included: put the previous directory back
            if old is not None:  # put the previous directory back
                os.replace(old / "previous", path)
            raise
    except BaseException:  # any failure, Ctrl-C included: drop the partial directory
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and (old / "previous").exists() and not path.exists():
            os.replace(old / "previous", path)
        raise
    finally:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
