"""The ``p3d`` command group, and the one place where errors become messages and exit codes.

Exit statuses:

- 0: success.
- 1: inputs were read, but a result failed a requirement (``p3d check`` found a defect,
  ``--strict`` met a warning).
- 2: usage error, or an input that cannot be used (missing, unreadable, corrupt, unknown format,
  invalid scene).
- 3: internal error: a bug in p3d (set ``P3D_DEBUG=1`` for the traceback, and please report it).
"""

from __future__ import annotations

import gc
import importlib
import os
import re
import signal
import sys
from collections.abc import MutableMapping

# The command line never does BLAS work worth threads (3x3 matrices), but OpenBLAS starts one
# thread per core when numpy loads, and they spin: a third of the CPU time of
# 'p3d props small.stl', and on a busy machine a wait for cores others hold. Set before
# numpy is first imported (by a command's module), for this process only; an explicit
# setting of the user's wins. The library itself leaves the environment alone.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _keep_freed_memory() -> None:
    """Ask glibc's malloc to reuse freed memory instead of returning it to the system.

    Every block of a mesh allocates and frees the same few MB of numpy temporaries; with
    glibc's defaults these go back to the kernel (munmap, heap trimming) and come back as
    fresh page faults, block after block: on a 1M-triangle STL 29k page faults and a third
    of the run's time, 4M triangles 90k. Larger mmap/trim thresholds keep them in the heap
    (7k faults; 0.26 -> 0.21 s and 0.7 -> 0.5 s); the peak is unchanged. Command line only,
    glibc only (mallopt is absent elsewhere and this is then skipped).
    """
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes  # noqa: PLC0415 - numpy imports it anyway

        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return
    m_trim_threshold, m_top_pad, m_mmap_threshold = -1, -2, -3
    mallopt(m_mmap_threshold, 32 << 20)
    mallopt(m_trim_threshold, 128 << 20)
    mallopt(m_top_pad, 16 << 20)


_keep_freed_memory()

import click  # noqa: E402

from p3d_cli import __version__  # noqa: E402
from p3d_cli.errors import P3DError  # noqa: E402

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERNAL = 0, 1, 2, 3

#: Library parameter names -> the command-line flags that set them. Library errors name
#: parameters (``density, mass: both given``); the command line reports them by flag.
FLAGS = {
    "about": "--about", "density": "--density", "mass": "--mass", "method": "--method",
    "samples": "--samples", "seed": "--seed", "tolerance": "--tolerance", "tessellate": "--tessellate",
    "format": "--format", "scale": "--scale", "rotate": "--rotate", "quat": "--quat",
    "translate": "--translate", "require": "--require", "files_from": "--files-from",
    "dask": "--dask", "jobs": "--jobs", "steps": "--steps", "dt": "--dt", "trajectory": "--trajectory",
    "rpy": "--rpy", "units": "--units", "output_units": "--output-units",
    "null": "-0/--null", "ignore_warning": "--ignore-warning", "rtol": "--rtol", "atol": "--atol",
    "root": "--root",
    "size": "--size", "show": "--show", "view": "--view", "up": "--up", "azimuth": "--azimuth",
    "elevation": "--elevation", "output": "--output", "plot": "--plot", "animate": "--animate",
    "weld": "--weld", "fill_holes": "--fill-holes", "flatness": "--flatness", "max_hole_edges": "--max-hole-edges",
    "max_volume_change": "--max-volume-change", "output_format": "--output-format", "in_place": "--in-place",
}


def error_line(text: str) -> None:
    """Print one diagnostic line to stderr in p3d's format: ``p3d: error: <text>`` (control
    characters of a file name escaped: one line, whatever the name)."""
    from p3d_cli.cli.output import one_line

    click.echo(f"p3d: error: {one_line(text)}", err=True)


_PARAMETER = re.compile(r"\b([a-z_]+)=(\S?)")


def _as_flags(text: str) -> str:
    """``method=montecarlo`` -> ``--method montecarlo``, ``density=`` -> ``--density``."""
    def flag(match: re.Match) -> str:
        name, value = match.group(1), match.group(2)
        if name not in FLAGS:
            return match.group(0)
        return f"{FLAGS[name]} {value}" if value else FLAGS[name]
    return _PARAMETER.sub(flag, text)


def error_message(error: P3DError) -> str:
    """The message of a p3d error as the command line shows it: the parameters the library
    names (``where`` a list of parameter names; ``name=`` in the text) become flags."""
    where = error.where
    names = [name.strip() for name in where.split(",")]
    if where and all(name in FLAGS for name in names):
        where = "/".join(FLAGS[n] for n in names)
    return P3DError(where, _as_flags(error.what), _as_flags(error.hint)).message


