"""The ``assist3d`` command line. Each area registers its commands from its own module."""

from __future__ import annotations

import errno
import logging
import os
import sys

import typer
from rich.console import Console
from rich.logging import RichHandler

from ..core.errors import AssistError, FaultError, describe_os_error, inert
from ..core.interrupts import Interrupted, exit_on_signals

app = typer.Typer(
    name="assist3d",
    help="Synthesise fully annotated indoor scenes for class-agnostic 3D instance segmentation.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


@app.callback()
def _root(
    verbose: int = typer.Option(0, "--verbose", "-v", count=True, help="More log output (-v info, -vv debug)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Only warnings and errors."),
) -> None:
    """assist3d: assets, layouts, rendered point clouds, training and evaluation."""
    setup_logging(logging.WARNING if quiet else (logging.DEBUG if verbose >= 2 else logging.INFO))


def setup_logging(level: int = logging.INFO) -> None:
    """Attach one rich handler to the package logger (the library itself never configures logging)."""
    logger = logging.getLogger("assist3d")
    logger.setLevel(level)
    for h in list(logger.handlers):
        logger.removeHandler(h)
    handler = RichHandler(console=Console(stderr=True), show_path=False, show_time=False, markup=False)
    handler.setFormatter(_InertFormatter("%(message)s"))
    logger.addHandler(handler)
    logger.propagate = False


class _InertFormatter(logging.Formatter):
    """Log lines with control characters escaped: a message that quotes outside text (a file
    name, an LLM answer) can never move the cursor, retitle the terminal or fake a line."""

    def format(self, record: logging.LogRecord) -> str:
        return inert(super().format(record), keep="\n\t")


def _register_all() -> None:
    from . import assets as _assets
    from . import scene as _scene
    from . import generate as _generate
    from . import evaluate as _evaluate
    from . import metrics as _metrics
    from . import train as _train
    from . import segment as _segment
    from . import view as _view
    from . import export as _export

    for mod in (_assets, _scene, _generate, _evaluate, _metrics, _train, _segment, _view, _export):
        mod.register(app)


_register_all()


#: How to go on after a fault, for the commands that keep their finished work (``generate``'s own
#: message counts its complete scenes).
_RESUME_HINTS = {
    "probe": "re-run the same command to resume (finished seeds are kept)",
    "train": "re-run with --resume to continue from the last checkpoint",
}


#: Faults that strike part-way through a run (the others, a read-only or misplaced --out, come first).
_MID_RUN_FAULTS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})


def _command_name(argv: list[str]) -> str | None:
    """The subcommand of a command line (the first word that is not an option)."""
    return next((a for a in argv[1:] if not a.startswith("-")), None)


def main() -> None:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    try:
        with exit_on_signals():
            app()
    except AssistError as e:  # a bad input (2), or a fault of the machine met by a writer (1)
        logging.getLogger("assist3d").error(str(e))
        sys.exit(1 if isinstance(e, FaultError) else 2)
    except OSError as e:  # disk full, read-only, permissions, a file where a folder is expected
        hint = _RESUME_HINTS.get(_command_name(sys.argv)) if e.errno in _MID_RUN_FAULTS else None
        logging.getLogger("assist3d").error(describe_os_error(e) + (f", then {hint}" if hint else ""))
        sys.exit(1)
    except MemoryError as e:  # the bounds and estimates should refuse first; the last safety net
        detail = f" ({inert(e)})" if str(e) else ""
        logging.getLogger("assist3d").error(f"not enough memory{detail}; lower the sizes that scale the work "
                                            "(image size, views, points, counts) and re-run")
        sys.exit(1)
    except Interrupted as e:  # workers stopped, temporary files removed, locks released: say what is done
        sys.stderr.write(f"assist3d: {inert(str(e))}\n")
        sys.stderr.flush()
        sys.exit(e.exit_code)


if __name__ == "__main__":  # pragma: no cover
    main()
