"""The Typer application and the one place that turns library errors into one-line messages."""

from __future__ import annotations

import errno
import signal
import sys
import warnings
from types import FrameType

import typer
from rich.console import Console
from typer._click import exceptions as click_errors  # typer's own click (typer >= 0.20 vendors it)

from pedenv.errors import InputError
from pedenv.paths import MAX_NAME_BYTES

app = typer.Typer(
    name="pedenv",
    help="Pedestrian environment model from a monocular camera and ego localisation.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
#: stderr console for errors, warnings and progress. Emoji codes and markup are off: a path
#: such as ``runs/:x:/a.png`` or ``[red]/b.png`` is printed as it is, not as an emoji or a style.
console = Console(stderr=True, soft_wrap=True, emoji=False, markup=False)


def stdout_console(width: int | None) -> Console:
    """The stdout console of tables and results (``width`` columns when piped), emoji and markup off."""
    return Console(width=width, emoji=False, markup=False)


def _one_line_warning(message: Warning | str, *_where: object, **_line: object) -> str:
    """``warnings.formatwarning``: the message alone (category, file, line number left out)."""
    return f"warning: {message}\n"


def main() -> None:
    """Entry point of the ``pedenv`` console script: bad input (InputError) and a bad flag are one
    ``error:`` line each, warnings one ``warning:`` line each.

    SIGTERM (``kill``, ``timeout``) stops a run as Ctrl-C does (exit code 130): through the
    writers' ``close()``, so the outputs stay valid up to the last finished frame. A second
    Ctrl-C or SIGTERM while they close is ignored with one line (it would cut ``run.json`` or
    ``summary.json`` short); Ctrl-\\ (SIGQUIT) still ends the process at once.
    """
    previous, warnings.formatwarning = warnings.formatwarning, _one_line_warning
    _Stop.stopping = False
    handlers = {sig: signal.signal(sig, _stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        code = app(standalone_mode=False, prog_name="pedenv")
        sys.exit(code if isinstance(code, int) else 0)
    except click_errors.NoArgsIsHelpError as exc:  # the help is printed as it is made
        sys.exit(exc.exit_code)
    except click_errors.ClickException as exc:  # a flag's value or name: one line, not a framed usage box
        where = exc.ctx.command_path if isinstance(exc, click_errors.UsageError) and exc.ctx is not None else "pedenv"
        console.print(f"error: {where}: {exc.format_message()} (see {where} --help)", style="red", highlight=False,
                      markup=False)
        sys.exit(exc.exit_code)
    except typer.Abort:
        sys.exit(1)
    except InputError as exc:  # bad input only: any other exception is a bug and keeps its traceback
        console.print(f"error: {exc}", style="red", highlight=False, markup=False)
        sys.exit(2)
    except OSError as exc:
        if exc.errno != errno.ENAMETOOLONG:  # a path given with a name over 255 bytes is bad input too
            raise
        console.print(f"error: {exc.filename}: a name in this path is longer than the file system takes "
                      f"({MAX_NAME_BYTES} bytes)", style="red", highlight=False, markup=False)
        sys.exit(2)
    finally:
        warnings.formatwarning = previous
        for sig, handler in handlers.items():
            signal.signal(sig, handler)


class _Stop:
    stopping = False  # a stop signal came: the outputs are being closed


def _stop(signum: int, _frame: FrameType | None) -> None:
    if _Stop.stopping:
        print("pedenv: still closing the outputs; they are kept (Ctrl-\\ quits at once)", file=sys.stderr, flush=True)
        return
    _Stop.stopping = True
    raise KeyboardInterrupt(f"signal {signum}")