def exit_status(error: P3DError) -> int:
    """The exit status of a p3d error (its class's code; 2 at least for an input not done)."""
    return error.exit_code

HELP = """Exact mass properties, bounds and constraint solves for meshes and shapes.

\b
Inputs are mesh files (STL binary/ASCII, OBJ, PLY, OFF, and any format meshio reads),
`-` for standard input, or primitive specs such as box:1,2,3 or sphere:0.5.

\b
Examples:
  p3d props part.stl
  p3d props part.stl --json
  p3d props part.stl --field volume

\b
Exit statuses: 0 success; 1 a result failed a requirement (check, --strict);
2 usage error or unusable input; 3 internal error (a bug: please report it).
Errors are one line on stderr: p3d: error: <where>: <what>; <how to fix>.
"""


#: Each command's one-line summary, as ``p3d --help`` lists it: the first sentence of the
#: command's docstring (tests/cli/test_startup.py checks that they agree). Kept here so that
#: listing the commands imports none of them (numpy, the solver, yaml): ``p3d --help`` loads
#: click and this module, not the ~270 modules of every command.
SUMMARIES = {
    "bounds": "Exact axis-aligned bounds of meshes and shapes, after --scale, a rotation and --translate.",
    "check": "Check that meshes are clean solids: one verdict per file, and an exit status.",
    "config": "Show the project settings file p3d would use here, and what it sets.",
    "diff": "Compare meshes with a baseline of their mass properties; exit 1 if anything changed.",
    "props": "Volume, mass, centre of mass and inertia of meshes and shapes.",
    "render": "Draw a shaded picture of a mesh, shape or assembly: PNG or SVG, no display needed.",
    "repair": "Repair meshes: fix what p3d check finds, change nothing else, say every change.",
    "robot": "Check and fill the <inertial> of every link of a URDF, MJCF or SDF description.",
    "solve": "Solve ball, hinge and bar constraints between rigid bodies.",
}


#: Click 8.2's error for a command given no arguments where that means "show the help" (click
#: 8.1, the declared minimum, prints the help and exits by itself): one name for both.
_NO_ARGS_IS_HELP: type | None = getattr(click.exceptions, "NoArgsIsHelpError", None)


def _shortened(text: str, width: int) -> str:
    """``text`` cut after a whole word to fit ``width`` columns, with ``...``, as click shortens."""
    if len(text) <= width:
        return text
    words: list[str] = []
    used = 0
    for word in text.split():
        if used + len(word) + (1 if words else 0) > width - 3:
            break
        used += len(word) + (1 if words else 0)
        words.append(word)
    return " ".join(words).rstrip(",;:") + "..."


class P3DGroup(click.Group):
    """A click group that turns every failure into one stderr line and a documented status."""

    def format_commands(self, ctx, formatter):
        """The command list of ``p3d --help``, from ``SUMMARIES`` where it can (no import)."""
        rows = []
        width = formatter.width - 6 - max((len(name) for name in self.list_commands(ctx)), default=0)
        for name in self.list_commands(ctx):
            summary = SUMMARIES.get(name)
            if summary is None:       # a command added without a summary here: ask it
                command = self.get_command(ctx, name)
                if command is None or command.hidden:
                    continue
                summary = command.get_short_help_str(width)
            else:
                summary = _shortened(summary, width)
            rows.append((name, summary))
        if rows:
            with formatter.section("Commands"):
                formatter.write_dl(rows)

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        if standalone_mode and hasattr(signal, "SIGPIPE"):
            # Like any Unix filter, stop quietly when the reader goes away (p3d ... | head):
            # Python ignores SIGPIPE and click would turn the broken pipe into exit 1.
            signal.signal(signal.SIGPIPE, signal.SIG_DFL)
        try:
            status = super().main(args, prog_name or "p3d", complete_var, standalone_mode=False, **extra)
        except click.exceptions.Exit as exc:  # --version and --help end this way
            status = exc.exit_code
        except click.Abort:
            error_line("interrupted")
            status = 130
        except click.ClickException as exc:
            if _NO_ARGS_IS_HELP is not None and isinstance(exc, _NO_ARGS_IS_HELP):
                context = getattr(exc, "ctx", None)
                click.echo(context.get_help() if context else exc.format_message())
                status = EXIT_OK
            else:
                status = _usage_error(exc)
        except P3DError as exc:
            error_line(error_message(exc))
            status = exit_status(exc)
        except KeyboardInterrupt:
            status = 130
        except Exception as exc:  # noqa: BLE001 - the last guard: a bug still gets one line
            if os.environ.get("P3D_DEBUG"):
                raise
            error_line(f"internal error: {type(exc).__name__}: {exc}; this is a bug in p3d, please "
                       "report it (set P3D_DEBUG=1 to see the traceback)")
            status = EXIT_INTERNAL
        if not standalone_mode:
            return status
        sys.exit(status or 0)


