"""The ``evalsuite`` command.

Subcommands live beside the code they drive and are imported only when used, so
``evalsuite --help`` stays fast and optional extras (torch, flask, pyrender) are never
imported by commands that do not need them.
"""
from __future__ import annotations

import importlib
import importlib.util

import click

from evalsuite._version import __version__
from evalsuite.errors import InputError

# name -> "module:attribute"; the attribute is a click command or group.
COMMANDS = {
    "info": "evalsuite.motion.cli:info",
    "convert": "evalsuite.motion.cli:convert",
    "demo": "evalsuite.demo:demo",
    "score": "evalsuite.score_command:score",
    "fgd": "evalsuite.learned.cli:fgd",
    "render": "renderers.cli:render",
    "study": "study_app.cli:study",
    "analyze": "evalsuite.analysis.cli:analyze",
    "generators": "evalsuite.generators.cli:generators",
    "generate": "evalsuite.generators.cli:generate_command",
    "train": "evalsuite.generators.cli:train_command",
    "corpus": "evalsuite.corpus.cli:corpus",
    "features": "evalsuite.features.cli:features",
    "validate-metrics": "evalsuite.validity.cli:validate_metrics",
    "correlate": "evalsuite.analysis.correlate.cli:correlate",
    "import-judgements": "evalsuite.analysis.importers.cli:import_judgements_command",
    "critic": "evalsuite.critic.cli:critic",
    "validate-submission": "evalsuite.leaderboard.submission_cli:validate_submission_command",
}


def _module_exists(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except ModuleNotFoundError:  # a parent package is missing
        return False
    except ImportError:  # present, but its optional extra is not: importing it says which
        return True


class _MissingExtraCommand(click.Command):
    """Stands in for a command whose optional extra (e.g. torch) is missing: prints which, exit 1."""

    def __init__(self, name: str, message: str):
        super().__init__(name, help=message, short_help="(optional extra not installed)",
                         context_settings={"ignore_unknown_options": True, "allow_extra_args": True})
        self.message = message

    def invoke(self, ctx):
        raise click.ClickException(self.message)


class LazyGroup(click.Group):
    """A click group whose subcommands are imported on first use."""

    def list_commands(self, ctx):
        return sorted(set(super().list_commands(ctx)) | set(self._available()))

    def _available(self):
        # Only list commands whose module exists in this checkout/installation.
        return [name for name, target in COMMANDS.items() if _module_exists(target.split(":")[0])]

    def get_command(self, ctx, name):
        cmd = super().get_command(ctx, name)
        if cmd is not None or name not in COMMANDS:
            return cmd
        module_name, attr = COMMANDS[name].split(":")
        if not _module_exists(module_name):
            return None
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:
            if not isinstance(exc, InputError):  # a real bug, not a missing extra
                raise
            return _MissingExtraCommand(name, str(exc))
        return getattr(module, attr)

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except InputError as exc:
            # Bad input is the user's to fix: a clear message, no traceback, exit 1.
            raise click.ClickException(str(exc)) from exc


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="evalsuite")
def main():
    """evalsuite: evaluate speech-driven gesture generation.

    Score generated motion against natural motion, render comparison videos, host
    crowd studies and analyse their results. Run `evalsuite COMMAND --help` for details.
    """


def run() -> None:
    """The ``evalsuite`` console command (and ``python -m evalsuite``): :func:`main`, then a quick exit.

    Once a command has finished, the interpreter's own shutdown (freeing every module and object one by one)
    takes 0.1-0.15 s more, a twentieth of a short rendering command. So the exit handlers run here (files,
    logs, temporary folders, child processes: everything ``atexit`` knows, except freeing GL contexts, which the
    OS does) and the process then ends at once with the command's exit status. Where another thread is still running, or the interpreter
    has no ``atexit._run_exitfuncs``, the normal shutdown is kept. Tests call :func:`main` and never exit."""
    import atexit
    import contextlib
    import os
    import sys
    import threading

    try:
        main()
    except SystemExit as exc:
        code = exc.code
    else:  # pragma: no cover - click's standalone mode always exits
        code = 0
    run_exitfuncs = getattr(atexit, "_run_exitfuncs", None)
    others = [t for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon]
    if run_exitfuncs is None or others or not (code is None or isinstance(code, int)):
        sys.exit(code)
    gl = sys.modules.get("renderers._gl")
    if gl is not None:        # GL contexts need no freeing in a process that ends now (pyrender's delete: ~35 ms)
        atexit.unregister(gl.free_contexts)
    run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError, AttributeError):
            stream.flush()
    os._exit(code or 0)
