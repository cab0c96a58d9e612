"""The floating-point environment guard (psgsl_pgm._shared._fpenv): FTZ/DAZ set inside the block are undone."""

import ctypes
import platform
import struct
import warnings

import pytest

from psgsl_pgm._shared import _fpenv
from psgsl_pgm._shared._fpenv import preserved_float_environment, subnormals_work

#: glibc's x86-64 fenv_t: the x87 environment (28 bytes), then MXCSR; FTZ is bit 15, DAZ bit 6
MXCSR_OFFSET, FTZ_DAZ = 28, 0x8040

needs_x86_libm = pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64") or _fpenv._libm() is None
                                    or platform.system() != "Linux", reason="sets MXCSR through glibc's fenv_t")


def _set_flush_to_zero():
    """What a fast-math library's start-up code does: MXCSR |= FTZ | DAZ for this thread."""
    get, put = _fpenv._libm()
    env = ctypes.create_string_buffer(_fpenv._FENV_BYTES)
    assert get(env) == 0
    (mxcsr,) = struct.unpack_from("<I", env, MXCSR_OFFSET)
    struct.pack_into("<I", env, MXCSR_OFFSET, mxcsr | FTZ_DAZ)
    assert put(env) == 0


@needs_x86_libm
def test_flush_to_zero_set_inside_the_block_is_undone():
    assert subnormals_work()
    with preserved_float_environment():
        _set_flush_to_zero()
        assert not subnormals_work()  # the block really ran flushed
    assert subnormals_work()


@needs_x86_libm
def test_without_fenv_a_flushed_environment_is_reported(monkeypatch):
    get, put = _fpenv._libm()
    saved = ctypes.create_string_buffer(_fpenv._FENV_BYTES)
    get(saved)
    monkeypatch.setattr(_fpenv, "_libm", lambda: None)
    try:
        with pytest.warns(RuntimeWarning, match="flush subnormal numbers to zero"):
            with preserved_float_environment():
                monkeypatch.undo()
                _set_flush_to_zero()
                monkeypatch.setattr(_fpenv, "_libm", lambda: None)
    finally:
        put(saved)
    assert subnormals_work()


def test_a_clean_block_neither_warns_nor_changes_anything():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with preserved_float_environment():
            x = 1.0
    assert x == 1.0 and subnormals_work()
