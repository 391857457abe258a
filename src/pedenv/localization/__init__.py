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
    """``config`` switched to ``method``: the fields still at the defaults of ``config``'s
    method (:data:`pedenv.config.METHOD_PRESETS`) take ``method``'s defaults; values set on
    purpose stay. ``configure(Config(), "paper")`` is the paper's method as printed.
    """
    _check(method)
    old, new, data = Config(method=config.method).to_dict(), Config(method=method).to_dict(), config.to_dict()
    changes = {section: {k: v for k, v in values.items() if data[section][k] == old[section][k] != v}
               for section, values in new.items() if section != "method"}
    return config.replace(method=method, **changes)


__all__ = ["FrameGeometry", "LOCATORS", "METHODS", "Locator", "Measurement", "configure", "create_locator"]
