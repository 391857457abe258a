"""The one error type pedenv raises for bad input, and the checks that raise it."""

from __future__ import annotations

import importlib

import numpy as np
import numpy.typing as npt


class InputError(ValueError):
    """Bad input data: the message names the file, frame or field at fault."""


class MissingExtra(InputError):
    """Something was asked for whose optional dependency (a pyproject extra) is not installed."""


def require_extra(module: str, extra: str, flag: str) -> None:
    """Import ``module`` or raise :class:`MissingExtra` naming ``pip install -e ".[extra]"``."""
    try:
        importlib.import_module(module)
    except ImportError:
        raise MissingExtra(f'{flag} needs the {extra} extra: pip install -e ".[{extra}]"') from None



def check_array(name: str, value: object, shape: tuple[int | None, ...], *, dtype: npt.DTypeLike = np.float64,
                finite: bool = True) -> np.ndarray:
    """Return ``value`` as an array of ``dtype`` after checking its shape.

    ``shape`` holds ints for fixed sizes and ``None`` for free ones, e.g. ``(None, 17, 2)``.
    Raises :class:`InputError` with a message like
    ``keypoints must have shape (N, 17, 2), got (3, 20, 2)``.
    """
    try:
        array = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be a numeric array, got {type(value).__name__}: {exc}") from None
    wanted = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
    if array.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, array.shape)):
        raise InputError(f"{name} must have shape {wanted}, got {tuple(array.shape)}")
    if finite and array.dtype.kind == "f" and not np.all(np.isfinite(array)):
        raise InputError(f"{name} contains NaN or inf")
    return array
