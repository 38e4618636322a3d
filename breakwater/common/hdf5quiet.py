"""HDF5's error stack kept off the terminal while breakwater reads an ``.h5`` itself.

HDF5 prints its error stack (30 to 50 lines, ``HDF5-DIAG: Error detected in HDF5 ...``)
to stderr before it returns an error to its caller (dolfinx's ``XDMFFile``), which then
raises a ``RuntimeError`` that breakwater turns into one line: the stack was printed
first. :func:`hdf5_quiet` turns HDF5's automatic printing off (``H5Eset_auto2``) for a
block and back on after it, in the HDF5 library the process has loaded (dolfinx's).
"""

from __future__ import annotations

import contextlib
import ctypes
import pathlib
from collections.abc import Iterator

__all__ = ["hdf5_quiet"]

_H5E_DEFAULT = ctypes.c_int64(0)  # hid_t of the default error stack (HDF5 >= 1.10)


def _library() -> ctypes.CDLL | None:
    """The HDF5 library loaded in the process (Linux: from /proc/self/maps), or None."""
    maps = pathlib.Path("/proc/self/maps")
    try:
        lines = maps.read_text().splitlines() if maps.exists() else []
    except OSError:
        return None
    for line in lines:
        path = line.split()[-1] if line.split() else ""
        if pathlib.Path(path).name.startswith("libhdf5.so"):
            try:
                lib = ctypes.CDLL(path)
                lib.H5Eset_auto2.argtypes = [ctypes.c_int64, ctypes.c_void_p, ctypes.c_void_p]
                lib.H5Eget_auto2.argtypes = [ctypes.c_int64, ctypes.POINTER(ctypes.c_void_p),
                                             ctypes.POINTER(ctypes.c_void_p)]
                return lib
            except (OSError, AttributeError):
                return None
    return None


@contextlib.contextmanager
def hdf5_quiet() -> Iterator[None]:
    """HDF5's automatic error printing off in the block (nothing done without the library)."""
    lib = _library()
    if lib is None:
        yield
        return
    func, data = ctypes.c_void_p(), ctypes.c_void_p()
    saved = lib.H5Eget_auto2(_H5E_DEFAULT, ctypes.byref(func), ctypes.byref(data)) >= 0
    lib.H5Eset_auto2(_H5E_DEFAULT, None, None)
    try:
        yield
    finally:
        if saved:
            lib.H5Eset_auto2(_H5E_DEFAULT, func, data)
