"""Position methods: each turns the frame's tracked skeletons into world positions.

``paper`` is the paper's method (:mod:`pedenv.localization.paper`), ``fused`` the one
beyond it (:mod:`pedenv.localization.fused`). :data:`LOCATORS` maps each method name to
its class; it is the one list of method names (``Config`` checks against it).
"""

from __future__ import annotations

from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.localization.base import FrameGeometry, Locator, Measurement
from pedenv.localization.fused.locator import FusedLocator
from pedenv.localization.paper import PaperLocator

#: Method name -> locator class; each class takes the whole Config.
LOCATORS: dict[str, type] = {"paper": PaperLocator, "fused": FusedLocator}


#: The method names, in the registry's order.
METHODS: tuple[str, ...] = tuple(LOCATORS)


def _check(name: str) -> type:
    if name not in LOCATORS:
        raise InputError(f"unknown position method {name!r}; valid: {', '.join(LOCATORS)}")
    return LOCATORS[name]


def create_locator(config: Config) -> Locator:
    """The locator of ``config.method``."""
    return _check(config.method)(config)


def configure(config: Config, method: str) -> Config:
    """``config`` with ``method`` and that method's preset (the locator class's ``PRESET``).

    A preset changes only fields still at their defaults, so values set on purpose win.
    ``paper`` has no preset: the paper's method as printed.
    """
    preset = getattr(_check(method), "PRESET", {})
    defaults, data = Config().to_dict(), config.to_dict()
    changes = {section: {k: v for k, v in values.items() if data[section][k] == defaults[section][k]}
               for section, values in preset.items()}
    return config.replace(method=method, **changes)


__all__ = ["FrameGeometry", "LOCATORS", "METHODS", "Locator", "Measurement", "configure", "create_locator"]
