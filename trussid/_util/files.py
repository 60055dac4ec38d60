"""Writing files so that a failure never leaves a partial output behind."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None):
    """Yield a temporary path beside ``path``; rename it onto ``path`` only on success.

    Parameters
    ----------
    path : path-like
        The final output file.
    suffix : str, optional
        Suffix of the temporary file (default: that of ``path``), for writers that pick the
        format from the extension (matplotlib, pyvista, numpy).

    Notes
    -----
    The temporary file lives in the same directory so that the rename is atomic. On any
    exception the temporary file is removed and ``path`` is left as it was.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{path.stem}.", suffix=suffix if suffix is not None else path.suffix,
        dir=path.parent,
    )
    os.close(fd)
    try:
        yield Path(tmp)
        os.replace(tmp, path)
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
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".partial", dir=path.parent))
    old = None
    try:
        yield tmp
        if path.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".old", dir=path.parent))
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
