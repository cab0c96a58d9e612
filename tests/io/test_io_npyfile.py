"""The one .npy/.npz reader: headers that promise more than the file holds, and corrupt headers, name the file."""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest

from psgsl_pgm.io._class_maps import read_class_beliefs
from psgsl_pgm.io._npyfile import READ_ERRORS, load_npy


def _npy_bytes(arr) -> bytes:
    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


def _lying(arr, shape: str) -> bytes:
    """``arr`` saved, its header's shape replaced by ``shape`` (same header length)."""
    raw = _npy_bytes(arr)
    head_end = raw.index(b"\n") + 1
    head = raw[:head_end].decode("latin-1")
    old = str(arr.shape)
    body = head.replace(old, shape).rstrip(" \n")
    new = body + " " * (len(head) - len(body) - 1) + "\n"  # the header's padding keeps its length
    return new.encode("latin-1") + raw[head_end:]


def test_a_header_promising_more_than_the_file_is_refused_before_allocating(tmp_path):
    path = tmp_path / "big.npy"
    path.write_bytes(_lying(np.zeros((3, 4)), "(99999999999,)"))  # 800 GB promised, 96 bytes there
    with pytest.raises(ValueError, match=r"^big.npy: the array header promises shape \(99999999999,\) of float64 "
                                         r"\(799999999992 bytes\), but 96 bytes follow it"):
        load_npy(path, "big.npy")


def test_an_archive_member_promising_more_than_it_holds_is_named(tmp_path):
    path = tmp_path / "b.npz"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("probs.npy", _lying(np.zeros((2, 3)), "(99999, 3)"))
        z.writestr("classes.npy", _npy_bytes(np.array(["a", "b", "c"])))
    with pytest.raises(ValueError, match=r"b\.npz: array 'probs': the array header promises shape \(99999, 3\)"):
        load_npy(path, "b.npz")
    with pytest.raises(ValueError, match=r"b\.npz: not a \.npy/\.npz array file \(.*array 'probs'"):
        read_class_beliefs(path, ["a", "b", "c"])


def test_a_garbled_header_is_one_of_the_read_errors(tmp_path):
    """numpy's header parser lets tokenize.TokenError through for a header cut inside its dict."""
    raw = _npy_bytes(np.zeros((3, 4)))
    path = tmp_path / "g.npy"
    path.write_bytes(raw[:40] + b"\x00" * 40 + b"[" + raw[81:])
    with pytest.raises(READ_ERRORS):
        load_npy(path, "g.npy")
    with pytest.raises(ValueError, match=r"g\.npy: not a \.npy/\.npz array file"):
        read_class_beliefs(path, ["a", "b", "c", "d"])


def test_valid_files_read_as_numpy_reads_them(tmp_path):
    a = np.random.default_rng(0).random((4, 5))
    np.save(tmp_path / "a.npy", a)
    np.savez(tmp_path / "a.npz", x=a, y=np.arange(3))
    np.testing.assert_array_equal(load_npy(tmp_path / "a.npy", "a.npy"), a)
    with load_npy(tmp_path / "a.npz", "a.npz") as z:
        np.testing.assert_array_equal(z["x"], a)
        assert z["y"].tolist() == [0, 1, 2]