def _usage_error(exc: click.ClickException) -> int:
    ctx = getattr(exc, "ctx", None)
    command = ctx.command_path if ctx is not None else "p3d"
    message = exc.format_message().rstrip(".")   # click ends some sentences with a full stop; ours go on
    if isinstance(exc, click.UsageError):
        error_line(f"{command}: {message}; see '{command} --help'")
        return EXIT_USAGE
    error_line(message)
    return exc.exit_code


@click.group(cls=P3DGroup, help=HELP, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="p3d")
def cli() -> None:
    pass


class _Commands(MutableMapping):
    """The group's ``commands`` mapping, importing a command's module when it is first used.

    ``p3d props part.stl`` then imports the props command alone, not the constraint solver
    (yaml, ...) behind ``solve`` nor the topology checks behind ``check``: start-up is most of
    the time of a small file in a shell loop (issue 7). Listing the commands (``p3d --help``,
    ``cli.commands.items()``) imports them all.
    """

    def __init__(self, modules: dict[str, str]) -> None:
        self._modules = dict(modules)
        self._loaded: dict[str, click.Command] = {}

    def __getitem__(self, name: str) -> click.Command:
        if name not in self._loaded:
            module = self._modules[name]              # KeyError: no such command
            self._loaded[name] = getattr(importlib.import_module(module), name)
        return self._loaded[name]

    def __setitem__(self, name: str, command: click.Command) -> None:
        self._loaded[name] = command

    def __delitem__(self, name: str) -> None:
        if name not in self._modules and name not in self._loaded:
            raise KeyError(name)
        self._modules.pop(name, None)
        self._loaded.pop(name, None)

    def __iter__(self):
        return iter(sorted(set(self._modules) | set(self._loaded)))

    def __len__(self) -> int:
        return len(set(self._modules) | set(self._loaded))


# One line per command: its name and the module that defines a click command of that name
# (imported only when the command runs; see _Commands).
cli.commands = _Commands({
    "bounds": "p3d_cli.cli.bounds",
    "check": "p3d_cli.cli.check",
    "config": "p3d_cli.cli.config",
    "diff": "p3d_cli.cli.diff",
    "props": "p3d_cli.cli.props",
    "render": "p3d_cli.cli.render",
    "repair": "p3d_cli.cli.repair",
    "robot": "p3d_cli.cli.robot",
    "solve": "p3d_cli.cli.solve",
})


#: True once ``run`` has started: this process is the ``p3d`` program, not a caller of ``cli``.
_whole_process = False


def import_frozen(name: str) -> None:
    """Import module ``name`` with the cyclic garbage collector paused, then, in the ``p3d``
    program only (``run``), freeze every object made so far (``gc.freeze``).

    dask.distributed's import makes some 90,000 objects the collector tracks (classes,
    functions, tornado's and asyncio's tables) that live as long as the process. On their way
    in, the collector walks them at each threshold crossed: ~160 collections, a full one among
    them, 50-60 ms of a 0.4 s import; and every full collection after walks them again. Frozen, they are left
    alone: the client of a ``--dask`` batch sends its first task 0.075 s sooner (0.54 s to
    0.47 s after start, medians of 12 alternated runs). A caller of ``cli`` from Python
    (the tests) keeps its collector as it was: freezing is not a library's call to make. An
    import error is left for the caller's own import to report.
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        importlib.import_module(name)
    except ImportError:
        pass
    finally:
        if _whole_process:
            gc.freeze()
        if enabled:
            gc.enable()


def run() -> None:
    """The ``p3d`` program: ``cli`` as a whole process (the console script, ``python -m p3d_cli``).

    A ``--dask`` batch leaves dask.distributed loaded (about 700 modules, tornado's and
    asyncio's among them); tearing them down at interpreter exit costs ~0.2 s of CPU and wall
    time, a tenth of a batch of 1,000 small files, and does nothing for the user: by then the
    client is closed and every result written. So, once the command has finished and its
    output is flushed, such a process ends with ``os._exit`` and the command's status. Any
    other run (and ``cli`` called from Python, as the tests do) exits normally.
    """
    global _whole_process
    _whole_process = True
    try:
        cli.main(prog_name="p3d")
        status = 0
    except SystemExit as exc:
        status = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    if "distributed" in sys.modules:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        except OSError:      # the reader has gone (p3d ... | head): nothing more can be said
            pass
        os._exit(status)
    sys.exit(status)
