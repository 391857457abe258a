"""The one progress bar of pedenv's applications (evaluation over scenes, runs over recordings)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn


def progress_bar(console: Console | None = None, *, enabled: bool = True) -> Progress:
    """A rich progress bar: the task's description, the bar, done of total, time left.

    Use it as a context manager and add one task per scene or recording
    (``bar.add_task(name, total=frames)``). ``console``: where to draw (default: rich's).
    ``enabled`` False gives a bar that counts but draws nothing.
    """
    return Progress(TextColumn("{task.description:<24}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn(),
                    console=console, disable=not enabled)


@contextmanager
def progress_callback(description: str, console: Console | None = None) -> Iterator[Callable[[int, int], None]]:
    """A :func:`progress_bar` with one task, handed out as a ``progress(done, total)`` callback.

    The bar opens at the first call, so an error while loading the input stays one line.
    ``total`` 0 means not known yet (the bar then shows no time left).
    """
    bar = progress_bar(console)
    task = None

    def progress(done: int, total: int) -> None:
        nonlocal task
        if task is None:
            bar.start()
            task = bar.add_task(description, total=None)
        bar.update(task, completed=done, total=total or None)

    try:
        yield progress
    finally:
        if task is not None:
            bar.stop()


class FrameCounter:
    """One line of a :func:`progress_bar` over all workers: frames done of the frames of the items started.

    ``update(item, done, total)`` as a worker reports; ``finish(item)`` when an item ends.
    """

    def __init__(self, bar: Any, items: int, already: int = 0, noun: str = "scenes") -> None:
        self.bar, self.items, self.finished, self.noun = bar, items, already, noun
        self.task = bar.add_task(self._label(), total=None)
        self.frames: dict[Any, tuple[int, int]] = {}

    def _label(self) -> str:
        return f"{self.noun} {self.finished}/{self.items}"

    def update(self, item: Any, done: int, total: int) -> None:
        self.frames[item] = (done, total)
        self.bar.update(self.task, completed=sum(d for d, _ in self.frames.values()),
                        total=sum(t for _, t in self.frames.values()) or None)

    def finish(self, item: Any, failed: bool = False) -> None:
        if not failed:
            done, total = self.frames.get(item, (0, 0))
            self.update(item, total, total)
        self.finished += 1
        self.bar.update(self.task, description=self._label())
