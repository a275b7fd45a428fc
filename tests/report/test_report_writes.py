"""The report is written atomically, never through a symlink, and never reads a huge figure
(issue 23, item 5)."""
from __future__ import annotations

import errno

import pytest

from sosdyn import files
from sosdyn.errors import InputError
from sosdyn.report import html as H


def test_a_failed_write_leaves_the_previous_report_whole(tmp_path, results_factory, monkeypatch):
    old = H.render_html(results_factory(), tmp_path).read_bytes()

    def full_disk(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(files.os, "fsync", full_disk)
    with pytest.raises(OSError, match="No space left"):
        H.render_html(results_factory(seed=2), tmp_path)
    assert (tmp_path / "index.html").read_bytes() == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["index.html"]      # no temporary file left


def test_a_symlinked_index_is_replaced_not_followed(tmp_path, results_factory):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    out = tmp_path / "out"
    out.mkdir()
    (out / "index.html").symlink_to(victim)
    path = H.render_html(results_factory(), out)
    assert victim.read_text() == "keep me"
    assert not path.is_symlink() and "<html" in path.read_text()


def test_a_huge_figure_is_refused_before_it_is_read(tmp_path, results_factory):
    """A results file naming a 1.5 GiB PNG (sparse here): refused by its size, in milliseconds."""
    (tmp_path / "figures").mkdir()
    with open(tmp_path / "figures" / "big.png", "wb") as f:
        f.truncate(3 * 2**29)
    results = results_factory(figures={"big": {"png": "figures/big.png", "caption": "c"}})
    with pytest.raises(InputError, match=r"figure 'big': .*big.png is 1.5 GiB, over max_file_bytes = 64.0 MiB"
                                         r".* Try: a smaller figure .* sosdyn.set_limits\(max_file_bytes=...\) "
                                         r"\(the sosdyn command: SOSDYN_MAX_FILE_BYTES=... in the environment\)"):
        H.render_html(results, tmp_path / "out", base_dir=tmp_path)
    assert not (tmp_path / "out").exists()
