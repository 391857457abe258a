"""Reading ``.npy`` files that hold pickled objects without running code from the file.

``np.load(path, allow_pickle=True)`` unpickles whatever the file holds, and unpickling
calls any importable function the file names (``os.system`` included). The paper's CARLA
recordings are pickled dicts of numpy arrays, so pickle cannot simply be refused:
:func:`load_npy` parses the ``.npy`` header with :mod:`numpy.lib.format` and unpickles an
object payload with :class:`RestrictedUnpickler`, which admits only what numpy arrays,
dtypes and plain containers need. Anything else is one :class:`~pedenv.errors.InputError`
naming the file; nothing the file names is ever called.
"""

from __future__ import annotations

import io
import pickle
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.lib import format as npy_format

from pedenv.errors import InputError

#: ``(module, name)`` pairs a pickled numpy array, dtype or scalar refers to, under numpy's
#: module names before and after 2.0 (``numpy.core`` became ``numpy._core``).
NUMPY_GLOBALS: frozenset[tuple[str, str]] = frozenset(
    (module, name)
    for module in ("numpy.core.multiarray", "numpy._core.multiarray")
    for name in ("_reconstruct", "scalar")
) | frozenset({("numpy", "ndarray"), ("numpy", "dtype")})

#: Builtins a plain container of numbers and strings may name.
BUILTIN_GLOBALS: frozenset[str] = frozenset(
    {"dict", "list", "tuple", "str", "int", "float", "bool", "complex", "bytes", "bytearray", "set", "frozenset"})


class RestrictedUnpickler(pickle.Unpickler):
    """An unpickler that resolves only numpy array/dtype reconstruction and plain builtins.

    Any other global (``os.system``, ``builtins.eval``, ``subprocess.Popen``, ...) raises
    :class:`pickle.UnpicklingError` before it is imported, so it can never be called.
    """

    def find_class(self, module: str, name: str) -> Any:
        if (module, name) in NUMPY_GLOBALS or (module == "builtins" and name in BUILTIN_GLOBALS):
            return super().find_class(module, name)
        raise pickle.UnpicklingError(f"refusing to load {module}.{name}: only numpy arrays, dtypes and "
                                     f"plain containers (dict, list, tuple, str, numbers, None) are allowed")


def restricted_loads(data: bytes) -> Any:
    """Unpickle ``data`` with :class:`RestrictedUnpickler`."""
    return RestrictedUnpickler(io.BytesIO(data)).load()


def load_npy(path: str | Path) -> Any:
    """The array stored in the ``.npy`` file ``path``; an object array's payload is unpickled safely.

    A 0-d object array (``np.save`` of a dict) is returned as its single item.
    Raises :class:`InputError` naming the file for anything unreadable or refused.
    """
    path = Path(path)
    try:
        with path.open("rb") as f:
            version = npy_format.read_magic(f)
            _shape, _fortran, dtype = _read_header(f, version)
            if not dtype.hasobject:
                f.seek(0)
                return npy_format.read_array(f, allow_pickle=False)
            value = restricted_loads(f.read())
    except InputError:
        raise
    except Exception as exc:  # noqa: BLE001 - any unreadable or refused file is bad input naming the file
        raise InputError(f"{path}: not a readable .npy file ({type(exc).__name__}: {exc})") from None
    if isinstance(value, np.ndarray) and value.shape == ():
        return value.item()
    return value


def _read_header(f: BinaryIO, version: tuple[int, int]) -> tuple:
    if version == (1, 0):
        return npy_format.read_array_header_1_0(f)
    if version == (2, 0):
        return npy_format.read_array_header_2_0(f)
    raise ValueError(f"unsupported .npy format version {version}")
