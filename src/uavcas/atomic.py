"""Atomic, non-destructive file output: the one home of how uavcas writes an output path.

Rules (every writer of the package goes through here):
- The data goes to a temporary file beside the target (same directory, so the final rename is
  atomic), is fsynced, and is renamed onto the target. Readers never see half a file; on any
  error the temporary file is removed and the target is left as it was.
- Writing never destroys what the tool did not create: an existing target that is not a regular
  file (a symbolic link, a FIFO, a device, a socket, a directory) is refused with `UnsafeOutput`
  before anything is written, and checked again just before the rename. `os.replace` would
  otherwise turn `--out /dev/null` (as root) or a symlink into a regular file.
- A directory written as a whole (`atomic_dir`) is built in a temporary directory beside it and
  renamed onto it; the target must not exist or be an empty directory.
- An output directory (`ensure_out_dir`) must be a directory (a symlink to one is fine: writing
  inside it destroys nothing) or not exist yet; a FIFO, device or regular file in its place, or a
  dangling symlink, is refused the same way.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path


class UnsafeOutput(ValueError):
    """An output path that would replace something that is not a regular file (exit 2)."""


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISLNK, "a symbolic link"), (stat.S_ISFIFO, "a FIFO"),
                       (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"), (stat.S_ISDIR, "a directory"),
                       (stat.S_ISREG, "a regular file")):  # fmt: skip
        if test(mode):
            return name
    return "of an unknown kind"


def check_target(path: str | os.PathLike) -> Path:
    """`path` if it is absent or a regular file (never following a symlink); else UnsafeOutput."""
    path = Path(path)
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return path
    if not stat.S_ISREG(st.st_mode):
        raise UnsafeOutput(f"refusing to write {path}: it is {_kind(st.st_mode)} (uavcas only replaces regular files)")
    return path


def check_out_dir(path: str | os.PathLike) -> Path:
    """`path` if it is absent or a directory (a symlink to one included); else UnsafeOutput."""
    path = Path(path)
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return path
    if stat.S_ISDIR(st.st_mode) or (stat.S_ISLNK(st.st_mode) and path.is_dir()):
        return path
    raise UnsafeOutput(f"refusing to use {path} as an output directory: it is {_kind(st.st_mode)}")


def ensure_out_dir(path: str | os.PathLike) -> Path:
    """Create output directory `path` (and parents) unless it already is a directory."""
    path = check_out_dir(path)
    path.mkdir(parents=True, exist_ok=True)
    return path


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside `path`; on success it is renamed onto `path`.

    For writers that want a file name (pyarrow, matplotlib): `with atomic_path(p) as tmp: f(tmp)`.
    On an exception the temporary file is removed and `path` is left as it was.
    """
    path = check_target(path)
    ensure_out_dir(path.parent)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + path.suffix, dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    # mkstemp makes the file 0600; give it the mode a plain open() would (0666 less the umask).
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp_path, 0o666 & ~umask)
    try:
        yield tmp_path
        with open(tmp_path, "rb+") as fh:
            os.fsync(fh.fileno())
        check_target(path)  # something may have appeared there while we were writing
        os.replace(tmp_path, path)
    finally:
        tmp_path.unlink(missing_ok=True)


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def atomic_write_text(path: str | os.PathLike, text: str) -> Path:
    return atomic_write_bytes(path, text.encode())


@contextlib.contextmanager
def atomic_dir(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary directory beside `path`; on success it is renamed onto `path`, which must
    be absent or an empty directory (FileExistsError otherwise, before anything is written). The
    parent folder is created. On an exception the temporary directory is removed."""
    path = check_out_dir(path)
    if path.exists() and any(path.iterdir()):
        raise FileExistsError(f"{path} exists and is not an empty directory")
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    try:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)  # mkdtemp makes it 0700; give it a plain mkdir's mode
        if path.exists():
            path.rmdir()  # empty, checked above (rmdir refuses one that filled up meanwhile)
        os.replace(tmp, path)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
