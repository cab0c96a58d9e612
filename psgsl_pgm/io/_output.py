"""Output paths of the command line: checked before any work starts, written exactly where the user said.

``--out DIR`` (``psgsl demo``, ``psgsl experiment``, ...) is a directory: :func:`prepare_output_dir` creates it
(with parents) and proves that a file can be written in it, so an unwritable output fails in a second, not
after an hour of runs. ``--out FILE`` (``psgsl estimate``) is a file: :func:`check_output_file` refuses a
directory, a device (``/dev/full``, ``/dev/null``), a missing or unwritable folder, and
:func:`write_file_atomically` writes the bytes to exactly that path (no suffix appended) via a temporary
file in the same folder and :func:`os.replace`, so a full disk leaves the old file (or none), never half a
file.

All failures are :class:`ValueError` naming the option and the path; the command line maps them to one line
on stderr and exit code 2.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

__all__ = ["check_output_dir", "check_output_file", "prepare_output_dir", "write_file_atomically"]


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def _probe(directory: Path, option: str, path) -> None:
    """Write, flush and remove one byte in ``directory``: the only test of writability that root cannot fool."""
    try:
        fd, name = tempfile.mkstemp(prefix=".psgsl-probe-", dir=directory)
    except OSError as exc:
        raise ValueError(f"{option}: cannot write in {str(directory)!r} ({_reason(exc)})") from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(b"\0")
            fh.flush()
            os.fsync(fh.fileno())
    except OSError as exc:
        raise ValueError(f"{option}: cannot write {str(path)!r} ({_reason(exc)})") from None
    finally:
        with contextlib.suppress(OSError):
            os.unlink(name)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _as_path(path, option: str) -> Path:
    if isinstance(path, bool) or not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{option} must be a path (str or os.PathLike), got {type(path).__name__} {path!r}")
    text = os.fspath(path)
    if not text or (isinstance(text, str) and not text.strip()):
        raise ValueError(f"{option} must be a path, got an empty string")
    return Path(text)


def prepare_output_dir(path, *, option: str = "--out", subdirs=()) -> Path:
    """Create the output directory ``path`` (and ``subdirs`` inside it) and check that it is writable.

    Parameters
    ----------
    path : str or os.PathLike
        The directory; created with its parents when missing.
    option : str, keyword-only
        The option's name for messages.
    subdirs : sequence of str, keyword-only
        Sub-folders that must be directories too (created when missing), e.g. ``("runs",)``.

    Returns
    -------
    Path

    Raises
    ------
    ValueError
        ``path`` (or a sub-folder, or a parent) exists and is not a directory, cannot be created, or no file
        can be written in it.
    """
    out = _as_path(path, option)
    for d in (out, *(out / s for s in subdirs)):
        if d.exists() and not d.is_dir():
            raise ValueError(f"{option}: {str(d)!r} exists and is not a directory; give a directory")
        try:
            d.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ValueError(f"{option}: cannot create the directory {str(d)!r} ({_reason(exc)})") from None
    _probe(out, option, out)
    return out


def check_output_dir(path, *, option: str = "--out", subdirs=()) -> Path:
    """Check, creating nothing, that :func:`prepare_output_dir` would succeed: ``path`` and its ``subdirs`` are
    directories or missing, and a file can be written in ``path`` (or, when it is missing, in its nearest
    existing parent, where it would be created). A command that is refused later leaves no folder behind.

    Raises
    ------
    ValueError
        As :func:`prepare_output_dir`.
    """
    out = _as_path(path, option)
    for d in (out, *(out / s for s in subdirs)):
        if d.exists() and not d.is_dir():
            raise ValueError(f"{option}: {str(d)!r} exists and is not a directory; give a directory")
    parent = out
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise ValueError(f"{option}: cannot create the directory {str(out)!r} ({str(parent)!r} is not a directory)")
    if parent == out:
        _probe(out, option, out)
        return out
    try:
        _probe(parent, option, out)
    except ValueError as exc:
        reason = str(exc).split(" (", 1)[-1].rstrip(")") if " (" in str(exc) else "not writable"
        raise ValueError(f"{option}: cannot create the directory {str(out)!r} ({reason})") from None
    return out


def check_output_file(path, *, option: str = "--out") -> Path:
    """Check that the file ``path`` can be written, before any work: its folder exists and is writable, and
    ``path`` is not a directory nor a device.

    Returns
    -------
    Path
        ``path`` itself (no suffix is ever appended).

    Raises
    ------
    ValueError
        ``path`` is a directory or an existing non-regular file (``/dev/full``, a FIFO), its folder is missing,
        or no file can be written in the folder.
    """
    out = _as_path(path, option)
    if out.is_dir():
        raise ValueError(f"{option}: {str(out)!r} is a directory; give the file to write")
    if out.exists() and not out.is_file():
        raise ValueError(f"{option}: {str(out)!r} is not a regular file (a device or pipe); give a file to write")
    parent = out.parent
    if not parent.is_dir():
        what = "does not exist" if not parent.exists() else "is not a directory"
        raise ValueError(f"{option}: the folder {str(parent)!r} of {str(out)!r} {what}")
    _probe(parent, option, out)
    return out


def write_file_atomically(path, write, *, option: str = "--out") -> Path:
    """Write a file at exactly ``path``: ``write(fh)`` fills a temporary file next to it, then it replaces ``path``.

    Parameters
    ----------
    path : str or os.PathLike
    write : callable
        ``write(fh)`` writes the content to the binary file object ``fh``.
    option : str, keyword-only
        The option's name for messages.

    Raises
    ------
    ValueError
        The write, flush or rename failed (disk full, permissions): nothing is left at ``path`` that was not
        there before, and the temporary file is removed.
    """
    out = check_output_file(path, option=option)
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".part", dir=out.parent)
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # what open() would have given the file (mkstemp makes it 0600)
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, out)
    except OSError as exc:
        raise ValueError(f"{option}: cannot write {str(out)!r} ({_reason(exc)})") from None
    finally:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
    return out
