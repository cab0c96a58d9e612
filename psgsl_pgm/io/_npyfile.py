"""The one safe reader of the .npy / .npz files handed to psgsl: arrays, class beliefs, stored runs.

On top of ``np.load(path, allow_pickle=False)`` (no pickled objects):

* a header that promises more data than the file (or the archive member) holds — a truncated file, or a
  header claiming a 10¹¹-entry array in a file of a few bytes — is a :class:`ValueError` before anything is
  allocated (numpy allocates what the header promises first, so it would end in :class:`MemoryError`);
* every way numpy reports a corrupt file — :class:`ValueError`, :class:`OSError`, :class:`EOFError`, the
  :class:`SyntaxError` and :class:`tokenize.TokenError` its header parser lets through, and for archives
  :class:`zipfile.BadZipFile` and :class:`zlib.error` — is in :data:`READ_ERRORS`, so a caller catches one
  tuple and names the file.

Examples
--------
>>> import numpy as np, tempfile, os
>>> path = os.path.join(tempfile.mkdtemp(), "a.npy")
>>> np.save(path, np.arange(6.0).reshape(2, 3))
>>> load_npy(path, "a.npy").shape
(2, 3)
>>> with open(path, "r+b") as fh:
...     _ = fh.truncate(os.path.getsize(path) - 8)
>>> load_npy(path, "a.npy")
Traceback (most recent call last):
...
ValueError: a.npy: the array header promises shape (2, 3) of float64 (48 bytes), but 40 bytes follow it (a truncated or corrupt file)
"""

from __future__ import annotations

import math
import os
import tokenize
import zipfile
import zlib
from pathlib import Path

import numpy as np

__all__ = ["READ_ERRORS", "load_npy"]

#: What reading a corrupt .npy/.npz can raise (with :func:`load_npy`'s own ValueError among them).
READ_ERRORS = (OSError, ValueError, EOFError, SyntaxError, tokenize.TokenError, zipfile.BadZipFile, zlib.error)

_NPY_MAGIC = b"\x93NUMPY"
_ZIP_MAGIC = b"PK\x03\x04"


def load_npy(path, where: str):
    """``np.load(path, allow_pickle=False)`` after checking every array header against the bytes behind it.

    Parameters
    ----------
    path : str or path-like
    where : str
        The file as messages name it.

    Returns
    -------
    numpy.ndarray or numpy.lib.npyio.NpzFile

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError, and the rest of :data:`READ_ERRORS`
        A header promising more than the file holds (this function, naming ``where``), or numpy's own
        report of a corrupt file.
    """
    p = Path(path)
    with open(p, "rb") as fh:
        start = fh.read(len(_ZIP_MAGIC))
        fh.seek(0)
        if start == _ZIP_MAGIC:
            with zipfile.ZipFile(fh) as archive:
                for info in archive.infolist():
                    if info.filename.endswith(".npy"):
                        with archive.open(info) as member:
                            _check_header(member, info.file_size, f"{where}: array {info.filename[:-4]!r}")
        elif start.startswith(_NPY_MAGIC[:4]):
            _check_header(fh, os.fstat(fh.fileno()).st_size, where)
    return np.load(p, allow_pickle=False)


def _check_header(fh, size: int, where: str) -> None:
    """Refuse a .npy header (read from ``fh``, a stream of ``size`` bytes) that promises more than follows it."""
    version = np.lib.format.read_magic(fh)
    if version == (1, 0):
        shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
    elif version == (2, 0):
        shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
    else:  # other versions: np.load reads (or refuses) them itself
        return
    if dtype.hasobject:  # refused by np.load(allow_pickle=False)
        return
    need = math.prod(shape) * dtype.itemsize  # exact: no overflow for a lying shape
    have = size - fh.tell()
    if need > have:
        raise ValueError(f"{where}: the array header promises shape {shape} of {dtype} ({need} bytes), but {have} "
                         "bytes follow it (a truncated or corrupt file)")
