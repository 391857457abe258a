"""The Typer application and the one place that turns library errors into one-line messages."""

from __future__ import annotations

import signal
import sys
import warnings

import typer
from rich.console import Console

from pedenv.errors import InputError

app = typer.Typer(
    name="pedenv",
    help="Pedestrian environment model from a monocular camera and ego localisation.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console(stderr=True, soft_wrap=True)


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    return f"warning: {message}\n"


def main() -> None:
    """Entry point of the ``pedenv`` console script: bad input (InputError) is one ``error:`` line,
    warnings one ``warning:`` line each.

    SIGTERM (``kill``, ``timeout``) stops a run as Ctrl-C does (exit code 130): through the
    writers' ``close()``, so the outputs stay valid up to the last finished frame.
    """
    previous, warnings.formatwarning = warnings.formatwarning, _one_line_warning
    signal.signal(signal.SIGTERM, _stop)
    try:
        app()
    except InputError as exc:  # bad input only: any other exception is a bug and keeps its traceback
        console.print(f"error: {exc}", style="red", highlight=False, markup=False)
        sys.exit(2)
    finally:
        warnings.formatwarning = previous


def _stop(signum, _frame) -> None:
    raise KeyboardInterrupt(f"signal {signum}")
