"""The atomic writer: outputs get the umask's permissions, no directory appears unasked, and
an error names the user's path, never the hidden temporary file."""

import errno
import os
import stat

import pytest

from trussid._util.files import atomic_path, check_parent


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    try:
        yield
    finally:
        os.umask(old)


def _mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


def test_a_new_file_gets_the_mode_the_umask_gives_like_a_shell_redirect(tmp_path, umask_022):
    shell_like = tmp_path / "by_open.txt"
    with open(shell_like, "w") as fh:  # what `echo > file` does: 0666 & ~umask
        fh.write("x")
    with atomic_path(tmp_path / "out.csv") as tmp:
        tmp.write_text("t,u1,y1\n")
    assert _mode(tmp_path / "out.csv") == 0o644 == _mode(shell_like)


def test_a_stricter_umask_is_honoured(tmp_path):
    old = os.umask(0o077)
    try:
        with atomic_path(tmp_path / "private.npz") as tmp:
            tmp.write_bytes(b"x")
    finally:
        os.umask(old)
    assert _mode(tmp_path / "private.npz") == 0o600


def test_replacing_a_file_keeps_its_mode(tmp_path, umask_022):
    target = tmp_path / "shared.json"
    target.write_text("old")
    os.chmod(target, 0o664)
    with atomic_path(target) as tmp:
        tmp.write_text("new")
    assert target.read_text() == "new" and _mode(target) == 0o664


def test_a_missing_directory_is_refused_and_not_created(tmp_path):
    out = tmp_path / "newdir" / "sub" / "x.png"
    with pytest.raises(FileNotFoundError) as err:
        with atomic_path(out) as tmp:
            tmp.write_text("never")
    assert f"directory {tmp_path / 'newdir' / 'sub'} does not exist" in err.value.strerror
    assert err.value.filename == str(out)
    assert not (tmp_path / "newdir").exists()


def test_a_file_where_the_directory_should_be_is_named(tmp_path):
    (tmp_path / "afile").write_text("x")
    with pytest.raises(FileNotFoundError, match="is not a directory"):
        check_parent(tmp_path / "afile" / "x.png")


def test_an_unwritable_directory_names_the_users_path_not_the_temporary(tmp_path, monkeypatch):
    # Tests run as root here, for whom chmod does not deny writing: simulate the kernel's
    # refusal at the temporary file's creation, which is where it happens for a user.
    real_open = os.open

    def denied(path, flags, mode=0o777, **kw):
        if os.path.basename(path).startswith(".r7."):
            raise PermissionError(errno.EACCES, "Permission denied", path)
        return real_open(path, flags, mode, **kw)

    monkeypatch.setattr(os, "open", denied)
    with pytest.raises(PermissionError) as err:
        with atomic_path(tmp_path / "r7.png"):
            pass
    assert err.value.filename == str(tmp_path / "r7.png")


def test_a_failing_writer_leaves_neither_output_nor_temporary(tmp_path):
    with pytest.raises(RuntimeError):
        with atomic_path(tmp_path / "x.csv") as tmp:
            tmp.write_text("partial")
            raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_an_error_of_the_writer_on_the_temporary_is_reported_against_the_output(tmp_path):
    with pytest.raises(OSError) as err:
        with atomic_path(tmp_path / "x.gif") as tmp:
            raise OSError(errno.ENOSPC, "No space left on device", str(tmp))
    assert err.value.filename == str(tmp_path / "x.gif")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not os.path.isdir("/sys/kernel"), reason="needs Linux sysfs")
def test_a_real_unwritable_place_names_the_given_path():
    with pytest.raises(OSError) as err:
        with atomic_path("/sys/r7.png"):
            pass
    assert err.value.filename == "/sys/r7.png"


def test_a_report_directory_gets_the_mode_the_umask_gives(tmp_path, umask_022):
    from trussid._util.files import atomic_directory

    with atomic_directory(tmp_path / "report") as tmp:
        (tmp / "report.md").write_text("# report\n")
    assert _mode(tmp_path / "report") == 0o755  # mkdtemp's 0700 would lock colleagues out
    assert [p.name for p in tmp_path.iterdir()] == ["report"]
