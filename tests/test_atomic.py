import os

import pytest

from uavcas.atomic import atomic_path, atomic_write_text


def test_atomic_write_replaces_whole_and_has_a_normal_mode(tmp_path):
    p = tmp_path / "a.txt"
    atomic_write_text(p, "one")
    atomic_write_text(p, "two")
    assert p.read_text() == "two"
    umask = os.umask(0)
    os.umask(umask)
    assert p.stat().st_mode & 0o777 == 0o666 & ~umask
    assert [x.name for x in tmp_path.iterdir()] == ["a.txt"]


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    p = tmp_path / "a.txt"
    atomic_write_text(p, "old")
    with pytest.raises(RuntimeError):
        with atomic_path(p) as tmp:
            tmp.write_text("half")
            raise RuntimeError("writer crashed")
    assert p.read_text() == "old"
    assert [x.name for x in tmp_path.iterdir()] == ["a.txt"]


def _refuses(target, kind):
    from uavcas.atomic import UnsafeOutput

    with pytest.raises(UnsafeOutput, match=kind):
        atomic_write_text(target, "data")
    assert [x.name for x in target.parent.iterdir() if x.name.startswith(".")] == []  # no temporary left


def test_never_replaces_what_is_not_a_regular_file(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    link = tmp_path / "link"
    link.symlink_to(victim)
    _refuses(link, "symbolic link")
    assert link.is_symlink() and victim.read_text() == "keep me"
    dangling = tmp_path / "dangling"
    dangling.symlink_to(tmp_path / "nowhere")
    _refuses(dangling, "symbolic link")
    assert dangling.is_symlink() and not (tmp_path / "nowhere").exists()
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    _refuses(fifo, "FIFO")
    import stat as st

    assert st.S_ISFIFO(os.lstat(fifo).st_mode)
    d = tmp_path / "dir"
    d.mkdir()
    _refuses(d, "directory")
    assert d.is_dir()


@pytest.mark.skipif(os.geteuid() != 0, reason="creating a device node needs root")
def test_never_replaces_a_device(tmp_path):
    import stat as st

    dev = tmp_path / "null-like"
    os.mknod(dev, 0o666 | st.S_IFCHR, os.makedev(1, 3))  # a private node of /dev/null's device, not /dev/null
    _refuses(dev, "character device")
    assert st.S_ISCHR(os.lstat(dev).st_mode)


def test_output_directories(tmp_path):
    from uavcas.atomic import UnsafeOutput, ensure_out_dir

    assert ensure_out_dir(tmp_path / "a" / "b").is_dir()
    (tmp_path / "real").mkdir()
    (tmp_path / "to-real").symlink_to(tmp_path / "real")
    assert ensure_out_dir(tmp_path / "to-real").is_dir()  # writing inside a linked directory destroys nothing
    (tmp_path / "file").write_text("x")
    with pytest.raises(UnsafeOutput, match="a regular file"):
        ensure_out_dir(tmp_path / "file")
    os.mkfifo(tmp_path / "fifo")
    with pytest.raises(UnsafeOutput, match="FIFO"):
        ensure_out_dir(tmp_path / "fifo")
    assert (tmp_path / "file").read_text() == "x"
