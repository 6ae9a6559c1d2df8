"""robotplan.base.files: whole or not at all, with ordinary permissions."""

import os
import stat

import pytest

from robotplan.base.files import write_atomically


def test_written_files_get_the_permissions_of_plainly_created_ones(tmp_path):
    old = os.umask(0o022)
    try:
        write_atomically(tmp_path / "a.json", lambda tmp: tmp.write_text("{}"))
    finally:
        os.umask(old)
    assert (tmp_path / "a.json").read_text() == "{}"
    assert stat.S_IMODE((tmp_path / "a.json").stat().st_mode) == 0o644
    old = os.umask(0o077)
    try:
        write_atomically(tmp_path / "b.json", lambda tmp: tmp.write_text("{}"))
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "b.json").stat().st_mode) == 0o600


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / "a.json"
    path.write_text("old")

    def fail(tmp):
        tmp.write_text("half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        write_atomically(path, fail)
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["a.json"]
