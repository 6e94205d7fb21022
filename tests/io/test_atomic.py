"""Every file p3d writes is written whole or not at all, and never over what it must not replace."""

from __future__ import annotations

import os
import stat

import pytest

from p3d_cli.errors import OutputError
from p3d_cli.io.atomic import replacing, write_bytes


def test_writes_a_new_file_with_the_umask_mode(tmp_path):
    path = tmp_path / "out.txt"
    write_bytes(path, b"hello")
    assert path.read_bytes() == b"hello"
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_an_error_part_way_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / "robot.urdf"
    path.write_bytes(b"original")
    with pytest.raises(RuntimeError):
        with replacing(path) as f:
            f.write(b"half of the new")
            raise RuntimeError("killed")
    assert path.read_bytes() == b"original"
    assert [p.name for p in tmp_path.iterdir()] == ["robot.urdf"]


def test_keeps_the_replaced_files_permissions(tmp_path):
    path = tmp_path / "robot.urdf"
    path.write_bytes(b"old")
    os.chmod(path, 0o640)
    write_bytes(path, b"new")
    assert path.read_bytes() == b"new"
    assert stat.S_IMODE(path.stat().st_mode) == 0o640


def test_refuses_to_write_over_an_input(tmp_path):
    mesh = tmp_path / "part.stl"
    mesh.write_bytes(b"mesh")
    with pytest.raises(OutputError, match="would overwrite the input"):
        write_bytes(tmp_path / "." / "part.stl", b"<junit/>", inputs=[mesh], what="the JUnit report")
    assert mesh.read_bytes() == b"mesh"
    write_bytes(mesh, b"in place", inputs=[mesh], in_place=True)
    assert mesh.read_bytes() == b"in place"


def test_refuses_a_read_only_file(tmp_path):
    path = tmp_path / "locked.urdf"
    path.write_bytes(b"old")
    os.chmod(path, 0o444)
    if os.access(path, os.W_OK):  # root ignores permission bits
        pytest.skip("running as a user whom permission bits do not stop")
    with pytest.raises(OutputError, match="read-only"):
        write_bytes(path, b"new")
    assert path.read_bytes() == b"old"


def test_read_only_is_refused_even_for_root(tmp_path, monkeypatch):
    path = tmp_path / "locked.urdf"
    path.write_bytes(b"old")
    monkeypatch.setattr(os, "access", lambda *args, **kwargs: False)
    with pytest.raises(OutputError, match="read-only"):
        write_bytes(path, b"new")
    assert path.read_bytes() == b"old"


def test_follows_a_symlink_and_keeps_it(tmp_path):
    real = tmp_path / "real.urdf"
    real.write_bytes(b"old")
    link = tmp_path / "link.urdf"
    link.symlink_to(real)
    write_bytes(link, b"new")
    assert link.is_symlink() and real.read_bytes() == b"new"


def test_refuses_a_file_with_other_hard_links(tmp_path):
    path = tmp_path / "a.urdf"
    path.write_bytes(b"old")
    os.link(path, tmp_path / "b.urdf")
    with pytest.raises(OutputError, match="hard link"):
        write_bytes(path, b"new")
    assert (tmp_path / "b.urdf").read_bytes() == b"old" and path.read_bytes() == b"old"


def test_refuses_a_missing_folder_and_a_directory(tmp_path):
    with pytest.raises(OutputError, match="does not exist"):
        write_bytes(tmp_path / "no" / "out.xml", b"x")
    with pytest.raises(OutputError, match="not a regular file"):
        write_bytes(tmp_path, b"x")
