"""The Typer application and the one place that turns library errors into one-line messages."""

from __future__ import annotations

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
    warnings one ``warning:`` line each."""
    previous, warnings.formatwarning = warnings.formatwarning, _one_line_warning
    try:
        app()
    except InputError as exc:  # bad input only: any other exception is a bug and keeps its traceback
        console.print(f"error: {exc}", style="red", highlight=False, markup=False)
        sys.exit(2)
    finally:
        warnings.formatwarning = previous
